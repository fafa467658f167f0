"""The compiled task travels with the outputs: the scene JSON's "task" key, a bundle's task.json,
and `<k>.task.json` beside scene k's MJCF, SDF and USD files, each listed in the manifest with
its scene's file (written first, journalled in the same line, replaced by --force only when listed)."""

from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
from pathlib import Path

from prsc.cli import main
from prsc.task.terms import Task, task_file

SPEC = Path(__file__).with_name("tray_task.prs")
REPO = Path(__file__).resolve().parents[2]
FILE_TARGETS = ("mjcf", "sdf", "usd")


def _listed(root: Path) -> dict[str, str]:
    """key -> path of every file manifest.json and its journal record (a cut journal line is skipped)."""
    listed = {}
    for scene in json.loads((root / "manifest.json").read_text())["scenes"]:
        listed.update({f"{scene['index']}:{k}": v for k, v in scene["files"].items()})
    journal = root / "manifest.jsonl"
    if journal.exists():
        for line in journal.read_text().split("\n")[:-1]:
            try:
                entry = json.loads(line)
            except ValueError:
                continue
            listed.update({f"{entry['index']}:{k}": v for k, v in entry["files"].items()})
    return listed


def test_every_format_s_folder_carries_each_scene_s_task(tmp_path):
    assert main(["compile", str(SPEC), "--target", "json,mjcf,urdf,sdf,usd", "-n", "2", "-o", str(tmp_path)]) == 0
    root = tmp_path / "tray_task"
    manifest = json.loads((root / "manifest.json").read_text())
    for k in (0, 1):
        scene = json.loads((root / "json" / f"0000{k}.json").read_text())
        files = manifest["scenes"][k]["files"]
        assert files == {"json": f"json/0000{k}.json", "urdf": f"urdf/0000{k}",
                         **{t: f"{t}/0000{k}{s}" for t, s in (("mjcf", ".xml"), ("sdf", ".sdf"), ("usd", ".usda"))},
                         **{f"{t}.task": f"{t}/0000{k}.task.json" for t in FILE_TARGETS}}
        for target in ("urdf",) + FILE_TARGETS:
            path = task_file(root / files[target])
            assert path == (root / files[f"{target}.task"] if target != "urdf" else root / files["urdf"] / "task.json")
            assert json.loads(path.read_text()) == scene["task"], path
    # No task file in json/ (the scene JSON holds it): `json/*.json` stays the scenes.
    assert sorted(p.name for p in (root / "json").iterdir()) == ["00000.json", "00001.json"]
    task = json.loads((root / "urdf" / "00000" / "task.json").read_text())
    compiled = Task.from_json(task)
    assert Task.from_json(compiled.to_json()) == compiled  # plain data, both ways
    assert [o.name for o in compiled.objects] == ["table", "tray", "cube"] and compiled.object("tray").container


def test_a_spec_without_a_task_writes_no_task_file(tmp_path):
    spec = tmp_path / "plain.prs"
    spec.write_text("a = Object at Vector3D(0, 0, 1)\n")
    assert main(["compile", str(spec), "--target", "mjcf,urdf", "-n", "1", "-o", str(tmp_path / "out")]) == 0
    root = tmp_path / "out" / "plain"
    assert sorted(p.name for p in (root / "mjcf").iterdir()) == ["00000.xml"]
    assert not (root / "urdf" / "00000" / "task.json").exists()


def test_force_replaces_the_listed_task_files_and_nothing_else(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["compile", str(SPEC), "--target", "json,mjcf", "-n", "2", "-o", str(out)]) == 0
    root = out / "tray_task"
    (root / "mjcf" / "notes.task.json").write_text("the user's")
    (root / "mjcf" / "00007.task.json").write_text("{}")  # at a prsc name, but not listed
    assert main(["compile", str(SPEC), "--target", "json,mjcf", "-n", "1", "--seed", "1", "-o", str(out)]) == 2
    assert "pass --force" in capsys.readouterr().err
    assert (root / "mjcf" / "00001.task.json").exists()
    assert main(["compile", str(SPEC), "--target", "json,mjcf", "-n", "1", "--seed", "1", "-o", str(out), "--force"]) == 0
    assert not (root / "mjcf" / "00001.task.json").exists()  # listed, of the old seed: gone
    scene = json.loads((root / "json" / "00000.json").read_text())
    assert scene["seed"] == 1 and json.loads((root / "mjcf" / "00000.task.json").read_text()) == scene["task"]
    assert (root / "mjcf" / "notes.task.json").read_text() == "the user's"
    assert (root / "mjcf" / "00007.task.json").read_text() == "{}"


def test_a_task_file_prsc_did_not_write_is_never_replaced(tmp_path, capsys):
    root = tmp_path / "out" / "tray_task"
    (root / "sdf").mkdir(parents=True)
    (root / "sdf" / "00000.task.json").write_text("the user's")
    assert main(["compile", str(SPEC), "--target", "sdf", "-n", "1", "-o", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert f"{root / 'sdf' / '00000.task.json'} exists and is not listed" in err
    assert (root / "sdf" / "00000.task.json").read_text() == "the user's"
    assert sorted(p.name for p in (root / "sdf").iterdir()) == ["00000.task.json"]


def _file_size_limit(size: int):
    def limit() -> None:
        resource.setrlimit(resource.RLIMIT_FSIZE, (size, size))
    return limit


def test_a_full_disk_mid_run_leaves_each_scene_file_with_its_task_file_listed(tmp_path):
    """The journal outgrows a file-size limit (EFBIG, as a full disk's ENOSPC) mid-run: exit 2, and
    on disk exactly the listed files, each MJCF file with its task file, no temporary."""
    spec = tmp_path / "two.prs"
    spec.write_text('a = Object at Vector3D((0, 1), 1, 1)\nb = Object at Vector3D(0, (3, 4), 1)\n'
                    'fail "fell" when a.z < 0.5\nterminate after 2 seconds\n')
    run = subprocess.run([sys.executable, "-m", "prsc.cli", "compile", str(spec), "--target", "mjcf", "-n", "400",
                          "-o", str(tmp_path / "out")], capture_output=True, text=True, cwd=tmp_path,
                         env=dict(os.environ, PYTHONPATH=str(REPO)), preexec_fn=_file_size_limit(8_000))
    assert run.returncode == 2 and run.stderr.startswith("prsc: error: cannot write"), run.stderr
    root = tmp_path / "out" / "two"
    listed = _listed(root)
    on_disk = {f"mjcf/{p.name}" for p in (root / "mjcf").iterdir()}
    assert on_disk == set(listed.values()) and 10 < len(on_disk) < 800
    scenes = {key.split(":")[0] for key in listed}
    assert all(f"{k}:mjcf" in listed and f"{k}:mjcf.task" in listed for k in scenes)
    for k in scenes:
        assert json.loads((root / listed[f"{k}:mjcf.task"]).read_text())["format"] == "prsc-task"
    assert not [p for p in root.rglob(".*") if p.name.endswith(".tmp")]


def test_each_scene_has_its_own_task_file_because_the_task_holds_its_boxes(tmp_path):
    spec = tmp_path / "sizes.prs"
    spec.write_text("a = Object at Vector3D(0, 0, 1), with width (0.1, 0.3)\n"
                    'fail "fell" when a.z < 0.5\n')
    assert main(["compile", str(spec), "--target", "mjcf", "-n", "2", "-o", str(tmp_path / "out")]) == 0
    tasks = [json.loads((tmp_path / "out" / "sizes" / "mjcf" / f"0000{k}.task.json").read_text()) for k in (0, 1)]
    assert tasks[0]["failures"] == tasks[1]["failures"]  # the same statements...
    assert tasks[0]["objects"][0]["dimensions"][0] != tasks[1]["objects"][0]["dimensions"][0]  # ...on each scene's box
