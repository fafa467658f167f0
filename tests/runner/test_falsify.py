"""`prsc falsify` as a user runs it: rounds, weights, outputs, determinism, and `--proposal` downstream."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from prsc.cli import main
from prsc.ir import compile_program
from prsc.runner.controller import load_controller, parse_target
from prsc.sampling import compile_sampler
from tests.sampling.scene_checks import check_scenes

REPO = Path(__file__).resolve().parents[2]
SPEC = REPO / "specs" / "table_cube.prs"
CORNER = str(REPO / "tests" / "data" / "corner_controller.py") + ":corner"


def _records(path: Path) -> list[dict]:
    return [{k: v for k, v in json.loads(line).items() if k != "wall_seconds"} for line in path.read_text().splitlines()]


def test_falsify_writes_every_output_and_is_deterministic_under_jobs(tmp_path, capsys):
    common = [str(SPEC), "--budget", "8", "--rounds", "2", "--seed", "11", "--controller", CORNER]
    assert main(["falsify", *common, "-o", str(tmp_path / "one")]) == 0
    assert main(["falsify", *common, "-o", str(tmp_path / "two"), "--jobs", "2"]) == 0
    one, two = tmp_path / "one", tmp_path / "two"
    records = _records(one / "results.jsonl")
    assert records == _records(two / "results.jsonl")
    assert (one / "proposal.json").read_bytes() == (two / "proposal.json").read_bytes()
    assert [r["index"] for r in records] == list(range(8))
    assert [r["round"] for r in records] == [0] * 4 + [1] * 4
    # One assets folder for the campaign: the rounds' MJCF files refer to it, none holds its own.
    assert (one / "assets").is_dir() and not list(one.glob("round_*/assets"))
    assert all(r["law"] == "sequential" and r["weight"] > 0 for r in records)
    assert [r["weight"] for r in records[:4]] == pytest.approx([1.0] * 4)  # round 0 is the spec's own law
    assert sum(r["outcome"] == "corner" for r in records) >= 3  # seed 11's round 0 puts 3 of 4 cubes there
    assert any(r["weight"] != pytest.approx(1.0) for r in records[4:])  # round 1 draws from the learnt proposal
    for k in range(2):
        folder = one / f"round_{k:02d}"
        assert len(list((folder / "json").glob("*.json"))) == 4 and len(list((folder / "mjcf").glob("*.xml"))) == 4
    for name in ("clusters.json", "summary.txt", "falsify.png"):
        assert (one / name).stat().st_size > 0
    summary = (one / "summary.txt").read_text()
    assert "sequential law (weighted)" in summary and "distinct failure clusters" in summary
    assert "95% upper bound (one-sided)" in summary and "interval: " in summary
    assert [r["spec_draw"] for r in records[:4]] == [True] * 4  # round 0 is the spec's own law
    assert "sequential law" in capsys.readouterr().out
    # A campaign killed after round 0 resumes to the same episodes and proposal.
    three = tmp_path / "three"
    shutil.copytree(one, three)
    lines = (three / "results.jsonl").read_text().splitlines(keepends=True)
    (three / "results.jsonl").write_text("".join(lines[:4]))
    (three / "proposal.json").unlink()
    assert main(["falsify", *common, "-o", str(three), "--resume"]) == 0
    assert "kept from" in capsys.readouterr().err
    assert _records(three / "results.jsonl") == records
    assert (three / "proposal.json").read_bytes() == (one / "proposal.json").read_bytes()
    assert main(["falsify", *common, "--seed", "12", "-o", str(three), "--resume"]) == 2
    assert "another campaign" in capsys.readouterr().err


def test_uniform_method_draws_the_scenes_of_the_one_at_a_time_sampler(tmp_path, capsys):
    # The spec's law draw for draw, from per-scene Generators: Table-Cube's `prsc sample` draws the
    # same law batched, from another stream (docs/falsify.md).
    assert main(["falsify", str(SPEC), "--budget", "3", "--rounds", "1", "--seed", "2", "--method", "uniform",
                 "--controller", CORNER, "-o", str(tmp_path / "f")]) == 0
    one_at_a_time = compile_sampler(str(SPEC), law="sequential", batched=False)
    sampled = [one_at_a_time.scene(2, k) for k in range(3)]
    compiled = [json.loads((tmp_path / "f" / "round_00" / "json" / f"{k:05d}.json").read_text()) for k in range(3)]
    assert [s["objects"] for s in sampled] == [c["objects"] for c in compiled]
    assert all(r["weight"] == 1.0 for r in _records(tmp_path / "f" / "results.jsonl"))


def test_sample_and_run_draw_from_a_learnt_proposal(tmp_path, capsys):
    corner = {str(8 * column + row): 1.0 for column in (6, 7) for row in (5, 6, 7)}  # x > 0.75, y > 0.625 of the tray
    proposal = {"format": "prsc-proposal/1", "eps": 0.05,
                "components": [{"share": 1.0, "spec_share": 0.0, "cells": {"position:c1": corner}}]}
    path = tmp_path / "proposal.json"
    path.write_text(json.dumps(proposal))
    assert main(["sample", str(SPEC), "-n", "40", "--proposal", str(path), "-o", str(tmp_path / "s.jsonl")]) == 0
    scenes = [json.loads(line) for line in (tmp_path / "s.jsonl").read_text().splitlines()]
    assert not check_scenes(compile_program(SPEC), scenes)
    from tests.data.corner_controller import in_corner

    assert sum(map(in_corner, scenes)) >= 25  # the corner cells carry 95 % of the cube's draws
    assert main(["run", str(SPEC), "-n", "2", "--proposal", str(path), "--controller", CORNER,
                 "-o", str(tmp_path / "run")]) == 0
    assert len(_records(tmp_path / "run" / "results.jsonl")) == 2


def test_proposal_errors_are_clear(tmp_path, capsys):
    bad = tmp_path / "bad.json"
    bad.write_text("{\"format\": \"something else\"}")
    assert main(["sample", str(SPEC), "--proposal", str(bad)]) == 2
    assert "not a prsc proposal" in capsys.readouterr().err
    scene = tmp_path / "scene.json"
    scene.write_text((REPO / "tests" / "data" / "table_cube_scene.json").read_text())
    assert main(["compile", str(scene), "--proposal", str(bad), "-o", str(tmp_path / "c")]) == 2
    assert "does not apply to scene JSON" in capsys.readouterr().err
    assert main(["falsify", str(SPEC), "--budget", "0", "--controller", CORNER]) == 2
    other = tmp_path / "other"
    other.mkdir()
    (other / "results.jsonl").write_text("a campaign of prsc run\n")
    assert main(["falsify", str(SPEC), "--budget", "1", "--controller", CORNER, "-o", str(other)]) == 2
    assert "did not write" in capsys.readouterr().err
    assert (other / "results.jsonl").read_text() == "a campaign of prsc run\n"


def test_the_nudge_controller_fails_only_near_the_corner(tmp_path, capsys):
    # examples/nudge_controller.py, the rare failure of docs/falsify.md: a cube 5 mm from both walls of its
    # tray's +x +y corner slides into it (cornered, clearance <= 0); one 10 cm away stops short (clearance > 0).
    import mujoco

    controller = load_controller(parse_target(str(REPO / "examples" / "nudge_controller.py") + ":nudge"))
    scene = json.loads((REPO / "tests" / "data" / "table_cube_scene.json").read_text())
    objects = {o["name"]: o for o in scene["objects"]}
    tray = objects["tr_1"]["position"]
    results = {}
    for name, offset in (("corner", 0.005), ("inside", 0.1)):
        cube = objects["c1"]
        cube["position"] = [tray[0] + 0.0887 - offset, tray[1] + 0.1966 - offset, cube["position"][2]]
        path = tmp_path / f"{name}.json"
        path.write_text(json.dumps(scene))
        assert main(["compile", str(path), "--target", "mjcf", "-o", str(tmp_path / name)]) == 0
        model = mujoco.MjModel.from_xml_path(str(next((tmp_path / name).rglob("*.xml"))))
        results[name] = controller(scene, model, mujoco.MjData(model))
    assert results["corner"]["outcome"] == "cornered" and results["corner"]["clearance"] <= 1e-4, results
    assert results["inside"]["outcome"] == "success" and 0.05 < results["inside"]["clearance"] < 0.1, results


@pytest.mark.parametrize("prop, said", [("arm in tray", "its failure labels: arm on table, cube dropped"),
                                        ("anything", "its failure labels")])
def test_a_property_the_task_lacks_is_refused_before_any_episode(tmp_path, capsys, prop, said):
    out = tmp_path / "falsify"
    code = main(["falsify", str(SPEC), "--budget", "4",
                 "--rounds", "1", "--property", prop, "-o", str(out)])
    assert code == 2 and said in capsys.readouterr().err
    assert not out.exists()  # nothing was run, nothing is left


def test_a_property_without_a_task_is_refused_before_any_episode(tmp_path, capsys):
    out = tmp_path / "falsify"
    naive = REPO / "specs" / "table_cube_naive.prs"  # the same scene, no task
    assert main(["falsify", str(naive), "--budget", "4", "--rounds", "1", "--property", "goal", "-o", str(out)]) == 2
    assert "states no task" in capsys.readouterr().err and not out.exists()
