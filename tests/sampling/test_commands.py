"""`prsc sample`, `prsc explain` and `prsc bench` through the real command line entry point."""

from __future__ import annotations

import json
from pathlib import Path

from prsc.cli import main
from prsc.sampling import compile_sampler

REPO = Path(__file__).resolve().parents[2]
# The project's own Table-Cube specs: the suite is complete without ../shared.
TABLE_CUBE = str(REPO / "specs" / "table_cube.prs")
NAIVE = str(REPO / "specs" / "table_cube_naive.prs")


def test_sample_prints_one_scene_per_line(capsys):
    assert main(["sample", TABLE_CUBE, "-n", "3", "--seed", "4"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert len(lines) == 3
    scenes = [json.loads(line) for line in lines]
    assert [s["index"] for s in scenes] == [0, 1, 2] and all(s["seed"] == 4 for s in scenes)
    assert scenes[2] == json.loads(json.dumps(compile_sampler(TABLE_CUBE).scene(4, 2)))


def test_sample_to_a_file_and_other_samplers(tmp_path, capsys):
    out = tmp_path / "scenes.jsonl"
    assert main(["sample", NAIVE, "-n", "2", "--start", "5", "--sampler", "baseline", "-o", str(out), "--stats"]) == 0
    captured = capsys.readouterr()
    assert captured.out == "" and "require" in captured.err
    assert [json.loads(line)["index"] for line in out.read_text().splitlines()] == [5, 6]
    assert main(["sample", NAIVE, "-n", "1", "--sampler", "hit-and-run", "--walk-length", "20"]) == 0


def test_sample_errors_exit_2_and_leave_no_file(tmp_path, capsys):
    spec = tmp_path / "bad.prs"
    spec.write_text(
        "from tabletop import *\n"
        "table = Table on Vector3D(0, 0, 0), with width 1.8, with length 0.8, with height 0.8\n"
        "a = Cube completely on table, left of (top table) by 0.1\n"
        "b = Cube completely on table, right of (top table) by 0.1\n"
        "c = Cube completely on table, left of a, right of b\n"
    )
    out = tmp_path / "out.jsonl"
    assert main(["sample", str(spec), "-n", "2", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert f"{spec}:5:1: error: could not sample scene 0" in err and "note: conflicting: left of a" in err
    assert not out.exists() and list(tmp_path.iterdir()) == [spec]


def test_explain_shows_rows_sources_regions_and_order(capsys):
    assert main(["explain", NAIVE]) == 0
    text = capsys.readouterr().out
    assert "evaluation order: table, r1, r2, tr_1, tr_2, c1, camera" in text
    assert f"require (right tr_1).x + 0.2 < table.x  [require; {NAIVE}:22]" in text
    assert "x <= -0.3182" in text
    assert "feasible region: dimension 2, area 0.11488 m^2" in text
    assert "moves with tr_1" in text
    assert "feasible region: dimension 0, a single point" in text
    assert main(["explain", TABLE_CUBE, "--stage", "ir"]) == 0
    assert "completely on table" in capsys.readouterr().out


def test_bench_json_reports_every_sampler(capsys):
    assert main(["bench", TABLE_CUBE, NAIVE, "--json", "-n", "5", "--seconds", "5"]) == 0
    report = json.loads(capsys.readouterr().out)["specs"]
    assert set(report) == {TABLE_CUBE, NAIVE}
    for spec, per in report.items():
        # Both specs are batched: each exact law also one scene at a time, side by side.
        assert set(per) == {"exact/joint", "exact/sequential", "exact/rejection", "hit-and-run", "baseline",
                            "exact/joint, one at a time", "exact/sequential, one at a time"}
        for name, r in per.items():
            assert r["scenes"] == 5 and r["scenes_per_s"] > 0 and r["peak_memory_mb"] > 0
            assert set(r["rejections_by_cause"]) >= {"collision", "relative position", "containment", "require"}
            assert r["ks_statistic"] is None  # 5 reference scenes: too few for a distance
        # Table-Cube's objects do not interact: the joint law needs no sweeps, nothing is rejected.
        assert per["exact/joint"]["rejections_per_scene"] == per["exact/sequential"]["rejections_per_scene"] == 0
        assert per["baseline"]["rejections_per_scene"] > 10


def test_bench_reports_the_distance_to_the_rejection_reference(capsys):
    spec = str(Path(__file__).parent / "data" / "tray_four_cubes.prs")
    args = ["bench", spec, "--json", "-n", "400", "--samplers", "exact", "--laws", "sequential,rejection"]
    assert main(args) == 0
    per = json.loads(capsys.readouterr().out)["specs"][spec]
    assert set(per) == {"exact/sequential", "exact/rejection"}
    assert per["exact/rejection"]["ks_statistic"] is None
    assert 0 < per["exact/sequential"]["ks_statistic"] <= 1 and 0 <= per["exact/sequential"]["ks_pvalue"] <= 1


def test_bench_table(capsys):
    assert main(["bench", TABLE_CUBE, "-n", "3", "--samplers", "exact"]) == 0
    out = capsys.readouterr().out
    assert "scenes/s" in out and "exact" in out


def test_sample_output_path_is_checked_before_sampling(tmp_path, capsys):
    """-o under a file, at a folder, in a missing folder or empty: exit 2 with why, nothing written."""
    blocker = tmp_path / "a_file"
    blocker.write_text("x")
    cases = [
        (str(blocker / "x.jsonl"), f"cannot write {blocker / 'x.jsonl'}: {blocker} is not a folder"),
        (str(tmp_path), f"cannot write {tmp_path}: it is a folder"),
        (str(tmp_path / "nowhere" / "x.jsonl"), f"cannot write {tmp_path / 'nowhere' / 'x.jsonl'}: folder {tmp_path / 'nowhere'} does not exist"),
        ("", "the output path is empty"),
    ]
    for output, message in cases:
        assert main(["sample", TABLE_CUBE, "-o", output]) == 2
        assert capsys.readouterr().err == f"prsc: error: {message}\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a_file"]


def test_sample_file_is_readable_by_others(tmp_path):
    """The temporary file is private (mkstemp); the dataset it becomes is not."""
    out = tmp_path / "scenes.jsonl"
    assert main(["sample", TABLE_CUBE, "-o", str(out)]) == 0
    assert out.stat().st_mode & 0o777 == 0o644


def test_sample_names_the_bad_option(capsys):
    assert main(["sample", TABLE_CUBE, "--start", "-3"]) == 2
    assert capsys.readouterr().err == "prsc: error: --start must be >= 0, got -3\n"


def test_bench_refuses_bad_counts_and_reports_spec_errors_as_such(tmp_path, capsys):
    for option, value, message in [("-n", "0", "-n must be >= 1, got 0"), ("-n", "-4", "-n must be >= 1, got -4"),
                                   ("--seconds", "0", "--seconds must be > 0, got 0.0"),
                                   ("--seconds", "nan", "--seconds must be > 0, got nan")]:
        assert main(["bench", TABLE_CUBE, "--samplers", "exact", option, value]) == 2
        assert capsys.readouterr().err == f"prsc: error: {message}\n"
    spec = tmp_path / "tiny_table.prs"
    spec.write_text("from tabletop import *\n"
                    "table = Table on Vector3D(0, 0, 0), with width (0.2, 0.3), with length (0.2, 0.3)\n"
                    "c = Cube completely on table, with width 1.0, with length 1.0\n")
    assert main(["bench", str(spec), "--samplers", "exact", "-n", "2"]) == 2
    err = capsys.readouterr().err
    # Formatted once, in this process, with its location and notes (not "prsc: error: <file>:...").
    assert err.startswith(f"{spec}:3:1: error: could not sample scene") and f"{spec}:3:10: note: conflicting" in err


def test_bench_reports_a_crash_of_its_process_as_an_internal_error(monkeypatch, capsys):
    """A bug in the measuring process is exit 3, never passed off as the user's error."""
    from prsc.commands import bench

    def broken(*args):
        raise ZeroDivisionError("division by zero")

    monkeypatch.setattr(bench, "measure", broken)
    assert main(["bench", TABLE_CUBE, "--samplers", "exact", "-n", "2"]) == 3
    assert "prsc: internal error: BenchmarkProcessError: ZeroDivisionError: division by zero" in capsys.readouterr().err


def test_sample_into_a_read_only_folder_simulated(tmp_path, capsys, monkeypatch):
    """EACCES on creating the temporary file (tests run as root, where permissions are not enforced)."""
    import errno
    import tempfile

    def denied(*args, **kwargs):
        raise PermissionError(errno.EACCES, "Permission denied")

    monkeypatch.setattr(tempfile, "mkstemp", denied)
    out = tmp_path / "scenes.jsonl"
    assert main(["sample", TABLE_CUBE, "-o", str(out)]) == 2
    assert capsys.readouterr().err == f"prsc: error: cannot write {out}: Permission denied\n"
    assert list(tmp_path.iterdir()) == []
