"""The compile output folder under attack: two writers, kill -9, SIGTERM, Ctrl-C, a forged
manifest, a changed seed, a spec named `...prs`, absurd --jobs and -n (issue 12, items 1-4, 7, 8)."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from prsc.cli import main
from prsc.commands import compile as compile_command
from prsc.commands.compile import JOURNAL, compile_scenes
from tests.backends import readback
from tests.backends.scenes import tray_with_cube

REPO = Path(__file__).resolve().parents[2]
SPEC = REPO / "specs" / "table_cube.prs"


def _terminal_signals() -> None:
    """SIGINT as a terminal's foreground process has it: a suite started as a background job
    (`make test &`) ignores SIGINT, and a child inherits SIG_IGN, so Ctrl-C would not reach it."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _prsc(*args: str, **kwargs) -> subprocess.Popen:
    env = dict(os.environ, PYTHONPATH=str(REPO))
    return subprocess.Popen([sys.executable, "-m", "prsc.cli", *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, cwd=REPO, env=env,
                            preexec_fn=_terminal_signals, **kwargs)


def _outputs(root: Path) -> set[str]:
    """Finished scene outputs on disk (files, and bundle folders), relative to the root."""
    found = set()
    for target in ("json", "mjcf", "urdf", "sdf", "usd"):
        folder = root / target
        if folder.is_dir():
            found |= {f"{target}/{p.name}" for p in folder.iterdir() if not p.name.startswith(".")}
    return found


def _listed(root: Path) -> set[str]:
    """Every file manifest.json and the journal record."""
    manifest = json.loads((root / "manifest.json").read_text())
    rels = {rel for scene in manifest["scenes"] for rel in scene["files"].values()}
    journal = root / JOURNAL
    if journal.exists():
        for line in journal.read_text().splitlines():
            rels |= set(json.loads(line)["files"].values())
    return rels


def _check_whole(root: Path, rels: set[str]) -> None:
    """Every listed output is complete and parses: JSON, MJCF (MuJoCo loads the first few), and
    every file of a URDF bundle, which holds the same files as every other (yourdfpy validates a few)."""
    bundles = set()
    for k, rel in enumerate(sorted(rels)):
        path = root / rel
        if rel.endswith(".task.json"):  # a scene's task file, beside its MJCF file
            assert json.loads(path.read_text())["format"] == "prsc-task"
        elif rel.startswith("json/"):
            assert json.loads(path.read_text())["format"] == "prsc-scene"
        elif rel.startswith("mjcf/"):
            ET.parse(path)
            if k < 5:
                readback.mjcf_model(path)
        elif rel.startswith("urdf/"):
            names = sorted(p.name for p in path.iterdir())
            bundles.add(tuple(names))
            assert json.loads((path / "scene.json").read_text())["objects"]
            for name in names:
                if name.endswith(".urdf"):
                    ET.parse(path / name)
            if len(bundles) == 1 and k % 50 == 0:
                readback.urdf_validate(path)
    assert len(bundles) <= 1, f"URDF bundles hold different files: {bundles}"


def _wait_for(predicate, seconds: float = 60.0) -> None:
    end = time.monotonic() + seconds
    while not predicate():
        assert time.monotonic() < end, "timed out waiting"
        time.sleep(0.05)


def _children(pid: int) -> set[int]:
    found = set()
    for task in Path(f"/proc/{pid}/task").iterdir():
        text = (task / "children").read_text().split()
        found |= {int(t) for t in text}
    return found


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().split(")")[-1].split()[0]
    except OSError:
        return False
    return state != "Z"


def test_two_compiles_into_one_folder_never_corrupt_it(tmp_path):
    """Item 1: a second writer is refused while the first runs; every listed file is whole."""
    out = tmp_path / "D"
    command = [str(SPEC), "--target", "json,urdf", "-n", "3000", "--jobs", "2", "-o", str(out)]
    first = _prsc("compile", *command)
    root = out / "table_cube"
    _wait_for(lambda: len(_outputs(root)) >= 3)
    second = _prsc("compile", *command)
    second_err = second.communicate(timeout=120)[1]
    assert first.poll() is None, "the first run ended before the second started"
    assert second.returncode == 2, second_err
    assert second_err == (f"prsc: error: output folder {root} is being written by another prsc run; "
                          "wait for it to finish or choose another output folder\n")
    first.send_signal(signal.SIGTERM)
    assert first.communicate(timeout=60)[1] == "prsc: terminated\n"
    rels = _listed(root)
    assert rels and rels <= _outputs(root)
    _check_whole(root, rels)


def test_kill_9_leaves_every_finished_file_recorded_and_no_writer_behind(tmp_path):
    """Item 2: after kill -9 of the parent, its workers die at once and the manifest
    (manifest.json and its journal) lists the finished files; a re-run completes the set."""
    out = tmp_path / "D"
    command = [str(SPEC), "--target", "json,mjcf", "-n", "3000", "--jobs", "2", "-o", str(out)]
    run = _prsc("compile", *command)
    root = out / "table_cube"
    _wait_for(lambda: len(_outputs(root)) >= 40)
    workers = _children(run.pid)
    assert len(workers) == 2
    run.send_signal(signal.SIGKILL)
    run.communicate(timeout=30)
    _wait_for(lambda: not any(_alive(w) for w in workers), seconds=2.0)
    on_disk = _outputs(root)
    time.sleep(0.3)
    assert _outputs(root) == on_disk, "files kept appearing after the kill"
    listed = _listed(root)
    assert listed <= on_disk
    # Files renamed in the microseconds before their journal line are the only gap: one per worker
    # at most, with its task file (table_cube states a task: mjcf/<k>.task.json is written first).
    assert len(on_disk - listed) <= 4, sorted(on_disk - listed)
    assert {rel.replace(".task.json", ".xml") for rel in listed if rel.endswith(".task.json")} \
        == {rel for rel in listed if rel.endswith(".xml")}  # each MJCF file is listed with its task file
    _check_whole(root, listed)
    rerun = subprocess.run([sys.executable, "-m", "prsc.cli", "compile", *command[:4], "60", *command[5:]],
                           capture_output=True, text=True, cwd=REPO, env=dict(os.environ, PYTHONPATH=str(REPO)))
    assert rerun.returncode == 0, rerun.stderr
    assert not (root / JOURNAL).exists()
    manifest = json.loads((root / "manifest.json").read_text())
    assert {s["index"] for s in manifest["scenes"]} >= set(range(60))


def test_sigterm_records_the_finished_scenes_and_ctrl_c_prints_one_line(tmp_path):
    """Items 2 and 8: SIGTERM writes the manifest and removes temporaries; Ctrl-C (SIGINT to
    the whole process group, as a terminal sends it) with --jobs 2 prints one line, no traceback."""
    out = tmp_path / "D"
    command = [str(SPEC), "--target", "json,mjcf", "-n", "3000", "--jobs", "2", "-o", str(out)]
    root = out / "table_cube"
    run = _prsc("compile", *command)
    _wait_for(lambda: len(_outputs(root)) >= 20)
    run.send_signal(signal.SIGTERM)
    err = run.communicate(timeout=30)[1]
    assert run.returncode == 143 and err == "prsc: terminated\n"
    listed = {rel for s in json.loads((root / "manifest.json").read_text())["scenes"] for rel in s["files"].values()}
    assert len(_outputs(root) - listed) <= 2
    assert not [p for p in root.rglob(".*") if p.name.endswith((".tmp", ".old"))]

    run = _prsc("compile", *command[:-1], str(tmp_path / "E"), start_new_session=True)
    _wait_for(lambda: len(_outputs(tmp_path / "E" / "table_cube")) >= 20)
    os.killpg(run.pid, signal.SIGINT)
    err = run.communicate(timeout=30)[1]
    assert run.returncode == 130 and err == "prsc: interrupted\n"


def _jsonl(tmp_path: Path, count: int) -> Path:
    path = tmp_path / "scenes.jsonl"
    lines = []
    for i in range(count):
        scene = tray_with_cube()
        scene["index"] = i
        lines.append(json.dumps(scene))
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.mark.parametrize("forged", [
    {"scenes": [{"index": 0, "files": {"json": "."}}]},
    {"scenes": [{"index": 0, "files": {"json": "../outside.json"}}]},
    {"scenes": [{"index": 0, "files": {"json": "json/00001.json"}}]},
    {"scenes": [1]},
])
def test_a_forged_manifest_never_makes_prsc_delete_a_file(tmp_path, capsys, forged):
    """Item 3: a manifest entry that is not a name prsc gives is refused, whatever the seed."""
    source = _jsonl(tmp_path, 2)
    root = tmp_path / "out" / "scenes"
    root.mkdir(parents=True)
    (root / "mine.txt").write_text("the user's")
    (tmp_path / "out" / "outside.json").write_text("the user's too")
    (root / "manifest.json").write_text(json.dumps(dict(forged, seed=99, spec_sha256="x")))
    for seed in ("0", "99"):
        for force in ([], ["--force"]):
            assert main(["compile", str(source), "--seed", seed, "-o", str(tmp_path / "out"), *force]) == 2
            err = capsys.readouterr().err
            assert "is not a prsc manifest" in err and "Traceback" not in err
    assert (root / "mine.txt").read_text() == "the user's"
    assert (tmp_path / "out" / "outside.json").read_text() == "the user's too"


def test_a_changed_seed_needs_force_and_then_deletes_only_listed_files(tmp_path, capsys):
    """Item 3: a different --seed is refused; with --force only the files the manifest lists go."""
    source = _jsonl(tmp_path, 3)
    out = tmp_path / "out"
    root = compile_scenes(str(source), ["json", "mjcf"], 3, 0, str(out))
    (root / "json" / "notes.txt").write_text("the user's")
    (root / "json" / "00007.json").write_text("{}")  # at a prsc name, but not listed
    assert main(["compile", str(source), "--target", "json", "--seed", "1", "-o", str(out)]) == 2
    assert "pass --force to replace them" in capsys.readouterr().err
    assert len(list((root / "mjcf").glob("*.xml"))) == 3
    assert main(["compile", str(source), "--target", "json", "--seed", "1", "-o", str(out), "--force"]) == 0
    assert not list((root / "mjcf").glob("*.xml"))  # listed outputs of the old seed are gone
    assert (root / "json" / "notes.txt").read_text() == "the user's"
    assert (root / "json" / "00007.json").read_text() == "{}"
    assert json.loads((root / "manifest.json").read_text())["seed"] == 1


def test_a_file_prsc_did_not_write_is_never_replaced(tmp_path, capsys):
    """Item 3: in a folder without a manifest, a user's file at a scene's name stops the run."""
    source = _jsonl(tmp_path, 2)
    root = tmp_path / "out" / "scenes"
    (root / "json").mkdir(parents=True)
    (root / "json" / "00001.json").write_text("the user's")
    assert main(["compile", str(source), "-n", "2", "-o", str(tmp_path / "out")]) == 2
    assert "exists and is not listed" in capsys.readouterr().err
    assert (root / "json" / "00001.json").read_text() == "the user's"


def test_removing_earlier_scenes_in_a_read_only_folder_is_a_clear_error(tmp_path, capsys, monkeypatch):
    """Item 5: a stale manifest over a folder prsc cannot delete from (root ignores chmod: simulated)."""
    source = _jsonl(tmp_path, 2)
    root = compile_scenes(str(source), ["json"], 2, 0, str(tmp_path / "out"))

    def read_only(self, *args, **kwargs):
        raise OSError(30, "Read-only file system", str(self))  # EROFS

    monkeypatch.setattr(Path, "unlink", read_only)
    assert main(["compile", str(source), "--seed", "5", "--force", "-o", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"prsc: error: cannot remove the earlier scenes in {root}: ") and "Read-only" in err


def test_a_spec_named_dots_cannot_write_outside_the_output_folder(tmp_path, capsys):
    """Item 4: `...prs` has the stem `..`: refused, nothing written beside -o."""
    spec = tmp_path / "...prs"
    spec.write_text("a = Object at Vector3D(0, 0, 1)\n")
    out = tmp_path / "deep" / "out"
    assert main(["compile", str(spec), "-o", str(out)]) == 2
    assert "cannot name an output folder after" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["...prs"]


def test_jobs_are_capped_at_the_cores(tmp_path, capsys, monkeypatch):
    """Item 7: --jobs 1000 starts no more workers than cores, with a note."""
    started = []
    monkeypatch.setattr(compile_command, "_run_parallel",
                        lambda job, indices, executor, done, listed: started.append(executor.jobs) or
                        compile_command._run_serial(job, indices, done, listed))
    assert main(["compile", str(_jsonl(tmp_path, 3)), "--jobs", "1000", "-o", str(tmp_path / "o")]) == 0
    cores = len(os.sched_getaffinity(0))
    assert started == [cores] or (cores == 1 and started == [])
    assert capsys.readouterr().err == f"prsc: note: --jobs 1000 is more than the {cores} cores available; using {cores}\n"


def test_a_huge_n_streams(tmp_path, monkeypatch):
    """Item 7: -n 10**12 writes its first scenes at once (no list of 10**12 indices, no
    existence check per index before the first scene)."""
    spec = tmp_path / "one.prs"
    spec.write_text("a = Object at Vector3D((0, 1), 0, 1)\n")
    import prsc.backends.json as json_backend

    real, calls = json_backend.render, []

    def render(scene, path, store):
        calls.append(scene.index)
        if len(calls) == 4:
            raise KeyboardInterrupt
        return real(scene, path, store)

    monkeypatch.setattr(json_backend, "render", render)
    checks = []
    real_exists = Path.exists
    monkeypatch.setattr(Path, "exists", lambda self: checks.append(1) or real_exists(self))
    with pytest.raises(KeyboardInterrupt):
        compile_scenes(str(spec), ["json"], 10**12, 0, str(tmp_path / "o"))
    assert calls == [0, 0, 1, 2] and len(checks) < 100  # scene 0 first in the scratch preflight
    root = tmp_path / "o" / "one"
    assert sorted(p.name for p in (root / "json").iterdir()) == ["000000000000.json", "000000000001.json"]


def test_a_killed_sample_leaves_a_temporary_the_next_run_removes(tmp_path):
    """Item 8: `sample -o` under SIGTERM removes its temporary; after kill -9 the next run does."""
    target = tmp_path / "scenes.jsonl"

    def temporaries() -> list[Path]:
        return [p for p in tmp_path.iterdir() if p.name.startswith(".scenes.jsonl.")]

    run = _prsc("sample", str(SPEC), "-n", "1000000", "-o", str(target))
    _wait_for(lambda: temporaries() and temporaries()[0].stat().st_size > 0)
    run.send_signal(signal.SIGTERM)
    assert run.communicate(timeout=30)[1] == "prsc: terminated\n" and run.returncode == 143
    assert not temporaries() and not target.exists()

    run = _prsc("sample", str(SPEC), "-n", "1000000", "-o", str(target))
    _wait_for(lambda: temporaries() and temporaries()[0].stat().st_size > 0)
    run.send_signal(signal.SIGKILL)
    run.communicate(timeout=30)
    (left,) = temporaries()
    os.utime(left, (time.time() - 10, time.time() - 10))
    other = tmp_path / ".other.prsc-abcdefgh.tmp"  # a temporary of another output: not this run's
    other.write_text("x")
    os.utime(other, (time.time() - 10, time.time() - 10))
    assert main(["sample", str(SPEC), "-n", "2", "-o", str(target)]) == 0
    assert not temporaries() and other.exists() and len(target.read_text().splitlines()) == 2


def test_a_bundle_whose_temporary_changes_while_written_is_never_renamed_into_place(tmp_path, monkeypatch):
    """Item 1: another process deleting files of a half-written bundle (what a second run's
    cleanup once did) makes the write fail; no partial bundle appears under the final name."""
    from prsc import files

    real, calls = files.write_bytes, []

    def meddling(handle, data):
        calls.append(1)
        if len(calls) == 3:
            for path in (tmp_path / "urdf").glob(".00000.prsc-*.tmp/a.urdf"):
                path.unlink()  # the intruder
        real(handle, data)

    (tmp_path / "urdf").mkdir()
    monkeypatch.setattr(files, "write_bytes", meddling)
    with pytest.raises(OSError, match="changed while it was written"):
        files.atomic_write_tree(tmp_path / "urdf" / "00000", {"a.urdf": "<robot/>", "b.urdf": "<robot/>",
                                                               "scene.json": "{}"})
    assert list((tmp_path / "urdf").iterdir()) == []


def test_force_never_follows_a_target_folder_replaced_by_a_link(tmp_path, capsys):
    """Item 3: `json/` swapped for a link to the user's folder: --force deletes nothing there."""
    source = _jsonl(tmp_path, 1)
    root = compile_scenes(str(source), ["json"], 1, 0, str(tmp_path / "out"))
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    (elsewhere / "00000.json").write_text("the user's")
    for path in (root / "json").iterdir():
        path.unlink()
    (root / "json").rmdir()
    (root / "json").symlink_to(elsewhere)
    assert main(["compile", str(source), "--seed", "3", "--force", "-o", str(tmp_path / "out")]) == 2
    assert "is a symbolic link" in capsys.readouterr().err
    assert (elsewhere / "00000.json").read_text() == "the user's"
