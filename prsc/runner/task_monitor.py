"""The task of a scene (LANGUAGE.md section 8) watched in a MuJoCo episode: the world state read
from MjData (poses, velocities, geom distances by MuJoCo's own `mj_geomDistance` after a
bounding-sphere broad phase), handed to the one evaluator of prsc/task."""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from prsc.backends.names import with_body_names
from prsc.task.monitor import EpisodeMonitor, TaskStatus
from prsc.task.terms import Task
from prsc.task.world import DISTANCE_CAP, Pose, WorldState

__all__ = ["TaskMonitor", "TaskStatus", "CONTROL_PERIOD"]

CONTROL_PERIOD = 0.02  # s of simulated time between two evaluations of the task (50 Hz)


@dataclass(frozen=True)
class _Geoms:
    ids: np.ndarray  # collision geoms (contype or conaffinity set)


def _subtree(model: mujoco.MjModel, root: int) -> list[int]:
    return [b for b in range(model.nbody) if _is_below(model, b, root)]


def _is_below(model: mujoco.MjModel, body: int, root: int) -> bool:
    while body > 0:
        if body == root:
            return True
        body = int(model.body_parentid[body])
    return False


class MjWorld:
    """Object names -> MuJoCo bodies and geoms of one model; builds WorldStates from its data."""

    def __init__(self, scene: dict, model: mujoco.MjModel, task: Task):
        self.model = model
        objects = with_body_names(scene)["objects"]
        self.body = {}
        self.geoms: dict[str, np.ndarray] = {}
        collides = (model.geom_contype != 0) | (model.geom_conaffinity != 0)
        for obj in objects:
            body = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, obj["body"])
            if body < 0:
                continue  # a camera or a light: no body
            self.body[obj["name"]] = body
            bodies = _subtree(model, body)
            if len(bodies) > 1 and model.body_dofnum[bodies].sum() > 0 and model.body_weldid[body] == 0:
                # A mounted robot touches with its moving links: its base rests where it was placed.
                bodies = [b for b in bodies if model.body_weldid[b] != 0]
            self.geoms[obj["name"]] = np.array([g for g in range(model.ngeom) if collides[g]
                                                and int(model.geom_bodyid[g]) in set(bodies)], dtype=int)
            for finger in task.object(obj["name"]).fingers if _has(task, obj["name"]) else ():
                link = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, f"{obj['body']}/{finger}")
                if link >= 0:
                    self.geoms[f"{obj['name']}/{finger}"] = np.array(
                        [g for g in range(model.ngeom) if collides[g] and model.geom_bodyid[g] == link], dtype=int)
        self._fromto = np.zeros(6)

    def pose(self, data: mujoco.MjData, name: str, dims) -> Pose:
        """The object's box centre and rotation now (the body frame is the box's, prsc/backends)."""
        b = self.body[name]
        velocity = np.zeros(6)
        mujoco.mj_objectVelocity(self.model, data, mujoco.mjtObj.mjOBJ_BODY, b, velocity, 0)
        return Pose(data.xpos[b].copy(), data.xmat[b].reshape(3, 3).copy(), velocity[3:].copy(), velocity[:3].copy())

    def distance(self, data: mujoco.MjData, a: str, b: str) -> float:
        """The least signed distance between the geoms of a and b (capped at DISTANCE_CAP)."""
        ga, gb = self.geoms.get(a), self.geoms.get(b)
        if ga is None or gb is None or not len(ga) or not len(gb):
            return DISTANCE_CAP
        centres_a, centres_b = data.geom_xpos[ga], data.geom_xpos[gb]
        lower = (np.linalg.norm(centres_a[:, None] - centres_b[None], axis=2)
                 - self.model.geom_rbound[ga][:, None] - self.model.geom_rbound[gb][None])
        best = DISTANCE_CAP
        order = np.argsort(lower, axis=None)
        flat = lower.ravel()
        for k in order:
            if flat[k] >= best:
                break
            i, j = divmod(int(k), len(gb))
            d = mujoco.mj_geomDistance(self.model, data, int(ga[i]), int(gb[j]), best, self._fromto)
            best = min(best, d)
        return float(best)


def _has(task: Task, name: str) -> bool:
    return any(o.name == name for o in task.objects)


class TaskMonitor:
    """The task of `scene["task"]` over one MuJoCo episode: `update` once per control step, `result` at the end."""

    def __init__(self, scene: dict, model: mujoco.MjModel):
        self.task = Task.from_json(scene["task"])
        self.world = MjWorld(scene, model, self.task)
        self.monitor = EpisodeMonitor(self.task)

    def state(self, model: mujoco.MjModel, data: mujoco.MjData) -> WorldState:
        """The world state of `data` at `data.time` (distances computed when the task asks)."""
        poses = _LazyPoses(self.world, data, {o.name: o.dimensions for o in self.task.objects})
        return WorldState(float(data.time), poses, lambda a, b: self.world.distance(data, a, b))

    def update(self, model: mujoco.MjModel, data: mujoco.MjData) -> TaskStatus:
        """Evaluate the task at `data.time`."""
        return self.monitor.update(self.state(model, data))

    def result(self, model: mujoco.MjModel, data: mujoco.MjData, controller_finished: bool) -> dict:
        """The record's "task" dict (`record final` evaluated on `data`)."""
        return self.monitor.result(self.state(model, data), controller_finished)


class _LazyPoses(dict):
    """Poses read from MjData when the evaluator first asks for them."""

    def __init__(self, world: MjWorld, data: mujoco.MjData, dims: dict):
        super().__init__()
        self.world, self.data, self.dims = world, data, dims

    def __missing__(self, name: str) -> Pose:
        pose = self.world.pose(self.data, name, self.dims[name])
        self[name] = pose
        return pose
