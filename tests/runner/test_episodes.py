"""Whole episodes in MuJoCo: the nominal scene succeeds, constructed ones fail as they should."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from prsc.runner import DEFAULT_CONTROLLER, EpisodeTask, parse_target
from prsc.runner.handover import OUTCOMES
from prsc.runner.harness import run_episode as run_task
from prsc.cli import main
from tests.original import ORIGINAL, needs_original


def run_episode(scene: dict, mjcf: Path):
    """One handover episode of a compiled scene, as `prsc run` runs it."""
    return run_task(EpisodeTask(0, scene, str(mjcf), 0, parse_target(DEFAULT_CONTROLLER)))


@pytest.fixture
def out_of_view(table_cube, variant):
    """The camera moved 0.7 m to the right: the left tray and its cube leave the image."""
    return variant(table_cube, camera=(0.7, -0.03))


@pytest.fixture
def beyond_reach(table_cube, variant):
    """Tray and cube at the far left corner of the table, 0.82 m from r1's base."""
    return variant(table_cube, tr_1=(-0.70, 0.17), c1=(-0.78, 0.33))


def test_nominal_scene_succeeds_and_is_deterministic(table_cube, compile_scene):
    mjcf = compile_scene(table_cube)
    first = run_episode(table_cube, mjcf)
    assert first.outcome == "success", first.reason
    tray = next(o for o in table_cube["objects"] if o["name"] == "tr_2")
    half = np.asarray(tray["dimensions"][:2]) / 2
    assert np.all(np.abs(np.asarray(first.extra["cube_final"][:2]) - tray["position"][:2]) < half)
    second = run_episode(table_cube, mjcf)
    strip = lambda r: {k: v for k, v in r.to_json().items() if k != "wall_seconds"}  # noqa: E731
    assert strip(first) == strip(second)


def test_cube_out_of_view_is_a_perception_fault(out_of_view, compile_scene):
    result = run_episode(out_of_view, compile_scene(out_of_view))
    assert result.outcome == "perception_fault", result.reason
    assert "not detected" in result.reason


def test_cube_beyond_reach_is_no_path(beyond_reach, compile_scene):
    result = run_episode(beyond_reach, compile_scene(beyond_reach))
    assert result.outcome == "no_path", result.reason
    assert "r1 cannot reach" in result.reason


def test_prsc_run_names_missing_roles(table_cube, tmp_path, capsys):
    table_cube["objects"] = [o for o in table_cube["objects"] if o["class"] != "Cube"]
    scene = tmp_path / "scene.json"
    scene.write_text(json.dumps(table_cube))
    assert main(["run", str(scene), "-o", str(tmp_path / "run")]) == 2
    assert "1 Cube (found 0)" in capsys.readouterr().err
    assert not (tmp_path / "run" / "results.jsonl").exists()


def test_prsc_run_refuses_a_spec_without_the_roles_before_compiling(tmp_path, capsys):
    """specs/shelf_bin.prs has one Robot and no Tray or Cube: exit 2 at once, nothing written."""
    spec = Path(__file__).resolve().parents[2] / "specs" / "shelf_bin.prs"
    out = tmp_path / "run"
    assert main(["run", str(spec), "-n", "3", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err == (f"prsc: error: scene {spec} #0 does not fit the handover task: it needs 2 Robots (found 1), "
                   "2 Trays (found 0), 1 Cube (found 0); the runner expects two Robots, two Trays, one Cube and one Camera\n")
    assert not out.exists()


def test_prsc_run_input_errors(tmp_path, capsys):
    """A malformed line of a .jsonl is named by its line; a missing file and a bad seed are plain errors."""
    scenes = tmp_path / "scenes.jsonl"
    scenes.write_text('{"format": "prsc-scene", "version": 1, "objects": []}\n{"oops"\n')
    assert main(["run", str(scenes), "-o", str(tmp_path / "run")]) == 2
    assert capsys.readouterr().err.startswith(f"{scenes}:2:8: error: invalid JSON: Expecting ':' delimiter")
    assert main(["run", str(tmp_path / "missing.prs"), "-o", str(tmp_path / "run")]) == 2
    assert capsys.readouterr().err == f"prsc: error: cannot read {tmp_path / 'missing.prs'}: No such file or directory\n"
    for option, value, message in [("--seed", "-1", "--seed must be >= 0, got -1"), ("-n", "0", "-n must be >= 1, got 0"),
                                   ("--jobs", "-1", "--jobs must be >= 1, got -1"),
                                   ("--video", "-2", "--video must be >= 0, got -2")]:
        assert main(["run", str(scenes), option, value, "-o", str(tmp_path / "run")]) == 2
        assert capsys.readouterr().err == f"prsc: error: {message}\n"
    assert not (tmp_path / "run").exists()


@needs_original
def test_prsc_run_three_episodes_of_the_original_spec(tmp_path, capsys):
    """`prsc run` on the original ProbRobScene tableCube.prs, unmodified: 3 episodes, 2 workers."""
    spec = ORIGINAL / "tableCube.prs"
    out = tmp_path / "run"
    assert main(["run", str(spec), "-n", "3", "--seed", "0", "-o", str(out), "--jobs", "2", "--video", "1"]) == 0
    lines = [json.loads(line) for line in (out / "results.jsonl").read_text().splitlines()]
    assert [r["index"] for r in lines] == [0, 1, 2]
    keys = {"index", "seed", "outcome", "reason", "cube_initial", "cube_final", "sim_seconds", "wall_seconds"}
    assert all(set(r) == keys and len(r["cube_initial"]) == 3 and r["outcome"] in OUTCOMES for r in lines)
    assert all((r["reason"] == "") == (r["outcome"] == "success") for r in lines)
    assert (out / "outcomes.png").stat().st_size > 0 and (out / "cube_map.png").stat().st_size > 0
    failures = [r for r in lines if r["outcome"] != "success"]
    strips = sorted(p.name for p in (out / "failures").glob("*.png")) if failures else []
    assert strips == [f"episode_{r['index']:04d}_{r['outcome']}.png" for r in failures[:1]]
    assert (out / "tableCube" / "mjcf" / "00002.xml").is_file()  # the files `prsc compile` writes
    table = capsys.readouterr().out
    assert "outcome" in table and "total" in table
