"""`not visible from C`: the box not wholly inside the camera's view (partly or wholly out of it),
uniform on that set: the object's region minus the cell of centres whose box is wholly in view.

The view is the test's own frustum (test_visibility.py's, written from docs/language.md) and
the scene checker's own copy, apart from prsc's code. Uniformity: chi-square over cells of the
table (p > P_MIN, fixed seeds) against a Monte Carlo count of uniform points on the table
minus the in-view set; the same test rejects laws that ignore the exclusion or exclude too much.
"""

from __future__ import annotations

import functools
import re
from pathlib import Path

import numpy as np
import pytest

from prsc.cli import main
from prsc.errors import PrscError
from prsc.ir import compile_program
from prsc.sampling import Sampler
from tests.sampling.scene_checks import check_scenes
from tests.sampling.test_visibility import CUBE_HALF, GRID, SPEC, _cells, _inside_view, _p_value, _uniform_on_table

SPECS = Path(__file__).resolve().parents[2] / "specs"
P_MIN = 1e-3
N = 3000


def _program(tmp_path, text: str):
    spec = tmp_path / "hidden.prs"
    spec.write_text(text)
    return compile_program(str(spec), (str(SPECS),))


def _centres(program, method: str, n: int, seed: int = 13) -> tuple[list[dict], np.ndarray]:
    sampler = Sampler(program, method)
    scenes = [sampler.scene(seed, i) for i in range(n)]
    return scenes, np.array([next(o for o in s["objects"] if o["name"] == "c")["position"] for s in scenes])


@functools.lru_cache(maxsize=None)
def _expected() -> np.ndarray:
    """Cell probabilities of the uniform law on the table minus the in-view set: 600k points."""
    points = _uniform_on_table(np.random.default_rng(7), 600_000, CUBE_HALF)
    kept = points[~_inside_view(points, CUBE_HALF)]
    return np.bincount(_cells(kept), minlength=GRID[0] * GRID[1]) / len(kept)


def test_not_visible_from_keeps_every_box_partly_out_of_view_and_is_uniform_there(tmp_path):
    program = _program(tmp_path, SPEC.format(visible="not visible from camera"))
    scenes, xy = _centres(program, "exact", N)
    report = check_scenes(program, scenes[:300])  # the checker's own frustum, negated
    assert not report and report.checked > 0, report
    assert not _inside_view(xy, CUBE_HALF).any()
    # The perception-fault cases are in: boxes at the edge of the view (centre seen, box cut).
    assert _inside_view(xy, np.zeros(3)).sum() > 50
    expected = _expected()
    assert (expected > 0).sum() >= 20  # the view takes a part of the table, not whole cells
    assert _p_value(xy, expected) > P_MIN


def test_the_uniformity_test_rejects_laws_that_ignore_or_overdo_the_exclusion():
    rng = np.random.default_rng(5)
    points = _uniform_on_table(rng, 40_000, CUBE_HALF)
    expected = _expected()
    # The whole table (the exclusion ignored): boxes wholly in view, and rejected.
    ignored = points[:N]
    assert _inside_view(ignored, CUBE_HALF).any() and _p_value(ignored, expected) < P_MIN
    # Only centres out of view (the edge cases dropped): rejected.
    overdone = points[~_inside_view(points, np.zeros(3))][:N]
    assert len(overdone) == N and _p_value(overdone, expected) < P_MIN
    # and the right law drawn the same way passes.
    right = points[~_inside_view(points, CUBE_HALF)][:N]
    assert _p_value(right, expected) > P_MIN


@pytest.mark.parametrize("method", ["hit-and-run", "baseline"])
def test_the_other_samplers_keep_the_exclusion(tmp_path, method):
    program = _program(tmp_path, SPEC.format(visible="not visible from camera"))
    scenes, xy = _centres(program, method, 100)
    assert not _inside_view(xy, CUBE_HALF).any()
    report = check_scenes(program, scenes)
    assert not report and report.checked > 0, report


def test_the_checker_flags_a_box_moved_wholly_into_view(tmp_path):
    program = _program(tmp_path, SPEC.format(visible="not visible from camera"))
    scene = Sampler(program, "exact").scene(13, 0)
    moved = next(o for o in scene["objects"] if o["name"] == "c")
    points = _uniform_on_table(np.random.default_rng(1), 2000, CUBE_HALF)
    moved["position"] = points[_inside_view(points, CUBE_HALF)][0].tolist()
    assert any("wholly inside the view of camera" in problem for problem in check_scenes(program, [scene]))


def test_explain_prints_the_cell_and_the_measure_left(tmp_path, capsys):
    spec = tmp_path / "hidden.prs"
    spec.write_text(SPEC.format(visible="not visible from camera"))
    assert main(["explain", str(spec), "-I", str(SPECS)]) == 0
    out = capsys.readouterr().out
    assert "  minus the cells (the centre stays out of each):" in out
    assert f"    not visible from camera  [containment; {spec}:4]" in out
    left = float(out.split("feasible region minus the cells: area ")[1].split()[0])
    table = (1.2 - 2 * CUBE_HALF[0]) * (0.8 - 2 * CUBE_HALF[1])
    points = _uniform_on_table(np.random.default_rng(2), 200_000, CUBE_HALF)
    assert abs(left - table * (~_inside_view(points, CUBE_HALF)).mean()) < 0.01 * table


def test_the_guides_example_samples_and_every_scene_checks(tmp_path):
    # The cube is placed after the cup: the cup's obstacle and the in-view cell are cut together.
    blocks = re.findall(r"```prs\n(.*?)```", (SPECS.parent / "docs" / "language.md").read_text(), re.S)
    program = _program(tmp_path, next(b for b in blocks if "not visible from camera" in b))
    sampler = Sampler(program, "exact")
    report = check_scenes(program, [sampler.scene(4, i) for i in range(50)])
    assert not report and report.checked > 0, report


HEAD = SPEC.split("c = ")[0]


@pytest.mark.parametrize(("line", "message"), [
    ("c = Cube completely on table, not visible from table\n", r"'not visible from' needs a camera .* table is a Table"),
    ("c = Cube completely on table, not visible from 3\n", r"`not visible from` needs a camera object, not a scalar"),
    ("c = Cube completely on table, facing toward camera, not visible from camera\n",
     r"needs c's rotation before its position, and `facing toward` sets it after"),
])
def test_a_bad_not_visible_is_an_error_at_its_line(tmp_path, line, message):
    text = HEAD + line
    with pytest.raises(PrscError, match=message) as caught:
        Sampler(_program(tmp_path, text), "exact").scene(0, 0)
    assert caught.value.span is not None and caught.value.span.line == text.count("\n")


def test_a_region_wholly_in_view_is_a_dead_end_that_names_the_exclusion(tmp_path):
    text = ("from tabletop import *\n"
            "table = Table on Vector3D(0, 0, 0), with width 0.4, with length 0.4, with height 0.75\n"
            "camera = Camera at Vector3D(0, 0, 2), with orientation Vector3D(0, 0, -90 deg)\n"
            "c = Cube completely on table, with width 0.08, not visible from camera\n")
    with pytest.raises(PrscError, match="no free position") as caught:
        Sampler(_program(tmp_path, text), "exact").scene(0, 0)
    assert caught.value.span.line == 4
    assert any(note.startswith("excluded by not visible from camera") for note, _ in caught.value.notes)


def test_a_camera_that_may_see_the_whole_region_is_redrawn(tmp_path):
    # With the camera above the small table (|x| < ~0.7) every box on it is wholly in view:
    # a dead end that only re-placing the camera resolves.
    text = ("from tabletop import *\n"
            "table = Table on Vector3D(0, 0, 0), with width 0.4, with length 0.4, with height 0.75\n"
            "camera = Camera at Vector3D(Range(-1.5, 1.5), 0, 2), with orientation Vector3D(0, 0, -90 deg)\n"
            "c = Cube completely on table, with width 0.08, not visible from camera\n")
    program = _program(tmp_path, text)
    sampler = Sampler(program, "exact")
    scenes = [sampler.scene(0, i) for i in range(60)]
    report = check_scenes(program, scenes)
    assert not report and report.checked > 0, report
    xs = [next(o for o in s["objects"] if o["name"] == "camera")["position"][0] for s in scenes]
    assert min(abs(x) for x in xs) > 0.6
