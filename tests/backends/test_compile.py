"""`prsc compile`: layout, manifest, skipping, determinism across --jobs, and failure modes."""

from __future__ import annotations

import errno
import json
import os
from pathlib import Path

import pytest

from prsc import files as backend_files
from prsc.cli import main
from prsc.commands.compile import compile_scenes
from tests.backends import readback
from tests.backends.scenes import cube_in_air, every_model, obj, scene, table_cube, tray_with_cube

ALL = ["json", "mjcf", "urdf", "sdf", "usd"]


def _jsonl(tmp_path: Path, scenes: list[dict], name: str = "scenes.jsonl") -> Path:
    path = tmp_path / name
    path.write_text("".join(json.dumps(s) + "\n" for s in scenes))
    return path


def _scenes(k: int) -> list[dict]:
    """k small scenes (a tray with a cube, moved a little each time)."""
    out = []
    for i in range(k):
        s = tray_with_cube()
        for o in s["objects"]:
            o["position"][0] += 0.01 * i
        s["index"] = i
        out.append(s)
    return out


def _all_files(root: Path) -> dict[str, bytes]:
    return {str(p.relative_to(root)): p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()}


def _no_temporaries(root: Path) -> bool:
    return not [p for p in root.rglob(".*") if p.name.endswith((".tmp", ".old"))]


def test_layout_and_manifest(tmp_path):
    source = _jsonl(tmp_path, _scenes(3))
    root = compile_scenes(str(source), ALL, 3, 7, str(tmp_path / "out"))
    assert root == tmp_path / "out" / "scenes"
    manifest = json.loads((root / "manifest.json").read_text())
    assert manifest["seed"] == 7 and manifest["spec_path"] == str(source.absolute()) \
        and (root / manifest["spec"]).resolve() == source.resolve()
    import hashlib

    assert manifest["spec_sha256"] == hashlib.sha256(source.read_bytes()).hexdigest()
    assert not (root / ".prsc-lock").exists()  # the run's lock file goes with the run
    assert [s["index"] for s in manifest["scenes"]] == [0, 1, 2]
    assert manifest["scenes"][2]["files"] == {
        "json": "json/00002.json", "mjcf": "mjcf/00002.xml", "sdf": "sdf/00002.sdf",
        "urdf": "urdf/00002", "usd": "usd/00002.usda",
    }
    for entry in manifest["scenes"]:
        for rel in entry["files"].values():
            assert (root / rel).exists()
    assert (root / "urdf" / "00001" / "scene.json").is_file()


def test_cli_exit_code_and_quiet_output(tmp_path, capsys):
    source = _jsonl(tmp_path, _scenes(2))
    assert main(["compile", str(source), "--target", "mjcf,json", "-n", "2", "-o", str(tmp_path / "o")]) == 0
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err == ""  # no terminal: no progress bar


def test_rerun_skips_scenes_already_written(tmp_path, monkeypatch):
    source = _jsonl(tmp_path, _scenes(3))
    root = compile_scenes(str(source), ["mjcf", "json"], 2, 0, str(tmp_path / "out"))
    before = {p: p.stat().st_mtime_ns for p in root.rglob("*.xml")}
    import prsc.backends.mjcf

    calls = []
    original = prsc.backends.mjcf.render
    monkeypatch.setattr(prsc.backends.mjcf, "render", lambda *a: calls.append(a[0].index) or original(*a))
    compile_scenes(str(source), ["mjcf", "json"], 3, 0, str(tmp_path / "out"))
    # Only the new scene is rendered: once in a scratch folder before the output folder is
    # touched (its errors are found before any write), once in place.
    assert calls == [2, 2]
    assert all(p.stat().st_mtime_ns == t for p, t in before.items())
    manifest = json.loads((root / "manifest.json").read_text())
    assert [s["index"] for s in manifest["scenes"]] == [0, 1, 2]


def test_a_changed_spec_or_seed_rewrites_the_scenes_only_with_force(tmp_path, capsys):
    scenes = _scenes(2)
    source = _jsonl(tmp_path, scenes)
    root = compile_scenes(str(source), ["json"], 2, 0, str(tmp_path / "out"))
    scenes[0]["objects"][1]["color"] = [0, 1, 0, 1]
    source.write_text("".join(json.dumps(s) + "\n" for s in scenes))
    before = _all_files(root)
    assert main(["compile", str(source), "-n", "2", "-o", str(tmp_path / "out")]) == 2
    assert "holds 2 scenes of another spec, imported file, seed, law or proposal" in capsys.readouterr().err
    assert _all_files(root) == before
    compile_scenes(str(source), ["json"], 2, 0, str(tmp_path / "out"), force=True)
    assert json.loads((root / "json" / "00000.json").read_text())["objects"][1]["color"] == [0, 1, 0, 1]


def test_files_are_identical_whatever_the_number_of_jobs(tmp_path):
    scenes = _scenes(6) + [table_cube()]
    source = _jsonl(tmp_path, scenes)
    one = compile_scenes(str(source), ALL, 7, 0, str(tmp_path / "one"))
    two = compile_scenes(str(source), ALL, 7, 0, str(tmp_path / "two"), jobs=2)
    a, b = _all_files(one), _all_files(two)
    a.pop("manifest.json"), b.pop("manifest.json")
    assert a.keys() == b.keys() and all(a[k] == b[k] for k in a)


def test_unknown_model_warns_once_per_class(tmp_path, capsys):
    first, second = every_model(), every_model()
    second["objects"].append(obj("gadget_2", "Gadget", (3.0, 3.0, 0.05), (0.1, 0.1, 0.1), model="hexagonal_gear"))
    other = obj("widget", "Widget", (3.0, -3.0, 0.05), (0.1, 0.1, 0.1), model="no_such_model")
    second["objects"].append(other)
    source = _jsonl(tmp_path, [first, second])
    compile_scenes(str(source), ["mjcf", "usd"], 2, 0, str(tmp_path / "out"), jobs=2)
    err = capsys.readouterr().err
    assert err.count("class Gadget: unknown model 'hexagonal_gear'") == 1
    assert err.count("class Widget: unknown model 'no_such_model'") == 1


# ------------------------------------------------------------------ failures


def test_unknown_target_is_a_clear_error(tmp_path, capsys):
    source = _jsonl(tmp_path, _scenes(1))
    assert main(["compile", str(source), "--target", "mjcf,obj", "-o", str(tmp_path / "o")]) == 2
    assert "unknown target obj; choose from json, mjcf, urdf, sdf, usd" in capsys.readouterr().err


def test_unwritable_output_path(tmp_path, capsys):
    source = _jsonl(tmp_path, _scenes(1))
    blocker = tmp_path / "a_file"
    blocker.write_text("not a folder")
    assert main(["compile", str(source), "--target", "mjcf", "-o", str(blocker / "out")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("prsc: error: cannot create output folder") and "Not a directory" in err
    assert "Traceback" not in err


def test_read_only_output_folder_simulated(tmp_path, capsys, monkeypatch):
    """EACCES at the first write (CI runs as root, where folder permissions are not enforced)."""
    source = _jsonl(tmp_path, _scenes(2))

    def denied(handle, data):
        raise PermissionError(errno.EACCES, "Permission denied")

    monkeypatch.setattr(backend_files, "write_bytes", denied)
    assert main(["compile", str(source), "--target", "mjcf", "-n", "2", "-o", str(tmp_path / "out")]) == 2
    assert "prsc: error: cannot write" in capsys.readouterr().err
    assert not list((tmp_path / "out").rglob("*.xml"))
    assert _no_temporaries(tmp_path / "out")


def test_broken_output_folder(tmp_path, capsys):
    source = _jsonl(tmp_path, _scenes(1))
    out = tmp_path / "out"
    (out / "scenes").mkdir(parents=True)
    (out / "scenes" / "mjcf").write_text("a file where the mjcf folder should be")
    assert main(["compile", str(source), "--target", "mjcf", "-o", str(out)]) == 2
    assert "scenes/mjcf exists and is not a folder" in capsys.readouterr().err
    (out / "scenes" / "mjcf").unlink()
    (out / "scenes" / "manifest.json").write_text("{ truncated")
    assert main(["compile", str(source), "--target", "mjcf", "-o", str(out)]) == 2
    assert "manifest.json is unreadable" in capsys.readouterr().err


def test_disk_full_mid_run_leaves_no_partial_file(tmp_path, capsys, monkeypatch):
    source = _jsonl(tmp_path, _scenes(6))
    real = backend_files.write_bytes
    count = {"n": 0}

    def filling(handle, data):
        count["n"] += 1
        if count["n"] == 9:
            # Half the bytes reach the disk, then the device is full.
            real(handle, data[: len(data) // 2])
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        real(handle, data)

    monkeypatch.setattr(backend_files, "write_bytes", filling)
    out = tmp_path / "out"
    assert main(["compile", str(source), "--target", "json,mjcf,urdf", "-n", "6", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "no space left on device" in err and "Traceback" not in err
    root = out / "scenes"
    assert _no_temporaries(root)
    # Whatever was written is whole: every JSON parses, every MJCF loads, every bundle validates.
    for path in root.glob("json/*.json"):
        json.loads(path.read_text())
    for path in root.glob("mjcf/*.xml"):
        readback.mjcf_model(path)
    for folder in root.glob("urdf/*"):
        assert (folder / "scene.json").is_file()
        readback.urdf_validate(folder)
    # A re-run once there is space again completes the set.
    monkeypatch.setattr(backend_files, "write_bytes", real)
    assert main(["compile", str(source), "--target", "json,mjcf,urdf", "-n", "6", "-o", str(out)]) == 0
    manifest = json.loads((root / "manifest.json").read_text())
    assert len(manifest["scenes"]) == 6 and all(len(s["files"]) == 3 for s in manifest["scenes"])


def test_interrupted_run_leaves_no_partial_file(tmp_path, monkeypatch):
    source = _jsonl(tmp_path, _scenes(4))
    real = backend_files.write_bytes
    count = {"n": 0}

    def interrupted(handle, data):
        count["n"] += 1
        if count["n"] == 3:
            real(handle, data[:10])
            raise KeyboardInterrupt
        real(handle, data)

    monkeypatch.setattr(backend_files, "write_bytes", interrupted)
    with pytest.raises(KeyboardInterrupt):
        compile_scenes(str(source), ["mjcf", "urdf"], 4, 0, str(tmp_path / "out"))
    root = tmp_path / "out" / "scenes"
    assert _no_temporaries(root)
    for path in root.glob("mjcf/*.xml"):
        readback.mjcf_model(path)


def test_malformed_scene_json_is_a_clear_error(tmp_path, capsys):
    bad = cube_in_air()
    bad["objects"][0]["quaternion"] = [1, 1, 0, 0]
    source = _jsonl(tmp_path, [bad])
    assert main(["compile", str(source), "--target", "mjcf", "-o", str(tmp_path / "o")]) == 2
    assert "object 'cube'.quaternion: expected a unit quaternion" in capsys.readouterr().err
    (tmp_path / "broken.json").write_text('{"format": "prsc-scene",\n "version": 1,,}')
    assert main(["compile", str(tmp_path / "broken.json"), "-o", str(tmp_path / "o")]) == 2
    assert "broken.json:2:" in capsys.readouterr().err


def test_settle_check_catches_interpenetration(tmp_path):
    """The physics check used on every spec is not vacuous: a cube sunk 5 mm into the ground fails."""
    sunk = scene([obj("cube", "Cube", (0, 0, 0.015), (0.04, 0.04, 0.04), model="cube", mass=0.032)])
    root = compile_scenes(str(_jsonl(tmp_path, [sunk])), ["mjcf"], 1, 0, str(tmp_path / "out"))
    failures = readback.mjcf_settle_failures(readback.mjcf_model(root / "mjcf" / "00000.xml"))
    assert any("interpenetration" in f for f in failures)


def test_progress_bar_on_a_terminal(tmp_path, monkeypatch):
    """On a TTY the rich progress bar runs (and disappears); the files are the same."""
    import io

    class Terminal(io.StringIO):
        def isatty(self) -> bool:
            return True

    terminal = Terminal()
    monkeypatch.setattr("sys.stderr", terminal)
    source = _jsonl(tmp_path, _scenes(3))
    root = compile_scenes(str(source), ["json"], 3, 0, str(tmp_path / "out"))
    assert len(list((root / "json").glob("*.json"))) == 3
    assert "compiling" in terminal.getvalue()


def test_a_bad_spec_is_reported_with_its_location_and_writes_nothing(tmp_path, capsys):
    spec = tmp_path / "bad.prs"
    spec.write_text("from tabletop import *\ncube = Cube on\n")
    out = tmp_path / "out"
    assert main(["compile", str(spec), "--target", "mjcf", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert f"{spec}:2:" in err and "Traceback" not in err
    assert not out.exists()


def test_scene_files_are_checked_before_anything_is_written(tmp_path, capsys):
    """Binary, empty or malformed scene files: exit 2 at the scene's line (or position), no output."""
    out = tmp_path / "out"
    garbage = tmp_path / "garbage.json"
    garbage.write_bytes(b"\xc1\x00\xff binary")
    assert main(["compile", str(garbage), "-o", str(out)]) == 2
    assert f"{garbage}:1:1: error: the file is not valid UTF-8 text (byte 0xc1)" in capsys.readouterr().err
    for name, text in [("none.json", "[]"), ("none.jsonl", "\n\n")]:
        (tmp_path / name).write_text(text)
        assert main(["compile", str(tmp_path / name), "-o", str(out)]) == 2
        assert capsys.readouterr().err == f"prsc: error: {tmp_path / name}: no scenes in the file\n"
    good, bad = _scenes(2)
    del bad["objects"][1]["position"]
    lines = _jsonl(tmp_path, [good, good, bad])
    lines.write_text(lines.read_text().replace("\n", "\n\n", 1))  # a blank line: line numbers still count it
    assert main(["compile", str(lines), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"{lines}:4:1: error: object 'cube'.position: expected a list of 3 numbers, got None")
    listed = tmp_path / "listed.json"
    listed.write_text(json.dumps([good, bad]))
    assert main(["compile", str(listed), "-o", str(out)]) == 2
    assert capsys.readouterr().err == (
        f"prsc: error: {listed}: scene 1: object 'cube'.position: expected a list of 3 numbers, got None\n")
    broken = tmp_path / "broken.jsonl"
    broken.write_text(json.dumps(good) + "\n" + '{"format" "prsc-scene"}\n')
    assert main(["compile", str(broken), "-o", str(out)]) == 2
    assert capsys.readouterr().err.startswith(f"{broken}:2:11: error: invalid JSON: Expecting ':' delimiter")
    for field, value, message in [("params", "x", "params: expected an object, got 'x'"),
                                  ("index", -5, "index: expected a non-negative integer, got -5"),
                                  ("seed", "abc", "seed: expected a non-negative integer, got 'abc'")]:
        one = tmp_path / "one.json"
        one.write_text(json.dumps(dict(good, **{field: value})))
        assert main(["compile", str(one), "-o", str(out)]) == 2
        assert capsys.readouterr().err == f"prsc: error: {one}: {message}\n"
    assert not out.exists()


def test_a_changed_imported_file_rewrites_the_scenes(tmp_path):
    """The scenes depend on every file the spec imports, not only on the spec itself."""
    (tmp_path / "lib.prs").write_text("class Box:\n    width: 0.1\n")
    spec = tmp_path / "main.prs"
    spec.write_text("from lib import *\nb = Box at Vector3D(0, 0, 1)\n")
    root = compile_scenes(str(spec), ["json"], 1, 0, str(tmp_path / "out"))
    assert json.loads((root / "json" / "00000.json").read_text())["objects"][0]["dimensions"][0] == 0.1
    (tmp_path / "lib.prs").write_text("class Box:\n    width: 0.25\n")
    compile_scenes(str(spec), ["json"], 1, 0, str(tmp_path / "out"), force=True)
    assert json.loads((root / "json" / "00000.json").read_text())["objects"][0]["dimensions"][0] == 0.25


def test_a_first_run_that_fails_leaves_nothing_behind(tmp_path, capsys):
    """A spec infeasible only when sampled: no empty folders or manifest are left."""
    spec = tmp_path / "tiny_table.prs"
    spec.write_text("from tabletop import *\n"
                    "table = Table on Vector3D(0, 0, 0), with width (0.2, 0.3), with length (0.2, 0.3)\n"
                    "c = Cube completely on table, with width 1.0, with length 1.0\n")
    out = tmp_path / "new" / "out"
    assert main(["compile", str(spec), "--target", "json,mjcf", "-o", str(out)]) == 2
    assert f"{spec}:3:1: error: could not sample scene 0 (seed 0)" in capsys.readouterr().err
    assert not (tmp_path / "new").exists()


def test_bad_options(tmp_path, capsys):
    source = _jsonl(tmp_path, _scenes(1))
    assert main(["compile", str(source), "-o", ""]) == 2
    assert capsys.readouterr().err == "prsc: error: the output folder path is empty\n"
    assert main(["compile", str(source), "--seed", "-1", "-o", str(tmp_path / "o")]) == 2
    assert capsys.readouterr().err == "prsc: error: --seed must be >= 0, got -1\n"
    assert main(["compile", str(tmp_path), "-o", str(tmp_path / "o")]) == 2
    assert capsys.readouterr().err == f"prsc: error: {tmp_path} is a directory, not a spec file\n"
    assert not (tmp_path / "o").exists()


def test_an_error_in_a_worker_keeps_its_location(tmp_path, capsys):
    """--jobs 2: a scene that cannot be sampled is reported with its notes, as with one job."""
    spec = tmp_path / "flaky.prs"
    # Candidate rounds find x > 0.999 in 32 % of scenes; the Gibbs sampler fails most of the others.
    spec.write_text("x = (0, 1)\nt = Object at Vector3D(0, 0, 1)\nrequire x > 0.999\n")
    assert main(["compile", str(spec), "-n", "40", "--jobs", "2", "-o", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "could not sample scene" in err and f"{spec}:3:1: note: this require: require x > 0.999" in err


def test_a_body_too_light_for_mujoco_is_a_clear_error(tmp_path, capsys):
    """MuJoCo refuses a moving body under 1e-15 kg (m^2): say which object, not an internal error."""
    dust = scene([obj("dust", "Object", (0, 0, 1), (1e-6, 1e-6, 1e-6))])
    assert main(["compile", str(_jsonl(tmp_path, [dust])), "--target", "mjcf", "-o", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("prsc: error: scene 0: object 'dust' cannot move in MuJoCo: its mass (5e-16 kg) and principal "
                          "inertia (smallest 8.33e-29 kg m^2) must exceed 1e-15")
    pinned = scene([obj("dust", "Object", (0, 0, 1), (1e-6, 1e-6, 1e-6), static=True)])
    assert main(["compile", str(_jsonl(tmp_path, [pinned])), "--target", "mjcf", "-o", str(tmp_path / "o")]) == 0
