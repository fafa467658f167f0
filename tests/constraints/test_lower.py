"""Lowering specs to labelled rows: static parts, anchors, requires, erosion, infeasibility."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.stats import binomtest

from prsc.constraints import lower_program
from prsc.constraints.context import SceneContext
from prsc.constraints.polytope_ir import Support
from prsc.constraints.regions import cuboid
from prsc.constraints.specifier_rows import rows_in, rows_on
from prsc.constraints.values import ObjectValue
from prsc.errors import PrscError, format_error
from prsc.geometry.rotations import compat_euler_to_matrix
from prsc.ir import compile_program
from prsc.sampling import Sampler
from tests.original import ORIGINAL, needs_original

REPO = Path(__file__).resolve().parents[2]


def lowered(tmp_path, text):
    spec = tmp_path / "spec.prs"
    spec.write_text(text)
    return lower_program(compile_program(str(spec), ())), spec


@needs_original
def test_table_cube_static_parts_and_anchor():
    cprog = lower_program(compile_program(str(ORIGINAL / "tableCube.prs"), ()))
    plans = {p.name: p for p in cprog.objects}
    np.testing.assert_allclose(plans["table"].static_position, [0, 0, 0.4])
    # the library Panda's box is its URDF's at home: 0.779 m high (docs/assets.md, "The library's arm")
    np.testing.assert_allclose(plans["r1"].static_position, [-0.4, -0.4, 0.8 + 0.778977545 / 2], rtol=1e-8)
    assert not plans["tr_1"].region.dynamic and plans["tr_1"].static_position is None
    assert plans["c1"].region.anchor == "tr_1"
    assert plans["camera"].region.anchor is None and len(plans["camera"].region.dynamic) == 1


@needs_original
def test_all_fourteen_requires_of_the_naive_spec_are_lowered_to_rows():
    cprog = lower_program(compile_program(str(ORIGINAL / "tableCubeNaive.prs"), ()))
    assert len(cprog.program.requires) == 14
    assert sum(len(ids) for ids in cprog.lowered_requires.values()) == 14
    assert all(not plan.checks for plan in cprog.objects) and not cprog.scene_checks
    # the cube's four requires move with its tray
    assert cprog.objects[5].name == "c1" and cprog.objects[5].region.anchor == "tr_1"


def test_nonlinear_and_non_rigid_requires(tmp_path):
    cprog, _ = lowered(
        tmp_path,
        "from tabletop import *\n"
        "t = Table on Vector3D(0, 0, 0), with width 1, with length 1, with height 0.5\n"
        "a = Cube on floor, right of t by 0.2\n"
        "b = Cube completely on t\n"
        "c = Cube completely on t\n"
        "require hypot(a.x, a.y) < 2\n"
        "require b.x < 2 * a.x\n"
        "require c.y < a.y + 0.1\n",
    )
    plans = {p.name: p for p in cprog.objects}
    assert len(plans["a"].checks) == 1  # hypot: checked by rejection
    assert "b" in cprog.lowered_requires and "c" in cprog.lowered_requires
    assert plans["b"].region.anchor is None  # 2 * a.x does not move rigidly with a
    assert plans["c"].region.anchor == "a"


@pytest.mark.parametrize("seed", range(5))
def test_closed_form_erosion_keeps_every_corner_inside(seed):
    rng = np.random.default_rng(seed)
    region_rot = compat_euler_to_matrix(*rng.uniform(-1, 1, 3))
    region = cuboid(np.array([0.1, 0.2, 1.0]), region_rot, 1.0, 0.8, 0.6, None)
    box_rot = compat_euler_to_matrix(*rng.uniform(-3, 3, 3))
    half = rng.uniform(0.02, 0.12, 3)
    poly = rows_in(region, True, Support(box_rot, half), 0, None)
    corners = np.array([[i, j, k] for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)]) * half @ box_rot.T
    inside = lambda pts: region.poly.contains(pts, tol=1e-9)
    pts = rng.uniform(-1, 2, (20000, 3))
    keep = poly.contains(pts, tol=0)
    assert keep.sum() > 20
    for p in pts[keep][:200]:
        assert inside(p + corners).all()
    # Just outside one eroded face some corner leaves the region: the erosion is tight.
    centre = np.array([0.1, 0.2, 1.0])
    for a, b in zip(poly.A, poly.b):
        p = centre + a / np.dot(a, a) * (b - a @ centre + 1e-6)
        assert not inside(p + corners).all()


def test_on_a_rotated_object_rests_on_its_top_face():
    rot = compat_euler_to_matrix(0.4, 0.2, -0.1)
    table = ObjectValue("t", "Table", None, np.array([0.0, 0.0, 1.0]), rot, (1.0, 0.6, 0.1))  # type: ignore[arg-type]
    half = np.array([0.02, 0.03, 0.04])
    poly = rows_on(table, True, Support(np.eye(3), half), 0, None)
    n = rot[:, 2]
    top = table.position + 0.05 * n
    assert poly.C.shape == (1, 3)
    np.testing.assert_allclose(poly.C[0], n)
    np.testing.assert_allclose(poly.d[0], n @ top + np.abs(n) @ half)


def test_an_object_larger_than_its_support_is_reported_with_both_lines(tmp_path):
    spec = tmp_path / "big.prs"
    spec.write_text(
        "from tabletop import *\n\n"
        "t = Table at Vector3D(0, 0, 0.45), with width 0.3, with length 0.3, with height 0.9\n"
        "c = ToyCube with width 0.5,\n"
        "    completely on t\n"
    )
    with pytest.raises(PrscError) as info:
        lower_program(compile_program(str(spec), ()))
    error = info.value
    assert "completely on t" in error.message
    lines = {span.line for _, span in error.notes}
    assert {3, 5} <= lines
    text = format_error(error)
    assert f"{spec}:5:5: note: conflicting: completely on t" in text


def test_left_of_a_and_right_of_b_with_a_left_of_b_names_both_specifiers(tmp_path):
    spec = tmp_path / "lr.prs"
    spec.write_text(
        "from tabletop import *\n"
        "a = Cube at Vector3D(-0.5, 0, 0.02)\n"
        "b = Cube at Vector3D(0.5, 0, 0.02)\n"
        "c = Cube on floor, left of a,\n"
        "    right of b\n"
    )
    with pytest.raises(PrscError) as info:
        lower_program(compile_program(str(spec), ()))
    error = info.value
    assert error.span.line == 4
    notes = {span.line: note for note, span in error.notes}
    assert "left of a" in notes[4] and "right of b" in notes[5]
    assert "on floor" not in error.message  # the IIS is minimal


def test_a_random_dead_end_is_reported_after_bounded_retries(tmp_path):
    spec = tmp_path / "lr_random.prs"
    spec.write_text(
        "from tabletop import *\n"
        "table = Table on Vector3D(0, 0, 0), with width 1.8, with length 0.8, with height 0.8\n"
        "a = Cube completely on table, left of (top table) by 0.1\n"
        "b = Cube completely on table, right of (top table) by 0.1\n"
        "c = Cube completely on table, left of a,\n"
        "    right of b\n"
    )
    sampler = Sampler(compile_program(str(spec), ()))
    with pytest.raises(PrscError) as info:
        sampler.scene(0, 0)
    error = info.value
    assert "dead end" in error.message and "rejections" in error.message
    notes = {span.line: note for note, span in error.notes}
    assert "left of a" in notes[5] and "right of b" in notes[6]


def test_a_require_on_no_object_and_a_soft_require(tmp_path):
    spec = tmp_path / "req.prs"
    spec.write_text(
        "from tabletop import *\n"
        "x = (0, 1)\n"
        "param level = x\n"
        "t = Table on Vector3D(0, 0, 0), with width 1, with length 1, with height 0.5\n"
        "c = Cube completely on t\n"
        "require x > 0.5\n"
        "require[0.4] c.x > 0\n"
    )
    sampler = Sampler(compile_program(str(spec), ()))
    assert len(sampler.constraints.scene_checks) == 1
    n = 400
    right = 0
    for i in range(n):
        scene = sampler.scene(1, i)
        assert scene["params"]["level"] > 0.5
        right += next(o for o in scene["objects"] if o["name"] == "c")["position"][0] > 0
    # P(c.x > 0) = 0.4 + 0.6 * 0.5 = 0.7
    assert binomtest(right, n, 0.7).pvalue > 1e-3


def test_scene_context_memo_is_not_shared_between_scenes():
    a, b = SceneContext(np.random.default_rng(0)), SceneContext(np.random.default_rng(0))
    assert a.uniform() == b.uniform()
    a.remember_draw(1, 0.5)
    assert 1 not in b.draws


def test_coordinates_beyond_floating_point_are_an_error_at_the_object(tmp_path):
    """1e300 m breaks the LPs; that is reported at the object, not as an internal error."""
    spec = tmp_path / "spec.prs"
    spec.write_text("from tabletop import *\nt = Table on Vector3D(0, 0, 0)\nc = Cube completely on t, ahead of t by 1e300\n")
    with pytest.raises(PrscError, match="cannot place c: its constraints could not be solved numerically") as info:
        lower_program(compile_program(str(spec), ()))
    assert (info.value.span.line, info.value.span.column) == (3, 1)
