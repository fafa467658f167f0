"""`visible from C`: every box inside the camera's view frustum, and uniform on that set.

The frustum is written out here from docs/language.md "`visible from C`" (near plane at the front
of the camera's box, far plane 3 m, fovy and resolution), apart from prsc's code; the scene
checker tests containment with its own copy. Uniformity: chi-square over cells of the
table (p > 0.001, fixed seeds) against a Monte Carlo count of uniform points tested against
the relations themselves, and the same test rejects a law that lets boxes stick out.
"""

from __future__ import annotations

import functools
import math
from pathlib import Path

import numpy as np
from scipy.stats import chisquare

from prsc.ir import compile_program
from prsc.sampling import Sampler
from tests.sampling.scene_checks import check_scenes, euler_compat

P_MIN = 1e-3
N = 3000
SPEC = (
    "from tabletop import *\n"
    "table = Table on Vector3D(0, 0, 0), with width 1.2, with length 0.8, with height 0.75\n"
    "camera = Camera at Vector3D(0.3, -0.5, 1.0), with orientation Vector3D(20 deg, 0, -55 deg)\n"
    "c = Cube completely on table, with width 0.08, {visible}\n"
)
CUBE_HALF = np.array([0.04, 0.02, 0.02])
CAMERA = np.array([0.3, -0.5, 1.0])
CAMERA_R = euler_compat(math.radians(20), 0.0, math.radians(-55))
TOP = 0.75 + 0.02  # the cube's centre height on the table
GRID = (6, 4)


def _inside_view(centres: np.ndarray, half: np.ndarray) -> np.ndarray:
    """Whether an axis-aligned box of half extents `half` at each centre is inside the frustum."""
    tan_z = math.tan(math.radians(60) / 2)
    tan_x = tan_z * 640 / 480
    signs = np.array([[i, j, k] for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)], dtype=float)
    corners = centres[:, None, :] + signs * half  # (n, 8, 3)
    local = (corners - CAMERA) @ CAMERA_R  # camera frame: x right, y ahead, z up
    x, y, z = local[..., 0], local[..., 1], local[..., 2]
    ok = (y >= 0.4 / 2) & (y <= 3.0) & (np.abs(x) <= y * tan_x) & (np.abs(z) <= y * tan_z)
    return ok.all(axis=1)


def _cells(xy: np.ndarray) -> np.ndarray:
    """The table cell (of GRID) each centre falls in."""
    ix = np.clip(((xy[:, 0] + 0.6) / 1.2 * GRID[0]).astype(int), 0, GRID[0] - 1)
    iy = np.clip(((xy[:, 1] + 0.4) / 0.8 * GRID[1]).astype(int), 0, GRID[1] - 1)
    return ix * GRID[1] + iy


def _uniform_on_table(rng: np.random.Generator, n: int, half: np.ndarray) -> np.ndarray:
    """Uniform centres of the box `half` completely on the table's top."""
    x = rng.uniform(-0.6 + half[0], 0.6 - half[0], n)
    y = rng.uniform(-0.4 + half[1], 0.4 - half[1], n)
    return np.stack([x, y, np.full(n, TOP)], axis=1)


@functools.lru_cache(maxsize=None)
def _expected() -> np.ndarray:
    """Cell probabilities of the uniform law on the feasible set: Monte Carlo, 600k points."""
    points = _uniform_on_table(np.random.default_rng(7), 600_000, CUBE_HALF)
    kept = points[_inside_view(points, CUBE_HALF)]
    return np.bincount(_cells(kept), minlength=GRID[0] * GRID[1]) / len(kept)


def _p_value(xy: np.ndarray, expected: np.ndarray) -> float:
    """Chi-square p-value of the draws' cell counts; cells of probability below 1% pooled."""
    observed = np.bincount(_cells(xy), minlength=len(expected))
    if observed[expected == 0].sum():
        return 0.0  # draws where the uniform law has none
    small = (expected > 0) & (expected < 0.01)
    keep = expected >= 0.01
    obs = np.append(observed[keep], observed[small].sum())
    exp = np.append(expected[keep], expected[small].sum())
    return float(chisquare(obs, exp / exp.sum() * obs.sum()).pvalue)


def _draws(tmp_path, visible: str, n: int) -> tuple[object, list[dict]]:
    spec = tmp_path / "view.prs"
    spec.write_text(SPEC.format(visible=visible))
    program = compile_program(str(spec), (str(Path(__file__).resolve().parents[2] / "specs"),))
    sampler = Sampler(program, "exact")
    return program, [sampler.scene(13, i) for i in range(n)]


def test_visible_from_keeps_boxes_in_the_frustum_and_is_uniform_there(tmp_path):
    program, scenes = _draws(tmp_path, "visible from camera", N)
    report = check_scenes(program, scenes[:300])  # the checker's own frustum test
    assert not report and report.checked > 0, report
    xy = np.array([next(o for o in s["objects"] if o["name"] == "c")["position"] for s in scenes])
    assert _inside_view(xy, CUBE_HALF).all()
    expected = _expected()
    assert (expected > 0).sum() >= 8 and (expected == 0).sum() >= 2  # the view cuts the table
    assert _p_value(xy, expected) > P_MIN


def test_the_uniformity_test_rejects_a_law_that_lets_boxes_stick_out():
    # The wrong law: uniform over centres in the view (the box may stick out of it).
    rng = np.random.default_rng(3)
    points = _uniform_on_table(rng, 80_000, CUBE_HALF)
    wrong = points[_inside_view(points, np.zeros(3))][:N]
    assert not _inside_view(wrong, CUBE_HALF).all()
    assert _p_value(wrong, _expected()) < P_MIN
    # A law on the right set, but weighted (1 to 2) towards +x: rejected too.
    inside = points[_inside_view(points, CUBE_HALF)]
    biased = inside[rng.uniform(size=len(inside)) < 0.5 + 0.5 * (inside[:, 0] + 0.6) / 1.2][:N]
    assert len(biased) == N and _p_value(biased, _expected()) < P_MIN
    # and the right law drawn the same way passes.
    right = points[_inside_view(points, CUBE_HALF)][:N]
    assert _p_value(right, _expected()) > P_MIN
