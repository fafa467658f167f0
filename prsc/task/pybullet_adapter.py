"""The task of a scene scored in a pybullet simulation (docs/tasks.md, "Any simulator"): the same
task.json, the same evaluator, the world state read with pybullet's own calls.

    task = PybulletTask(json.load(open("task.json")), {"cube": cube_id, "tray": tray_id, ...})
    while simulating:
        pybullet.stepSimulation(); t += dt
        status = task.update(t)        # once per control step
    record = task.result(t)            # outcome, trivial, decided_at, robustness, records

A body's base frame is taken as its object's box frame (as in the files prsc writes: the inertial
origin of a free object is its box centre). Distances are pybullet's `getClosestPoints`
(negative when penetrating), capped at DISTANCE_CAP; a name "robot/link" in `links` names one link
(a robot's finger, for `holds`).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from prsc.task.monitor import EpisodeMonitor, TaskStatus
from prsc.task.terms import Task
from prsc.task.world import DISTANCE_CAP, Pose, WorldState


class PybulletTask:
    """A compiled task watched in one pybullet client: object name -> body unique id."""

    def __init__(self, task: Task | dict, bodies: Mapping[str, int], client: int = 0,
                 links: Mapping[str, tuple[int, int]] | None = None):
        import pybullet

        self.p = pybullet
        self.task = task if isinstance(task, Task) else Task.from_json(task)
        missing = sorted(self.task.statements.objects() - set(bodies))
        if missing:
            raise ValueError(f"the task reads {', '.join(missing)}, which `bodies` does not map to pybullet bodies")
        self.bodies = dict(bodies)
        self.links = dict(links or {})
        self.client = client
        self.monitor = EpisodeMonitor(self.task)

    def _pose(self, name: str) -> Pose:
        body = self.bodies[name]
        position, quaternion = self.p.getBasePositionAndOrientation(body, physicsClientId=self.client)
        linear, angular = self.p.getBaseVelocity(body, physicsClientId=self.client)
        rotation = np.asarray(self.p.getMatrixFromQuaternion(quaternion), dtype=float).reshape(3, 3)
        return Pose(np.asarray(position, dtype=float), rotation, np.asarray(linear, dtype=float),
                    np.asarray(angular, dtype=float))

    def _part(self, name: str) -> dict:
        if name in self.links:
            body, link = self.links[name]
            return {"bodyA": body, "linkIndexA": link}
        return {"bodyA": self.bodies[name]}

    def distance(self, a: str, b: str, enough: float | None = None) -> float:
        """The least signed distance between a's and b's shapes (capped at DISTANCE_CAP; `enough` unused)."""
        if (a not in self.bodies and a not in self.links) or (b not in self.bodies and b not in self.links):
            return DISTANCE_CAP
        first, second = self._part(a), self._part(b)
        query = {**first, "bodyB": second["bodyA"]}
        if "linkIndexA" in second:
            query["linkIndexB"] = second["linkIndexA"]
        points = self.p.getClosestPoints(distance=DISTANCE_CAP, physicsClientId=self.client, **query)
        return min([DISTANCE_CAP] + [float(point[8]) for point in points])

    def state(self, time: float) -> WorldState:
        """The world state now (poses of the task's objects; distances when asked)."""
        return WorldState(float(time), {name: self._pose(name) for name in self.bodies}, self.distance)

    def update(self, time: float) -> TaskStatus:
        """Evaluate the task at simulated time `time` (once per control step)."""
        return self.monitor.update(self.state(time))

    def result(self, time: float, controller_finished: bool = True) -> dict:
        """The episode's task record (`record final` evaluated now)."""
        return self.monitor.result(self.state(time), controller_finished)
