"""Issue 23, "no partial output": a failed compile leaves the output folder as it was before
the run, plus only complete, recorded scenes. Errors that show in one scene are found before
anything is written; a full disk mid-run leaves only whole scenes that the manifest lists."""

from __future__ import annotations

import hashlib
import json
import os
import resource
import subprocess
import sys
from pathlib import Path

import pytest

from prsc.cli import main

REPO = Path(__file__).resolve().parents[2]
MESH = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n"
FAILING = {
    # detected before any scene: the mesh lies outside the spec's and --include folders
    "mesh-outside": 'a = Object at Vector3D(0, 1, 1), with mesh "../elsewhere/tet.obj"\n',
    # 43 files were left behind by this one: the URDF bundle's file name is too long
    "name-too-long": "x" * 260 + " = Object at Vector3D(0, 1, 1)\n",
    "impossible-mass": "a = Object at Vector3D(0, 1, 1), with mass 1e30\n",
    # only some scenes hold an impossible mass: scene 0 passes the preflight, scene 26 of seed 0 fails
    "mass-in-a-later-scene": "a = Object at Vector3D(0, 1, 1), with mass (1, 1.1e12)\n",
}


def _tree(folder: Path) -> dict[str, str]:
    """Every file under `folder` with a digest of its content."""
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def _listed(root: Path) -> set[str]:
    """Every file manifest.json and its journal (manifest.jsonl, which a re-run absorbs) record."""
    manifest = json.loads((root / "manifest.json").read_text())
    rels = {rel for scene in manifest["scenes"] for rel in scene["files"].values()}
    journal = root / "manifest.jsonl"
    if journal.exists():
        for line in journal.read_text().split("\n")[:-1]:
            try:
                rels |= set(json.loads(line)["files"].values())
            except ValueError:  # a line the full disk cut: prsc skips it too
                continue
    return rels


@pytest.mark.parametrize("case", sorted(FAILING))
def test_a_failed_compile_leaves_the_folder_as_it_was(tmp_path, capsys, case):
    """Into a fresh folder: nothing is created. Into one holding a user's file and an earlier
    run of another spec: every file is as before."""
    (tmp_path / "elsewhere").mkdir()
    (tmp_path / "elsewhere" / "tet.obj").write_text(MESH)
    work = tmp_path / "work"
    work.mkdir()
    spec = work / "s.prs"
    spec.write_text(FAILING[case])
    fresh = tmp_path / "fresh"
    assert main(["compile", str(spec), "--target", "json,mjcf,urdf,sdf,usd", "-n", "40", "-o", str(fresh)]) == 2
    err = capsys.readouterr().err
    assert "error:" in err and "Traceback" not in err
    if case != "mass-in-a-later-scene":
        assert err.startswith(f"{spec}:"), err  # at the spec's line
        assert not fresh.exists()

    used = tmp_path / "used"
    other = work / "t.prs"
    other.write_text("b = Object at Vector3D(0, 1, 1)\n")
    assert main(["compile", str(other), "--target", "json,mjcf", "-n", "2", "-o", str(used)]) == 0
    (used / "notes.txt").write_text("the user's")
    (used / "s").mkdir()
    (used / "s" / "mine.txt").write_text("the user's too")
    before = _tree(used)
    assert main(["compile", str(spec), "--target", "json,mjcf,urdf,sdf,usd", "-n", "40", "-o", str(used)]) == 2
    after = _tree(used)
    if case == "mass-in-a-later-scene":  # the scenes before the failing one are whole and recorded
        listed = _listed(used / "s")
        assert len(listed) == 5 * 26, len(listed)
        for new in set(after) - set(before):
            rel = new.removeprefix("s/")
            assert rel in ("manifest.json",) or rel.startswith("assets/") \
                or any(rel == out or rel.startswith(out + "/") for out in listed), new
        assert {k: v for k, v in after.items() if k in before} == before
    else:
        assert after == before


def _file_size_limit(size: int):
    def limit() -> None:
        resource.setrlimit(resource.RLIMIT_FSIZE, (size, size))
    return limit


def test_a_full_disk_mid_run_leaves_only_whole_recorded_scenes(tmp_path):
    """A file-size limit (EFBIG, as a full disk's ENOSPC) stops the run mid-way, when the journal
    of finished files outgrows it, with exit 2 and one line; every scene file left is whole and
    listed, and no temporary stays."""
    out = tmp_path / "out"
    spec = tmp_path / "two.prs"
    spec.write_text("a = Object at Vector3D((0, 1), 1, 1)\nb = Object at Vector3D(0, (3, 4), 1)\n")
    run = subprocess.run([sys.executable, "-m", "prsc.cli", "compile", str(spec), "--target", "json,mjcf", "-n", "400",
                          "-o", str(out)], capture_output=True, text=True, cwd=tmp_path,
                         env=dict(os.environ, PYTHONPATH=str(REPO)), preexec_fn=_file_size_limit(8_000))
    assert run.returncode == 2 and run.stderr.startswith("prsc: error: cannot write"), run.stderr
    assert "Traceback" not in run.stderr and run.stderr.count("\n") == 1
    root = out / "two"
    listed = _listed(root)
    on_disk = {f"{t}/{p.name}" for t in ("json", "mjcf") for p in (root / t).iterdir()}
    assert on_disk == listed and 10 < len(listed) < 800, (sorted(on_disk - listed), sorted(listed - on_disk))
    for rel in listed:
        if rel.startswith("json/"):
            assert json.loads((root / rel).read_text())["format"] == "prsc-scene"
    assert not [p for p in root.rglob(".*") if p.name.endswith(".tmp")]
    assert not (root / ".prsc-lock").exists()
