"""Benchmark of prsc.geometry: sampler setup and draw rates, OBB tests, free space, IIS.

Run: .venv/bin/python bench/bench_geometry.py   (prints one line per measurement)
"""

from __future__ import annotations

import time

import numpy as np
from scipy.spatial.transform import Rotation

from prsc.geometry import (
    Box,
    Polytope,
    boxes_collide,
    collides_many,
    compat_euler_to_matrix,
    free_space,
    hit_and_run,
    intersect,
    irreducible_infeasible_subset,
    minkowski_obstacle,
    prepare_sampler,
    rot_z,
)


def per_call(fn, min_time: float = 0.5) -> float:
    """CPU seconds per call of fn() (repeated for at least min_time of CPU time).

    Process CPU time, not wall time, so other load on the machine distorts it less.
    """
    fn()
    n, start = 0, time.process_time()
    while True:
        fn()
        n += 1
        elapsed = time.process_time() - start
        if elapsed > min_time:
            return elapsed / n


def main() -> None:
    rng = np.random.default_rng(0)
    r = compat_euler_to_matrix(0.4, 0.3, -0.2)
    # 3D: a rotated box region, eroded by a differently rotated object, cut by a direction row.
    region3 = (
        Polytope.from_box(Box([0, 0, 0.5], r, [0.7, 0.5, 0.4]), label=0)
        .erode_by_box(rot_z(0.9), [0.1, 0.2, 0.05])
        .intersect(Polytope.halfspace([1, 1, 0], 0.3, label=1))
    )
    # 2D: `completely on` a yawed table top (footprint rows eroded, plus the plane).
    table_r = rot_z(0.3)
    foot = Polytope.from_rows(
        np.vstack([table_r[:, 0], -table_r[:, 0], table_r[:, 1], -table_r[:, 1]]), [0.9, 0.9, 0.4, 0.4], labels=0
    ).erode_by_box(rot_z(1.2), [0.05, 0.1, 0.05])
    region2 = foot.intersect(Polytope.plane([0, 0, 1], 0.85, label=1), Polytope.halfspace(-table_r[:, 0], 0.0, label=2))

    for name, region in (("3D", region3), ("2D", region2)):
        s = prepare_sampler(region)
        setup = per_call(lambda: prepare_sampler(region))
        batch = per_call(lambda: s.sample(rng, 1_000_000), 1.0)
        single = per_call(lambda: s.sample_one(rng))
        print(f"{name} sampler ({region.num_rows} rows, {len(s.simplices)} simplices): setup {setup * 1e3:.3f} ms, "
              f"batch {1e6 / batch / 1e6:.1f} M draws/s, single {1 / single / 1e3:.0f} k draws/s")

    # Hit-and-run for comparison: one independent sample = walk_length steps.
    har = per_call(lambda: hit_and_run(region3, rng, 10_000, walk_length=100), 1.0)
    print(f"hit-and-run (walk 100, 10k parallel chains): {10_000 / har / 1e3:.1f} k samples/s")

    # OBB tests.
    a = Box([0, 0, 0], rot_z(0.3), [0.3, 0.2, 0.1])
    hit = Box([0.3, 0.1, 0.05], rot_z(1.0), [0.3, 0.2, 0.1])
    miss = Box([2.0, 0, 0], rot_z(1.0), [0.3, 0.2, 0.1])
    for label, b in (("colliding", hit), ("separated", miss)):
        t = per_call(lambda: boxes_collide(a, b))
        print(f"boxes_collide single pair ({label}): {1 / t / 1e3:.0f} k tests/s")
    n = 100_000
    cs = rng.uniform(-1, 1, (n, 3))
    rs = Rotation.random(n, random_state=1).as_matrix()
    hs = rng.uniform(0.05, 0.3, (n, 3))
    t = per_call(lambda: collides_many(a, cs, rs, hs), 1.0)
    print(f"collides_many (N={n}): {n / t / 1e6:.2f} M tests/s")

    # Free space: a new box on a table with k placed boxes.
    new_r, new_h = rot_z(0.5), np.array([0.05, 0.1, 0.05])
    top = Polytope.from_rows(np.array([[1.0, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0]]), [0.9, 0.9, 0.4, 0.4])
    top = top.erode_by_box(new_r, new_h).intersect(Polytope.plane([0, 0, 1], 0.85))
    cube = Polytope.from_box(Box([0, 0, 1.0], np.eye(3), [0.9, 0.4, 0.3])).erode_by_box(new_r, new_h)
    for k in (1, 3, 6):
        placed = [Box([-0.7 + 1.4 * i / max(k - 1, 1), 0.1 * (-1) ** i, 0.85], rot_z(0.7 * i), [0.08, 0.12, 0.05]) for i in range(k)]
        obs = [minkowski_obstacle(b, new_r, new_h) for b in placed]
        for name, reg in (("2D", top), ("3D", cube)):
            fs = free_space(reg, obs)
            t = per_call(lambda: free_space(reg, obs).sampler())
            print(f"free space {name}, {k} obstacles: {len(fs.pieces)} pieces, setup {t * 1e3:.2f} ms")

    # IIS: 20 labelled rows with one conflicting pair hidden among them.
    rows = [Polytope.from_box(Box([0, 0, 0.5], np.eye(3), [1, 1, 0.5]), label=0)]
    for i in range(1, 13):
        ang = 2 * np.pi * i / 13
        rows.append(Polytope.halfspace([np.cos(ang), np.sin(ang), 0], 0.9, label=i))
    rows.append(Polytope.halfspace([-1, 0, 0], -2.0, label=13))
    p = intersect(*rows)
    t = per_call(lambda: irreducible_infeasible_subset(p))
    print(f"IIS over {p.num_rows} rows / 14 labels -> {irreducible_infeasible_subset(p)}: {t * 1e3:.2f} ms")


if __name__ == "__main__":
    main()
