"""Any controller behind `prsc run --controller`: outcomes, errors, timeouts, faults, resuming, MUJOCO_GL unset."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from prsc.cli import main

REPO = Path(__file__).resolve().parents[2]
CUBES = REPO / "tests" / "data" / "three_cubes.prs"
INCLUDE = ["-I", str(REPO / "specs")]

def records(path: Path) -> list[dict]:
    """results.jsonl without the wall-clock field."""
    return [{k: v for k, v in json.loads(line).items() if k != "wall_seconds"}
            for line in path.read_text().splitlines()]


def test_a_user_controller_from_a_file(stay_put, tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["run", str(CUBES), *INCLUDE, "-n", "4", "-o", str(out), "--controller", stay_put]) == 0
    lines = records(out / "results.jsonl")
    assert [r["index"] for r in lines] == [0, 1, 2, 3]
    assert {r["outcome"] for r in lines} == {"still"}, lines
    assert all(len(r["drift_mm"]) == 3 and max(r["drift_mm"]) < 5 for r in lines)
    assert all(r["sim_seconds"] == 1.0 for r in lines)
    table = capsys.readouterr().out
    assert "still" in table and "moved" in table  # a declared outcome is listed with count 0
    assert (out / "outcomes.png").stat().st_size > 0
    assert not (out / "cube_map.png").exists()  # the handover's own plot, not the runner's


def test_errors_and_runaways_are_outcomes_and_the_campaign_goes_on(tmp_path):
    controller = tmp_path / "flaky.py"
    controller.write_text(textwrap.dedent('''
        import mujoco

        def flaky(scene, model, data):
            if scene["index"] == 1:
                raise RuntimeError("gripper driver crashed")
            if scene["index"] == 2:
                while True:  # a runaway: only the simulated-time limit ends it
                    try:
                        mujoco.mj_step(model, data)
                    except Exception:
                        pass
            if scene["index"] == 3:
                return {"outcome": "ok"}
            mujoco.mj_step(model, data, nstep=10)
            return {"outcome": "ok", "reason": "", "extra": object()} if scene["index"] == 4 else {"outcome": "ok", "reason": ""}
    '''))
    out = tmp_path / "run"
    assert main(["run", str(CUBES), *INCLUDE, "-n", "5", "-o", str(out), "--controller", f"{controller}:flaky",
                 "--max-sim-seconds", "0.5"]) == 0
    by_index = {r["index"]: r for r in records(out / "results.jsonl")}
    assert by_index[0]["outcome"] == "ok" and by_index[0]["reason"] == ""
    assert by_index[1] == {**by_index[1], "outcome": "error", "reason": "RuntimeError: gripper driver crashed"}
    assert by_index[2]["outcome"] == "timeout" and 0.5 <= by_index[2]["sim_seconds"] < 0.51
    assert by_index[3]["outcome"] == "error" and "'reason'" in by_index[3]["reason"]
    assert by_index[4]["outcome"] == "error" and "JSON" in by_index[4]["reason"]


@pytest.mark.parametrize("target, message", [
    ("nowhere", "expected package.module:name or path/to/file.py:name"),
    ("no_such_module_xyz:run", "cannot import no_such_module_xyz"),
    ("prsc.runner.handover:nothing", "has no 'nothing'"),
    ("missing.py:run", "cannot read missing.py"),
])
def test_a_controller_that_cannot_be_loaded_is_a_clear_error(target, message, tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["run", str(CUBES), *INCLUDE, "-n", "1", "-o", str(out), "--controller", target]) == 2
    assert message in capsys.readouterr().err
    assert not out.exists()


def test_a_file_mujoco_cannot_load_stops_the_campaign(stay_put, tmp_path, capsys):
    out = tmp_path / "run"
    args = ["run", str(CUBES), *INCLUDE, "-n", "2", "-o", str(out), "--controller", stay_put]
    assert main(args) == 0
    (out / "three_cubes" / "mjcf" / "00001.xml").write_text("<mujoco><worldbody><geom type='nonsense'/></worldbody></mujoco>")
    (out / "results.jsonl").unlink()
    assert main(args) == 2
    err = capsys.readouterr().err
    assert "MuJoCo cannot load" in err and "00001.xml" in err and "Traceback" not in err
    assert [r["outcome"] for r in records(out / "results.jsonl")] == ["still"]  # no episode recorded as an outcome


def _prsc(*args: str) -> list[str]:
    return [sys.executable, "-c", "import sys; from prsc.cli import main; sys.exit(main())", *args]


def test_a_killed_campaign_resumes_to_the_file_a_clean_run_writes(stay_put, tmp_path):
    slow = tmp_path / "slow.py"
    slow.write_text(Path(stay_put.rpartition(":")[0]).read_text() + "\n\nimport time\n\ndef slow(scene, model, data):\n"
                                "    time.sleep(0.3)\n    return stay_put(scene, model, data)\n")
    env = dict(os.environ, MUJOCO_GL=os.environ.get("MUJOCO_GL", "egl"))
    common = [str(CUBES), *INCLUDE, "-n", "8", "--controller", f"{slow}:slow"]
    killed = tmp_path / "killed"
    process = subprocess.Popen(_prsc("run", *common, "-o", str(killed)), env=env,
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    results = killed / "results.jsonl"
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and process.poll() is None:
        if results.is_file() and len(results.read_text().splitlines()) >= 3:
            break
        time.sleep(0.02)
    process.send_signal(signal.SIGKILL)
    process.wait()
    before = [json.loads(line) for line in results.read_text().splitlines()]
    assert 3 <= len(before) < 8, "the kill came too late to test resuming"

    assert subprocess.run(_prsc("run", *common, "-o", str(killed)), env=env, capture_output=True).returncode == 0
    clean = tmp_path / "clean"
    assert main(["run", *common, "-o", str(clean)]) == 0
    assert records(results) == records(clean / "results.jsonl")
    after = {r["index"]: r for r in map(json.loads, results.read_text().splitlines())}
    assert all(after[r["index"]] == r for r in before)  # recorded episodes were not run again


def test_prsc_run_with_mujoco_gl_unset(tmp_path):
    """`prsc run FILE -n 3` as typed into a fresh shell: no MUJOCO_GL, no PYOPENGL_PLATFORM."""
    env = {k: v for k, v in os.environ.items() if k not in ("MUJOCO_GL", "PYOPENGL_PLATFORM")}
    out = tmp_path / "run"
    done = subprocess.run(_prsc("run", str(REPO / "specs" / "table_cube.prs"), "-n", "3", "-o", str(out)),
                          env=env, capture_output=True, text=True, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    lines = [json.loads(line) for line in (out / "results.jsonl").read_text().splitlines()]
    assert [r["index"] for r in lines] == [0, 1, 2]
    # Every episode got as far as the camera: no GL failure recorded as an outcome.
    assert all(r["outcome"] in ("success", "perception_fault", "no_path", "poor_grip") for r in lines), lines
    assert any(r["sim_seconds"] > 1 for r in lines)


def test_the_example_pick_place_controller(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["run", str(REPO / "specs" / "pick_place.prs"), "-n", "3", "-o", str(out),
                 "--controller", "prsc.runner.pick_place:pick_place"]) == 0
    lines = records(out / "results.jsonl")
    assert [r["outcome"] for r in lines] == ["placed"] * 3, lines
    assert all(r["distance_to_target"] < 0.03 for r in lines)
    table = capsys.readouterr().out
    assert all(label in table for label in ("placed", "unreachable", "dropped", "missed"))
    # A scene the controller cannot drive is refused before anything is compiled.
    assert main(["run", str(CUBES), *INCLUDE, "-o", str(tmp_path / "cubes"),
                 "--controller", "prsc.runner.pick_place:pick_place"]) == 2
    assert "needs one Robot, two Trays and one Cube (found 0 Robot, 0 Tray, 3 Cube)" in capsys.readouterr().err
    assert not (tmp_path / "cubes").exists()


def test_no_gl_context_stops_the_campaign(tmp_path):
    """A GL backend that cannot render here (GLFW without a display) is an error, not an outcome."""
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY", "PYOPENGL_PLATFORM")}
    env["MUJOCO_GL"] = "glfw"
    out = tmp_path / "run"
    done = subprocess.run(_prsc("run", str(REPO / "specs" / "table_cube.prs"), "-n", "2", "-o", str(out)),
                          env=env, capture_output=True, text=True)
    assert done.returncode == 2, done.stderr
    assert "prsc: error: no offscreen OpenGL rendering with MUJOCO_GL='glfw'" in done.stderr
    assert "Traceback" not in done.stderr
    assert not out.exists()  # failed before its first episode: nothing left, not even an empty results.jsonl


def test_a_controller_finds_objects_whose_names_the_formats_cannot_hold(tmp_path):
    """Objects named `world` and `1 cube` become MJCF bodies `world_` and `_1_cube`; `body` says so."""
    spec = tmp_path / "odd_names.prs"
    spec.write_text(textwrap.dedent('''
        from tabletop import *

        table = Table on Vector3D(0, 0, 0), with width 1.2, with length 0.8, with height 0.8
        world = Cube completely on table, with color "red"
    '''))
    controller = tmp_path / "lookup.py"
    controller.write_text(textwrap.dedent('''
        import mujoco

        def lookup(scene, model, data):
            bodies = {o["name"]: o["body"] for o in scene["objects"]}
            for body in bodies.values():
                model.body(body)  # raises when the body is not in the model
            mujoco.mj_step(model, data)
            return {"outcome": "found", "reason": "", "bodies": bodies}
    '''))
    out = tmp_path / "run"
    assert main(["run", str(spec), *INCLUDE, "-n", "2", "-o", str(out), "--controller", f"{controller}:lookup"]) == 0
    lines = records(out / "results.jsonl")
    assert [r["outcome"] for r in lines] == ["found", "found"], lines
    assert lines[0]["bodies"] == {"table": "table", "world": "world_"}


def test_run_compiles_the_spec_once_and_checks_each_scene_once(tmp_path, monkeypatch):
    """Issue 23: `run` compiled the spec twice (once for `check`, once to write) and checked
    scene 0 twice; the scenes checked are now those written, from one compile."""
    import prsc.ir

    compiles = []
    real = prsc.ir.compile_program
    monkeypatch.setattr(prsc.ir, "compile_program", lambda *a, **k: compiles.append(a[0]) or real(*a, **k))
    checked = tmp_path / "checked.txt"
    controller = tmp_path / "counting.py"
    controller.write_text(textwrap.dedent(f'''
        def counting(scene, model, data):
            return {{"outcome": "success", "reason": "counted"}}

        def check(scene):
            with open({str(checked)!r}, "a") as f:
                f.write(str(scene["index"]) + "\\n")

        counting.check = check
    '''))
    out = tmp_path / "run"
    assert main(["run", str(CUBES), "-n", "3", "-o", str(out), "--controller", f"{controller}:counting"]) == 0
    assert compiles == [str(CUBES)]
    assert sorted(checked.read_text().split()) == ["0", "1", "2"]
