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
        self._boxes_at: tuple | None = None
        self._boxes: tuple[np.ndarray, np.ndarray] = (np.zeros((0, 3)), np.zeros((0, 3)))
        self._object_cache: dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
        self._nearest: dict[tuple[str, str], tuple[int, int]] = {}  # each pair's nearest geoms at the last step

    def _object_boxes(self, data: mujoco.MjData, name: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(lows, highs) of the world-aligned bounding boxes of an object's geoms (from MuJoCo's own
        geom_aabb) and the box around them all, computed once per state (a state set and forwarded
        without stepping is a new one)."""
        key = (data._address, data.time, data.geom_xpos.tobytes(), data.geom_xmat.tobytes())
        if self._boxes_at != key:
            rotations = data.geom_xmat.reshape(-1, 3, 3)
            aabb = self.model.geom_aabb
            centres = data.geom_xpos + np.einsum("nij,nj->ni", rotations, aabb[:, :3])
            halves = np.einsum("nij,nj->ni", np.abs(rotations), aabb[:, 3:])
            self._boxes = (centres - halves, centres + halves)
            self._boxes_at = key
            self._object_cache = {}
        found = self._object_cache.get(name)
        if found is None:
            geoms = self.geoms[name]
            low, high = self._boxes[0][geoms], self._boxes[1][geoms]
            found = self._object_cache[name] = (low, high, np.stack([low.min(axis=0), high.max(axis=0)]))
        return found

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
        best, nearest = DISTANCE_CAP, self._nearest.get((a, b))
        if nearest is not None:  # the pair nearest at the last step bounds this one's search (steps are short)
            best = min(best, mujoco.mj_geomDistance(self.model, data, nearest[0], nearest[1], best, self._fromto))
        # Broad phase: the distance between the geoms' world-aligned bounding boxes bounds theirs below,
        # first the objects' (one box around all their geoms), then each pair's.
        (low_a, high_a, box_a), (low_b, high_b, box_b) = self._object_boxes(data, a), self._object_boxes(data, b)
        gap = np.maximum(np.maximum(box_b[0] - box_a[1], box_a[0] - box_b[1]), 0.0)
        if float(gap @ gap) >= best * best:
            return float(best)
        gaps = np.maximum(np.maximum(low_b[None] - high_a[:, None], low_a[:, None] - high_b[None]), 0.0)
        lower = np.sqrt(np.einsum("ijd,ijd->ij", gaps, gaps)).ravel()
        candidates = np.flatnonzero(lower < best)
        width, ids_a, ids_b = len(gb), ga.tolist(), gb.tolist()
        for k, bound in sorted(zip(candidates.tolist(), lower[candidates].tolist()), key=lambda item: item[1]):
            if bound >= best:
                break
            pair = (ids_a[k // width], ids_b[k % width])
            if pair == nearest:
                continue
            d = mujoco.mj_geomDistance(self.model, data, pair[0], pair[1], best, self._fromto)
            if d < best:
                best, self._nearest[(a, b)] = d, pair
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
