"""Each relation's robustness equals an independent computation on random poses (to 1e-6 m), and
its sign agrees with an independently computed truth on 12,000 random states (fixed seed)."""

from __future__ import annotations

import numpy as np
from scipy.optimize import lsq_linear
from scipy.spatial.transform import Rotation

from prsc.task.robustness import Evaluator, Truth
from prsc.task.task_regions import box_corners, box_region
from prsc.task.terms import Region, Task, TaskObject, TaskStatements, Term
from prsc.task.world import Pose, WorldState

A_DIMS, B_DIMS = (0.05, 0.08, 0.04), (0.4, 0.3, 0.2)


def _task() -> Task:
    top = box_region(B_DIMS)
    objects = (TaskObject("a", A_DIMS, Region(box_region(A_DIMS).normals, box_region(A_DIMS).offsets, 0.02, 0.02)),
               TaskObject("b", B_DIMS, Region(top.normals, top.offsets, top.high, top.high)))
    return Task(TaskStatements(), objects)


def _pose(rng: np.random.Generator, spread: float) -> Pose:
    return Pose(rng.uniform(-spread, spread, 3), Rotation.random(random_state=rng.integers(1 << 31)).as_matrix(),
                np.zeros(3), np.zeros(3))


def _world(a: Pose, b: Pose, distance: float = 1.0) -> WorldState:
    return WorldState(0.0, {"a": a, "b": b}, lambda x, y, enough=None: distance)


def _box_distance(point: np.ndarray, pose: Pose, dims) -> float:
    """Signed distance of a point to a box (inside positive), by bounded least squares."""
    half = np.asarray(dims) / 2
    outside = lsq_linear(pose.rotation, point - pose.position, bounds=(-half, half), tol=1e-14, method="bvls")
    gap = np.linalg.norm(pose.rotation @ outside.x + pose.position - point)
    if gap > 1e-12:
        return -gap
    local = pose.rotation.T @ (point - pose.position)  # inside: the nearest face, each face a bounded problem
    best = np.inf
    for axis in range(3):
        for sign in (-1, 1):
            low, high = -half.copy(), half.copy()
            low[axis] = high[axis] = sign * half[axis]
            high[axis] += 1e-15
            face = lsq_linear(np.eye(3), local, bounds=(low, high), tol=1e-14, method="bvls")
            best = min(best, np.linalg.norm(face.x - local))
    return best


def _term(op: str, completely: bool = False, by: float | None = None) -> Term:
    args = (Term("object", name="a"), Term("object", name="b"))
    return Term(op, args + (() if by is None else (Term("const", value=by),)), completely=completely)


def test_in_and_completely_in_are_point_in_polytope_distances():
    rng = np.random.default_rng(1)
    evaluator = Evaluator(_task())
    for _ in range(100):
        a, b = _pose(rng, 0.3), _pose(rng, 0.05)
        world = _world(a, b)
        expected = _box_distance(a.position, b, B_DIMS)
        assert abs(evaluator.robustness(_term("in"), world) - expected) < 1e-6
        corners = a.position + box_corners(A_DIMS) @ a.rotation.T
        expected = min(_box_distance(c, b, B_DIMS) for c in corners)
        assert abs(evaluator.robustness(_term("in", completely=True), world) - expected) < 1e-6


def test_direction_relations_are_the_gap_of_the_nearest_corner():
    rng = np.random.default_rng(2)
    evaluator = Evaluator(_task())
    axes = {"left": [-1, 0, 0], "right": [1, 0, 0], "ahead": [0, 1, 0], "behind": [0, -1, 0], "above": [0, 0, 1],
            "below": [0, 0, -1]}
    for _ in range(200):
        a, b = _pose(rng, 0.5), _pose(rng, 0.1)
        by = float(rng.uniform(0, 0.1))
        for word, axis in axes.items():
            n = b.rotation @ np.asarray(axis, dtype=float)
            corners = a.position + box_corners(A_DIMS) @ a.rotation.T
            expected = min(n @ (c - b.position) for c in corners) - by
            assert abs(evaluator.robustness(_term(word, by=by), _world(a, b)) - expected) < 1e-9


def test_the_sign_agrees_with_the_truth_on_12000_random_states():
    rng = np.random.default_rng(3)
    evaluator = Evaluator(_task())
    checked = 0
    for _ in range(2000):
        a, b = _pose(rng, 0.4), _pose(rng, 0.05)
        distance = float(rng.uniform(-0.01, 0.05))
        world = _world(a, b, distance)
        local_centre = b.rotation.T @ (a.position - b.position)
        corners = a.position + box_corners(A_DIMS) @ a.rotation.T
        local_corners = (corners - b.position) @ b.rotation
        half = np.asarray(B_DIMS) / 2
        ahead = b.rotation[:, 1]
        truths = {
            _term("in"): bool(np.all(np.abs(local_centre) <= half)),
            _term("in", completely=True): bool(np.all(np.abs(local_corners) <= half)),
            _term("ahead", by=0.05): bool(np.all((corners - b.position) @ ahead >= 0.05)),
            _term("touches"): distance <= 0,
            Term("not", (_term("touches"),)): distance > 0,
            # on: the lowest corner within 1 cm of b's top, the centre over the top face, in contact
            _term("on"): bool(abs(np.min(local_corners[:, 2]) - half[2]) <= 0.01
                              and np.all(np.abs(local_centre[:2]) <= half[:2]) and distance <= 0),
        }
        for term, expected in truths.items():
            value = evaluator.truth(term, world)
            assert value.holds == expected
            assert (value.robustness >= 0) == expected
            checked += 1
    assert checked >= 10_000


def test_holds_needs_two_fingers_and_nothing_else_and_visible_needs_the_view():
    box = box_region((0.1, 0.1, 0.1))
    top = Region(box.normals, box.offsets, 0.05, 0.05)
    objects = (TaskObject("arm", (0.1, 0.1, 1.0), top, fingers=("left", "right")),
               TaskObject("cube", (0.04, 0.04, 0.04), top), TaskObject("table", (1, 1, 0.8), top),
               TaskObject("cam", (0.1, 0.2, 0.1), top, camera=(60.0, 4 / 3)))
    evaluator = Evaluator(Task(TaskStatements(), objects))
    holds = Term("holds", (Term("object", name="arm"), Term("object", name="cube")))
    still = np.zeros(3)
    down = Rotation.from_euler("x", -90, degrees=True).as_matrix()  # the camera's +y (its view) points down
    poses = {"arm": Pose(np.zeros(3), np.eye(3), still, still), "cube": Pose(np.array([0, 0, 0.5]), np.eye(3), still, still),
             "table": Pose(np.array([0, 0, -1.0]), np.eye(3), still, still),
             "cam": Pose(np.array([0, 0, 2.0]), down, still, still)}

    def world(distances):
        return WorldState(0.0, poses, lambda a, b, enough=None: distances.get((a, b), 0.3))

    gripped = {("arm/left", "cube"): -0.001, ("arm/right", "cube"): -0.002, ("cube", "table"): 0.4}
    assert evaluator.truth(holds, world(gripped)) == Truth(True, 0.001)
    one_finger = {**gripped, ("arm/right", "cube"): 0.01}
    assert evaluator.truth(holds, world(one_finger)) == Truth(False, -0.01)
    on_table = {**gripped, ("cube", "table"): -0.0005}
    assert evaluator.truth(holds, world(on_table)) == Truth(False, -0.0005)
    visible = Term("visible", (Term("object", name="cube"), Term("object", name="cam")))
    assert evaluator.truth(visible, world({})).holds
    poses["cube"] = Pose(np.array([3.0, 0, 0.5]), np.eye(3), still, still)
    assert not evaluator.truth(visible, world({})).holds


def test_a_distance_answered_only_as_far_as_enough_gives_the_same_robustness():
    """`on` reads the distance with `enough` (prsc/task/world.py, DistanceFn): a simulator answering
    as loosely as it may (enough itself, when the distance is within it) changes no robustness."""
    rng = np.random.default_rng(4)
    evaluator = Evaluator(_task())
    asked = loose = 0
    for _ in range(2000):
        a, b = _pose(rng, 0.2), _pose(rng, 0.05)
        distance = float(rng.uniform(-0.01, 0.3))

        def lazy(x, y, enough=None):
            nonlocal asked, loose
            asked += 1
            if enough is not None and distance <= enough:
                loose += 1
                return enough
            return distance

        for completely in (False, True):
            term = _term("on", completely=completely)
            exact = evaluator.robustness(term, _world(a, b, distance))
            assert evaluator.robustness(term, WorldState(0.0, {"a": a, "b": b}, lazy)) == exact
    assert loose > 500 and asked - loose > 500  # both answers were given often


def test_terms_of_static_objects_are_read_once_per_episode_and_moving_ones_at_every_state():
    """`a.z < b.z + b.height / 2` with b static: b's side is read at the first state (a static object
    does not move during an episode), a's at every state; with b not static, both at every state."""
    from dataclasses import replace

    task = _task()
    term = Term("compare", (Term("attr", (Term("object", name="a"),), name="z"),
                            Term("arith", (Term("attr", (Term("object", name="b"),), name="z"),
                                           Term("arith", (Term("attr", (Term("object", name="b"),), name="height"),
                                                          Term("const", value=2.0)), name="/")), name="+")), name="<")

    def at(a_z: float, b_z: float) -> WorldState:
        still = np.zeros(3)
        return _world(Pose(np.array([0.0, 0.0, a_z]), np.eye(3), still, still),
                      Pose(np.array([0.0, 0.0, b_z]), np.eye(3), still, still))

    static = Task(task.statements, (task.objects[0], replace(task.objects[1], static=True)))
    for which, b_read_later in ((static, False), (task, True)):
        evaluator = Evaluator(which)
        assert evaluator.truth(term, at(0.05, 0.0)) == Truth(True, 0.1 - 0.05)
        # b "moves" (it cannot when static): its side keeps its first value, a's side follows a
        later = evaluator.truth(term, at(0.02, 1.0))
        assert abs(later.robustness - ((1.0 if b_read_later else 0.0) + 0.1 - 0.02)) < 1e-12
