"""The task of a scene (docs/tasks.md) watched in a MuJoCo episode: the world state read
from MjData (poses, velocities, geom distances by MuJoCo's own `mj_geomDistance` after a
bounding-sphere broad phase), handed to the one evaluator of prsc/task."""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from prsc.backends.names import with_body_names
from prsc.task.robustness import distance_pairs, velocity_objects
from prsc.task.monitor import EpisodeMonitor, TaskStatus
from prsc.task.terms import Task
from prsc.task.world import DISTANCE_CAP, Pose, WorldState

__all__ = ["TaskMonitor", "TaskStatus", "CONTROL_PERIOD"]

_geom_distance = mujoco.mj_geomDistance
_object_velocity = mujoco.mj_objectVelocity
_set_state, _kinematics = mujoco.mj_setState, mujoco.mj_kinematics
_com_positions, _com_velocities = mujoco.mj_comPos, mujoco.mj_comVel
_BODY = mujoco.mjtObj.mjOBJ_BODY
CONTROL_PERIOD = 0.02  # s of simulated time between two evaluations of the task (50 Hz)
LOGGED_STATES = 50  # states TaskMonitor.log keeps before evaluating them (1 s of control steps)
_LOGGED = mujoco.mjtState.mjSTATE_FULLPHYSICS  # time, positions, velocities, activations, mocap poses


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
    """Object names -> MuJoCo bodies and geoms of one model; reads poses and geom distances from its data."""

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
            if task.touches_by_moving_links(obj["name"]) and model.body_dofnum[bodies].sum() > 0 and model.body_weldid[body] == 0:
                # A mounted robot touches with its moving links: its base rests where it was placed.
                bodies = [b for b in bodies if model.body_weldid[b] != 0]
            self.geoms[obj["name"]] = np.flatnonzero(collides & np.isin(model.geom_bodyid, bodies))
            for finger in task.object(obj["name"]).fingers if _has(task, obj["name"]) else ():
                link = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, f"{obj['body']}/{finger}")
                if link >= 0:
                    self.geoms[f"{obj['name']}/{finger}"] = np.flatnonzero(collides & (model.geom_bodyid == link))
        bodies_of = {obj["name"]: obj["body"] for obj in objects}
        self._offsets: dict[str, np.ndarray] = {}  # a link's box centre in its body frame
        for link in task.links():
            # `X.links["NAME"]`: body X/NAME of the compiled model, its own collision geoms (not its children's)
            body = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, f"{bodies_of[link.link.of]}/{link.link.link}")
            if body < 0:
                raise ValueError(f"the model has no body for {link.link.of}.links[{link.link.link!r}]")
            self.body[link.name] = body
            self.geoms[link.name] = np.flatnonzero(collides & (model.geom_bodyid == body))
            self._offsets[link.name] = np.asarray(link.link.offset, dtype=float)
        self._fixed_bodies = frozenset(b for b in self.body.values()
                                       if model.body_weldid[b] == 0 and model.body_mocapid[b] < 0)
        self._fixed_poses: dict[str, tuple[int, Pose]] = {}
        self._views: tuple = (None,)  # (an MjData, its xpos, its xmat as (nbody, 3, 3)): views made once
        welded = model.body_weldid[model.geom_bodyid] == 0
        self._moving = ~(welded & (model.body_mocapid[model.geom_bodyid] < 0))
        self._fromto = np.zeros(6)
        self._pair_geoms: dict[tuple[str, str], tuple[np.ndarray, np.ndarray]] = {}
        # each pair's nearest geoms at the last state, and their row among a batch pair's (from its first)
        self._nearest: dict[tuple[str, str], tuple[int, int, int]] = {}
        self.prepare(())

    def prepare(self, pairs) -> None:
        """The pairs the task will ask for at every state: one broad phase places their geoms' boxes together."""
        self._batch = list(dict.fromkeys(pairs))
        parts = [self._pairs_of(a, b) for a, b in self._batch]
        self._batch_a = np.concatenate([p[0] for p in parts]) if parts else np.zeros(0, int)
        self._batch_b = np.concatenate([p[1] for p in parts]) if parts else np.zeros(0, int)
        # the batch's geoms once each, and each row's two among them (the broad phase gathers fewer positions)
        self._batch_geoms, local = np.unique(np.concatenate([self._batch_a, self._batch_b]), return_inverse=True)
        self._batch_local = (local[:len(self._batch_a)], local[len(self._batch_a):])
        bounds = np.cumsum([0] + [len(p[0]) for p in parts]).tolist()
        self._batch_rows = {pair: (first, last) for pair, first, last in zip(self._batch, bounds[:-1], bounds[1:])}
        self._batch_boxes = None  # placed at the first state (place)

    def place(self, data: mujoco.MjData) -> None:
        """Once per episode (later calls return), from the poses of a state (`data`'s, computed): the
        batch rows' box offsets are their geoms' offset plus a constant (a moving geom's box is
        centred on it, a fixed one's does not move), and their summed half sizes."""
        if self._batch_boxes is not None:
            return
        centres, halves = self._boxes(data)
        a, b, position = self._batch_a, self._batch_b, data.geom_xpos
        shift = (centres[a] - position[a]) - (centres[b] - position[b])
        # by axis first, (3, rows): the broad phase's arrays are then contiguous per axis
        self._batch_boxes = (np.ascontiguousarray(shift.T)[:, None, :], np.ascontiguousarray((halves[a] + halves[b]).T)[:, None, :])

    def _pairs_of(self, a: str, b: str) -> tuple[np.ndarray, np.ndarray]:
        """Every (geom of a, geom of b), flattened."""
        found = self._pair_geoms.get((a, b))
        if found is None:
            ga, gb = self.geoms.get(a, np.zeros(0, int)), self.geoms.get(b, np.zeros(0, int))
            found = self._pair_geoms[(a, b)] = (np.repeat(ga, len(gb)), np.tile(gb, len(ga)))
        return found

    def _boxes(self, data: mujoco.MjData) -> tuple[np.ndarray, np.ndarray]:
        """Every geom's world-aligned box (centres, half sizes): a fixed geom's around its own box
        (MuJoCo's geom_aabb), a moving geom's a cube around its bounding sphere, centred on it."""
        rotations = data.geom_xmat.reshape(-1, 3, 3)
        local = self.model.geom_aabb
        centres = np.where(self._moving[:, None], data.geom_xpos,
                           data.geom_xpos + np.einsum("nij,nj->ni", rotations, local[:, :3]))
        halves = np.where(self._moving[:, None], self.model.geom_rbound[:, None],
                          np.einsum("nij,nj->ni", np.abs(rotations), local[:, 3:]))
        return centres, halves

    def batch_lower_bounds(self, positions: np.ndarray) -> np.ndarray:
        """Squared broad-phase bounds of every batch row (geom pair) given the geoms' `positions`
        (ngeom, 3) in one state, or (states, ngeom, 3) in several states of the episode (after place)."""
        shift, halves = self._batch_boxes
        states = positions if positions.ndim == 3 else positions[None]
        by_axis = states[:, self._batch_geoms, :].transpose(2, 0, 1)  # (3, states, the batch's geoms)
        first, second = self._batch_local
        gaps = np.abs(by_axis[:, :, first] - by_axis[:, :, second] + shift)
        gaps -= halves
        np.maximum(gaps, 0.0, out=gaps)
        gaps *= gaps
        lower2 = gaps[0] + gaps[1] + gaps[2]
        return lower2 if positions.ndim == 3 else lower2[0]

    def least_bounds(self, lower2: np.ndarray) -> list[dict[tuple[str, str], tuple[float, int, float]]]:
        """Per state (row of `lower2`, batch_lower_bounds of several states): each batch pair's least
        squared bound, the row it is in (counted from the pair's first row) and the least of the others."""
        states, columns = len(lower2), []
        for first, last in self._batch_rows.values():
            bounds = lower2[:, first:last]
            if last - first >= 2:
                two = np.partition(bounds, 1, axis=1)
                columns.append(zip(two[:, 0].tolist(), bounds.argmin(axis=1).tolist(), two[:, 1].tolist()))
            else:  # one geom pair or none: no other
                least = bounds[:, 0].tolist() if last > first else [math.inf] * states
                columns.append(zip(least, [0] * states, [math.inf] * states))
        return [dict(zip(self._batch_rows, found)) for found in zip(*columns)] if columns else [{}] * states

    def lower_bounds(self, data: mujoco.MjData, ia: np.ndarray, ib: np.ndarray) -> np.ndarray:
        """Squared broad-phase bounds of geom pairs (ia[k], ib[k]) outside the batch."""
        centres, halves = self._boxes(data)
        return _squared_box_gaps(centres[ia] - centres[ib], halves[ia] + halves[ib])

    def pose(self, data: mujoco.MjData, name: str, moving: bool = True) -> Pose:
        """The object's box centre and rotation now (the body frame is the box's, prsc/backends), views into
        `data` valid until it steps; its velocities when `moving` (else zeros: the task reads none)."""
        b = self.body[name]
        offset = self._offsets.get(name)
        if offset is not None:  # a link: its box centre, off its body's origin
            found = self._fixed_poses.get(name)
            if found is not None and found[0] == data._address:
                return found[1]
            rotation = data.xmat[b].reshape(3, 3).copy()
            pose = Pose(data.xpos[b] + rotation @ offset, rotation, _STILL, _STILL)
            if b in self._fixed_bodies:  # a link welded to the world (a cabinet's carcass): placed once
                self._fixed_poses[name] = (data._address, pose)
            return pose
        if b in self._fixed_bodies:  # welded to the world: placed once
            found = self._fixed_poses.get(name)
            if found is None or found[0] != data._address:
                found = self._fixed_poses[name] = (data._address, Pose(data.xpos[b].copy(), data.xmat[b].reshape(3, 3).copy(),
                                                                     _STILL, _STILL))
            return found[1]
        views = self._views
        if views[0] is not data:  # another MjData than the last one asked about (kept: its arrays stay valid)
            views = self._views = (data, data.xpos, data.xmat.reshape(-1, 3, 3))
        if not moving:
            return Pose(views[1][b], views[2][b], _STILL, _STILL)
        velocity = np.zeros(6)
        _object_velocity(self.model, data, _BODY, b, velocity, 0)
        return Pose(views[1][b], views[2][b], velocity[3:], velocity[:3])

    def distances(self, data: mujoco.MjData, lower2: np.ndarray | None = None,
                  least: dict | None = None) -> StateDistances:
        """The distances between geoms of `data`'s present state, computed when asked (`lower2`, `least`:
        the batch's broad phase in this state and its least bounds, when already computed)."""
        return StateDistances(self, data, lower2, least)


class StateDistances:
    """The least signed distance between two objects' geoms in one state of one MjData (capped at
    DISTANCE_CAP), by MuJoCo's own mj_geomDistance after a broad phase: the distance between two
    geoms' world-aligned boxes bounds theirs below, so only pairs whose bound is under the best
    distance found so far are computed, starting from the pair nearest at the last state."""

    def __init__(self, world: MjWorld, data: mujoco.MjData, lower2: np.ndarray | None = None,
                 least: dict | None = None):
        self.world, self.data = world, data
        self.exact: dict[tuple[str, str], float] = {}
        self._lower2 = lower2  # the squared broad-phase bound of every batch row, once per state
        self._least = least  # MjWorld.least_bounds of this state, when computed

    def __call__(self, a: str, b: str, enough: float | None = None) -> float:
        """The distance between a's and b's geoms; when `enough` is given and it is at most `enough`,
        possibly only some value between it and `enough` (prsc/task/world.py, DistanceFn)."""
        pair = (a, b)
        found = self.exact.get(pair)
        if found is not None:
            return found
        world, data = self.world, self.data
        nearest = world._nearest.get(pair)
        best = DISTANCE_CAP
        if nearest is not None:
            # at most DISTANCE_CAP: mj_geomDistance returns its limit for geoms further apart
            best = _geom_distance(world.model, data, nearest[0], nearest[1], DISTANCE_CAP, world._fromto)
            if enough is not None and best <= enough:
                return best  # the caller's answer does not depend on how much nearer the geoms are
        least = None if self._least is None else self._least.get(pair)
        if least is not None and best > 0.0:
            low, row, other = least
            if best * best <= (other if nearest is not None and row == nearest[2] else low):
                # no pair but the nearest one has a bound under its distance: the loop below would compute none
                self.exact[pair] = best
                return best
        rows = world._batch_rows.get(pair)
        if rows is None:  # a pair the task did not announce (prepare): its own broad phase
            ia, ib = world._pairs_of(a, b)
            lower2 = world.lower_bounds(data, ia, ib)
        else:
            if self._lower2 is None:
                world.place(data)
                self._lower2 = world.batch_lower_bounds(data.geom_xpos)
            first, last = rows
            ia, ib, lower2 = world._batch_a[first:last], world._batch_b[first:last], self._lower2[first:last]
        if best > 0.0:
            candidates = (lower2 < best * best).nonzero()[0]
            if candidates.size:
                # nearest bound first: a pair whose bound is past the best found so far is not computed
                for low2, first, second, row in sorted(zip(lower2[candidates].tolist(), ia[candidates].tolist(),
                                                           ib[candidates].tolist(), candidates.tolist())):
                    if low2 >= best * best:
                        break
                    if nearest is not None and first == nearest[0] and second == nearest[1]:
                        continue
                    d = _geom_distance(world.model, data, first, second, best, world._fromto)
                    if d < best:
                        best, world._nearest[pair] = d, (first, second, row)
        self.exact[pair] = best = float(best)
        return best


def _squared_box_gaps(offsets: np.ndarray, halves: np.ndarray) -> np.ndarray:
    """The squared distance between two world-aligned boxes `offsets` apart (centre to centre)
    whose half sizes sum to `halves` (0 where they overlap), over the last axis."""
    gaps = np.abs(offsets) - halves
    np.maximum(gaps, 0.0, out=gaps)
    return np.einsum("...d,...d->...", gaps, gaps)


_STILL = np.zeros(3)
_STILL.flags.writeable = False


def _has(task: Task, name: str) -> bool:
    return any(o.name == name for o in task.objects)


class TaskMonitor:
    """The task of `scene["task"]` over one MuJoCo episode: `update` once per control step, `result` at the end.

    `log` instead of `update` keeps the step's state (and its geoms' positions, for the broad phase)
    and evaluates the kept states together, on the monitor's own MjData, when LOGGED_STATES are kept
    or the result is asked for: the same statuses (positions and velocities are recomputed from the
    same state by the same MuJoCo functions), at about half the cost. A controller runs between two
    control steps and leaves the evaluator's code and data out of the CPU's caches: one update took
    137 us so against 64 us in a row (measured, docs/tasks.md, Cost). Whoever reads each step's
    status as it happens (`latest`) uses `update`."""

    def __init__(self, scene: dict, model: mujoco.MjModel):
        self.task = Task.from_json(scene["task"])
        self.model = model
        self.world = MjWorld(scene, model, self.task)
        self.world.prepare(distance_pairs(self.task))
        self.moving = velocity_objects(self.task)  # the objects whose velocities the task reads
        self.monitor = EpisodeMonitor(self.task)
        self.latest: TaskStatus | None = None  # the last update's status (a dataset recorder's frames read it)
        self._logged = np.zeros((LOGGED_STATES, mujoco.mj_stateSize(model, _LOGGED)))
        self._positions = np.zeros((LOGGED_STATES, model.ngeom, 3))  # their geoms' positions (broad phase)
        self._count = 0
        self._replay: mujoco.MjData | None = None

    def log(self, model: mujoco.MjModel, data: mujoco.MjData) -> None:
        """Keep `data`'s state at this control step, to be evaluated with the next ones; `data`'s
        positions are those of its state, as in a control callback (mj_step computed them)."""
        if not self._count:
            self.world.place(data)
        mujoco.mj_getState(model, data, self._logged[self._count], _LOGGED)
        # the geoms' positions for the broad phase: mj_kinematics of the state would give these same numbers
        self._positions[self._count] = data.geom_xpos
        self._count += 1
        if self._count == LOGGED_STATES:
            self.evaluate_logged()

    def evaluate_logged(self) -> None:
        """Evaluate the logged states in order (`update` on each), on the monitor's own MjData, after
        one broad phase over all of their geoms' positions."""
        if not self._count:
            return
        if self._replay is None:
            self._replay = mujoco.MjData(self.model)
        model, replay, rows = self.model, self._replay, self._logged[:self._count]
        world, moving, update = self.world, self.moving, self.monitor.update
        lower2 = world.batch_lower_bounds(self._positions[:self._count])
        for row, bounds, least in zip(rows, lower2, world.least_bounds(lower2)):
            _set_state(model, replay, row, _LOGGED)
            # what the task reads: body and geom poses, and the velocities (centres of mass first) when it reads any
            _kinematics(model, replay)
            if moving:
                _com_positions(model, replay)
                _com_velocities(model, replay)
            self.latest = update(WorldState(replay.time, _LazyPoses(world, replay, moving),
                                            StateDistances(world, replay, bounds, least)))
        self._count = 0

    def state(self, model: mujoco.MjModel, data: mujoco.MjData, lower2: np.ndarray | None = None,
              least: dict | None = None) -> WorldState:
        """The world state of `data` at `data.time` (distances computed when the task asks; `lower2`,
        `least`: its broad phase, computed with other logged states)."""
        poses = _LazyPoses(self.world, data, self.moving)
        return WorldState(float(data.time), poses, self.world.distances(data, lower2, least))

    def update(self, model: mujoco.MjModel, data: mujoco.MjData) -> TaskStatus:
        """Evaluate the task at `data.time`."""
        self.latest = self.monitor.update(self.state(model, data))
        return self.latest

    def result(self, model: mujoco.MjModel, data: mujoco.MjData, controller_finished: bool) -> dict:
        """The record's "task" dict (`record final` evaluated on `data`), after any logged states."""
        self.evaluate_logged()
        return self.monitor.result(self.state(model, data), controller_finished)


class _LazyPoses(dict):
    """Poses read from MjData when the evaluator first asks for them."""

    def __init__(self, world: MjWorld, data: mujoco.MjData, moving: frozenset[str]):
        self.world, self.data, self.moving = world, data, moving

    def __missing__(self, name: str) -> Pose:
        pose = self.world.pose(self.data, name, name in self.moving)
        self[name] = pose
        return pose
