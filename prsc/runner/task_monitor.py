"""The task of a scene (docs/tasks.md) watched in a MuJoCo episode: the world state read
from MjData (poses, velocities, geom distances by MuJoCo's own `mj_geomDistance` after a
bounding-sphere broad phase), handed to the one evaluator of prsc/task."""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from prsc.backends.names import with_body_names
from prsc.task.robustness import distance_pairs, velocity_objects
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
            self.geoms[obj["name"]] = np.flatnonzero(collides & np.isin(model.geom_bodyid, bodies))
            for finger in task.object(obj["name"]).fingers if _has(task, obj["name"]) else ():
                link = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, f"{obj['body']}/{finger}")
                if link >= 0:
                    self.geoms[f"{obj['name']}/{finger}"] = np.flatnonzero(collides & (model.geom_bodyid == link))
        self._fromto = np.zeros(6)
        self._velocity = np.zeros(6)
        self._pair_geoms: dict[tuple[str, str], tuple[np.ndarray, np.ndarray]] = {}
        self._distances_at: tuple | None = None
        self._distances: dict[tuple[str, str], float] = {}
        self._centres: np.ndarray | None = None
        self._halves: np.ndarray | None = None
        welded = model.body_weldid[model.geom_bodyid] == 0
        self._moving = ~(welded & (model.body_mocapid[model.geom_bodyid] < 0))
        self._moving_ids = np.flatnonzero(self._moving)
        self._nearest: dict[tuple[str, str], tuple[int, int]] = {}  # each pair's nearest geoms at the last step
        self.prepare(())

    def _state_key(self, data: mujoco.MjData) -> tuple:
        """What identifies a state (a state set and forwarded without stepping is a new one)."""
        return (data._address, data.time, data.qpos.tobytes(), data.mocap_pos.tobytes(), data.mocap_quat.tobytes())

    def _geom_centres(self, data: mujoco.MjData) -> np.ndarray:
        """Centres of the geoms' broad-phase boxes: a fixed geom's world-aligned box (MuJoCo's own geom_aabb,
        placed once), a moving geom's cube around its bounding sphere (centred on the geom)."""
        if self._centres is None:
            rotations = data.geom_xmat.reshape(-1, 3, 3)
            aabb = self.model.geom_aabb
            self._centres = data.geom_xpos + np.einsum("nij,nj->ni", rotations, aabb[:, :3])
            self._halves = np.where(self._moving[:, None], self.model.geom_rbound[:, None],
                                    np.einsum("nij,nj->ni", np.abs(rotations), aabb[:, 3:]))
            self.prepare(self._batch)  # the pairs' half sizes, now known
        self._centres[self._moving_ids] = data.geom_xpos[self._moving_ids]
        return self._centres

    def _pairs_of(self, a: str, b: str) -> tuple[np.ndarray, np.ndarray]:
        """Every (geom of a, geom of b), flattened."""
        found = self._pair_geoms.get((a, b))
        if found is None:
            ga, gb = self.geoms.get(a, np.zeros(0, int)), self.geoms.get(b, np.zeros(0, int))
            found = self._pair_geoms[(a, b)] = (np.repeat(ga, len(gb)), np.tile(gb, len(ga)))
        return found

    def prepare(self, pairs) -> None:
        """Distances the task will ask for at every step, computed together (one broad phase per step)."""
        self._batch = list(dict.fromkeys(pairs))
        parts = [self._pairs_of(a, b) for a, b in self._batch]
        self._batch_a = np.concatenate([p[0] for p in parts]) if parts else np.zeros(0, int)
        self._batch_b = np.concatenate([p[1] for p in parts]) if parts else np.zeros(0, int)
        self._batch_halves = None if self._halves is None else self._halves[self._batch_a] + self._halves[self._batch_b]
        bounds = np.cumsum([0] + [len(p[0]) for p in parts])
        self._batch_slices = list(zip(bounds[:-1].tolist(), bounds[1:].tolist()))

    def pose(self, data: mujoco.MjData, name: str, moving: bool = True) -> Pose:
        """The object's box centre and rotation now (the body frame is the box's, prsc/backends), views into
        `data` valid until it steps; its velocities when `moving` (else zeros: the task reads none)."""
        b = self.body[name]
        if not moving:
            return Pose(data.xpos[b], data.xmat[b].reshape(3, 3), _STILL, _STILL)
        velocity = np.zeros(6)
        mujoco.mj_objectVelocity(self.model, data, mujoco.mjtObj.mjOBJ_BODY, b, velocity, 0)
        return Pose(data.xpos[b], data.xmat[b].reshape(3, 3), velocity[3:], velocity[:3])

    def distance(self, data: mujoco.MjData, a: str, b: str) -> float:
        """The least signed distance between the geoms of a and b (capped at DISTANCE_CAP)."""
        key = self._state_key(data)
        if self._distances_at != key:
            self._distances_at, self._distances = key, {}
            centres = self._geom_centres(data)
            if self._batch:
                self._distances = self._nearest_of(data, self._batch, self._batch_slices, self._batch_a,
                                                   self._batch_b, self._batch_halves, centres)
        found = self._distances.get((a, b))
        if found is None:
            ia, ib = self._pairs_of(a, b)
            found = self._distances[(a, b)] = self._nearest_of(
                data, [(a, b)], [(0, len(ia))], ia, ib, self._halves[ia] + self._halves[ib], self._centres)[(a, b)]
        return found

    def _nearest_of(self, data, pairs, slices, ia, ib, halves, centres) -> dict[tuple[str, str], float]:
        """Broad phase (the distance between two geoms' world-aligned boxes bounds theirs below) over every
        geom pair at once, then MuJoCo's own mj_geomDistance, from the pair nearest at the last step."""
        if not len(ia):
            return {pair: DISTANCE_CAP for pair in pairs}
        gaps = np.maximum(np.abs(centres[ia] - centres[ib]) - halves, 0.0)
        lower = np.sqrt(np.einsum("nd,nd->n", gaps, gaps))
        # Each pair's search starts from its geoms nearest at the last step (steps are short); only geom
        # pairs whose broad-phase bound is under that distance are computed.
        bests, nearests = [], []
        for pair in pairs:
            nearest = self._nearest.get(pair)
            nearests.append(nearest)
            bests.append(DISTANCE_CAP if nearest is None else min(DISTANCE_CAP, mujoco.mj_geomDistance(
                self.model, data, nearest[0], nearest[1], DISTANCE_CAP, self._fromto)))
        sizes = [last - first for first, last in slices]
        candidates = np.flatnonzero(lower < np.repeat(bests, sizes)).tolist()
        owner = np.repeat(np.arange(len(pairs)), sizes)
        order = sorted(candidates, key=lambda k: lower[k])
        for k in order:
            p = int(owner[k])
            if lower[k] >= bests[p]:
                continue
            geoms = (int(ia[k]), int(ib[k]))
            if geoms == nearests[p]:
                continue
            d = mujoco.mj_geomDistance(self.model, data, geoms[0], geoms[1], bests[p], self._fromto)
            if d < bests[p]:
                bests[p], self._nearest[pairs[p]] = d, geoms
        out = {pair: float(best) for pair, best in zip(pairs, bests)}
        return out


_STILL = np.zeros(3)
_STILL.flags.writeable = False


def _has(task: Task, name: str) -> bool:
    return any(o.name == name for o in task.objects)


class TaskMonitor:
    """The task of `scene["task"]` over one MuJoCo episode: `update` once per control step, `result` at the end."""

    def __init__(self, scene: dict, model: mujoco.MjModel):
        self.task = Task.from_json(scene["task"])
        self.world = MjWorld(scene, model, self.task)
        self.world.prepare(distance_pairs(self.task))
        self.moving = velocity_objects(self.task)  # the objects whose velocities the task reads
        self.monitor = EpisodeMonitor(self.task)
        self.latest: TaskStatus | None = None  # the last update's status (a dataset recorder's frames read it)

    def state(self, model: mujoco.MjModel, data: mujoco.MjData) -> WorldState:
        """The world state of `data` at `data.time` (distances computed when the task asks)."""
        poses = _LazyPoses(self.world, data, self.moving)
        return WorldState(float(data.time), poses, lambda a, b: self.world.distance(data, a, b))

    def update(self, model: mujoco.MjModel, data: mujoco.MjData) -> TaskStatus:
        """Evaluate the task at `data.time`."""
        self.latest = self.monitor.update(self.state(model, data))
        return self.latest

    def result(self, model: mujoco.MjModel, data: mujoco.MjData, controller_finished: bool) -> dict:
        """The record's "task" dict (`record final` evaluated on `data`)."""
        return self.monitor.result(self.state(model, data), controller_finished)


class _LazyPoses(dict):
    """Poses read from MjData when the evaluator first asks for them."""

    def __init__(self, world: MjWorld, data: mujoco.MjData, moving: frozenset[str]):
        super().__init__()
        self.world, self.data, self.moving = world, data, moving

    def __missing__(self, name: str) -> Pose:
        pose = self.world.pose(self.data, name, name in self.moving)
        self[name] = pose
        return pose
