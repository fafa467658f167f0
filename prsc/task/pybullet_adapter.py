"""The task of a scene scored in a pybullet simulation (docs/tasks.md, "Any simulator"): the same
task file, the same evaluator, the world state read with pybullet's own calls.

    task = PybulletTask.load("out/spec/sdf/00003.sdf")   # or the bundle folder "out/spec/urdf/00003"
    while simulating:
        pybullet.stepSimulation(); t += dt
        status = task.update(t)        # once per control step
    record = task.result(t)            # outcome, trivial, decided_at, robustness, records

`load` loads the world prsc wrote (robots at their starting joint values) and reads the scene's
task file beside it (`sdf/00003.task.json`) or in it (`urdf/00003/task.json`); a world built
otherwise gives `PybulletTask(task_json, {"cube": cube_id, ...})`. An object's pose is its root
link's frame (pybullet reports a base's centre of mass; the link frame is recovered from the
inertial offset), which in prsc's files is the object's box frame. Distances are pybullet's
`getClosestPoints` (negative when penetrating), capped at DISTANCE_CAP; a name "object/link" in
`links` names one link (a robot's finger, for `holds`; a link the task names, `cab.links["drawer"]`,
whose pose is its link frame's from `getLinkState`, moved to its box centre).
"""

from __future__ import annotations

import json
import os
import xml.etree.ElementTree as ET
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from prsc.task.monitor import EpisodeMonitor, TaskStatus
from prsc.task.terms import Task, task_file
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
        unmapped = [o.name for o in self.task.links() if o.name not in self.links]
        if unmapped:
            raise ValueError(f"the task reads the links {', '.join(unmapped)}, which `links` does not map to "
                             "(pybullet body, link index) pairs")
        self._link_offsets = {o.name: o.link.offset for o in self.task.links()}  # type: ignore[union-attr]
        self.client = client
        self.monitor = EpisodeMonitor(self.task)
        self._moving: dict[str, list[tuple[int, int | None]]] = {}  # each name's parts (see _parts)

    @classmethod
    def load(cls, scene: str | os.PathLike[str], client: int = 0) -> PybulletTask:
        """Load a scene prsc wrote (an SDF world file or a URDF bundle folder) into `client` and
        watch the task of its task file; a robot's finger links are found by name (`holds`)."""
        bodies = load_scene(scene, client)
        task = Task.from_json(json.loads(task_file(scene).read_text(encoding="utf-8")))
        links = {}
        for o in task.objects:
            if o.name in bodies and o.fingers:
                joints = _joint_indices(bodies[o.name], client, child_links=True)
                links.update({f"{o.name}/{f}": (bodies[o.name], joints[f]) for f in o.fingers if f in joints})
        for o in task.links():  # `X.links["NAME"]`: link NAME of X's body, by its name in the files
            of, name = o.link.of, o.link.link  # type: ignore[union-attr]
            joints = _joint_indices(bodies[of], client, child_links=True) if of in bodies else {}
            if name not in joints:
                raise ValueError(f"{scene}: {of} has no link {name!r} in pybullet (the task reads {of}.links[{name!r}])")
            links[o.name] = (bodies[of], joints[name])
        return cls(task, bodies, client, links)

    def _pose(self, name: str) -> Pose:
        body, p, client = self.bodies[name], self.p, self.client
        com, com_quaternion = p.getBasePositionAndOrientation(body, physicsClientId=client)
        linear, angular = (np.asarray(v, dtype=float) for v in p.getBaseVelocity(body, physicsClientId=client))
        # The root link's frame: the base's centre of mass less its inertial offset (getDynamicsInfo).
        offset, offset_quaternion = p.getDynamicsInfo(body, -1, physicsClientId=client)[3:5]
        back, back_quaternion = p.invertTransform(offset, offset_quaternion)
        position, quaternion = p.multiplyTransforms(com, com_quaternion, back, back_quaternion)
        position = np.asarray(position, dtype=float)
        rotation = np.asarray(p.getMatrixFromQuaternion(quaternion), dtype=float).reshape(3, 3)
        (wx, wy, wz), (rx, ry, rz) = angular, position - np.asarray(com, dtype=float)
        linear = linear + (wy * rz - wz * ry, wz * rx - wx * rz, wx * ry - wy * rx)  # the frame's own velocity
        return Pose(position, rotation, linear, angular)

    def _link_pose(self, name: str) -> Pose:
        """A link's box centre and rotation: its link frame (getLinkState) moved by the box's offset in it."""
        body, link = self.links[name]
        state = self.p.getLinkState(body, link, computeForwardKinematics=True, physicsClientId=self.client)
        rotation = np.asarray(self.p.getMatrixFromQuaternion(state[5]), dtype=float).reshape(3, 3)
        position = np.asarray(state[4], dtype=float) + rotation @ np.asarray(self._link_offsets[name], dtype=float)
        return Pose(position, rotation, np.zeros(3), np.zeros(3))

    def _parts(self, name: str) -> list[tuple[int, int | None]]:
        """(body, link or None for every link) pairs whose shapes stand for `name`: one link of a
        "robot/link" name; the moving links of a fixed-base robot, as in MuJoCo (its base rests
        where it was placed: prsc/runner/task_monitor.py); else the whole body (furniture too)."""
        if name in self.links:
            return [self.links[name]]
        parts = self._moving.get(name)
        if parts is None:
            body, p, client = self.bodies[name], self.p, self.client
            fixed_base = p.getDynamicsInfo(body, -1, physicsClientId=client)[0] == 0
            moving: list[int] = []
            for link in range(p.getNumJoints(body, physicsClientId=client)):
                info = p.getJointInfo(body, link, physicsClientId=client)
                if info[2] != p.JOINT_FIXED or info[16] in moving:  # its own joint moves, or its parent does
                    moving.append(link)
            # a robot's base rests where it was placed
            mounted = fixed_base and bool(moving) and self.task.touches_by_moving_links(name)
            parts = self._moving[name] = [(body, k) for k in moving] if mounted else [(body, None)]
        return parts

    def distance(self, a: str, b: str, enough: float | None = None) -> float:
        """The least signed distance between a's and b's shapes (capped at DISTANCE_CAP; `enough` unused)."""
        if (a not in self.bodies and a not in self.links) or (b not in self.bodies and b not in self.links):
            return DISTANCE_CAP
        least = DISTANCE_CAP
        for body_a, link_a in self._parts(a):
            for body_b, link_b in self._parts(b):
                query = {"bodyA": body_a, "bodyB": body_b}
                if link_a is not None:
                    query["linkIndexA"] = link_a
                if link_b is not None:
                    query["linkIndexB"] = link_b
                points = self.p.getClosestPoints(distance=DISTANCE_CAP, physicsClientId=self.client, **query)
                least = min([least] + [float(point[8]) for point in points])
        return least

    def state(self, time: float) -> WorldState:
        """The world state now (poses of the task's objects; distances when asked)."""
        poses = {name: self._pose(name) for name in self.bodies}
        poses.update({name: self._link_pose(name) for name in self._link_offsets})
        return WorldState(float(time), poses, self.distance)

    def update(self, time: float) -> TaskStatus:
        """Evaluate the task at simulated time `time` (once per control step)."""
        return self.monitor.update(self.state(time))

    def result(self, time: float, controller_finished: bool = True) -> dict:
        """The episode's task record (`record final` evaluated now)."""
        return self.monitor.result(self.state(time), controller_finished)


def load_scene(scene: str | os.PathLike[str], client: int = 0) -> dict[str, int]:
    """Load an SDF world (`sdf/<k>.sdf`) or a URDF bundle folder (`urdf/<k>/`) prsc wrote into a
    pybullet client, every robot joint at the value the files state; object name -> body id."""
    import pybullet as p

    path = Path(scene)
    bodies: dict[str, int] = {}
    if path.is_dir():  # a URDF bundle: scene.json says how to load each object (docs/backends.md)
        bundle = json.loads((path / "scene.json").read_text(encoding="utf-8"))
        for entry in bundle["objects"] + ([bundle["ground"]] if bundle.get("ground") else []):
            body = p.loadURDF(str(path / entry["urdf"]), entry["base_position"], entry["base_orientation_xyzw"],
                              useFixedBase=entry["use_fixed_base"], physicsClientId=client)
            if "name" in entry:
                bodies[entry["name"]] = body
                _set_joints(body, client, entry.get("joints") or {})
        return bodies
    start: dict[str, dict[str, float]] = {}  # the SDF's <prsc:joint_positions> (docs/backends.md)
    for element in ET.parse(path).getroot().iter("{urn:prsc:sdf:joint-positions}joint"):
        start.setdefault(str(element.get("model")), {})[str(element.get("name"))] = float(element.text or 0)
    for body in p.loadSDF(str(path), physicsClientId=client):
        name = p.getBodyInfo(body, physicsClientId=client)[1].decode()
        bodies[name] = body
        _set_joints(body, client, start.get(name, {}))
    return bodies


def _joint_indices(body: int, client: int, child_links: bool = False) -> dict[str, int]:
    """Joint (or, with child_links, child link) name -> joint index of a body."""
    import pybullet as p

    field = 12 if child_links else 1
    return {p.getJointInfo(body, j, physicsClientId=client)[field].decode(): j
            for j in range(p.getNumJoints(body, physicsClientId=client))}


def _set_joints(body: int, client: int, values: Mapping[str, float]) -> None:
    import pybullet as p

    joints = _joint_indices(body, client)
    for name, value in values.items():
        if name in joints:
            p.resetJointState(body, joints[name], float(value), physicsClientId=client)
