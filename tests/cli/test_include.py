"""`--include DIR` for the commands that sample a spec and write files: compile, run and preview."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from prsc.cli import main
from prsc.pipeline.scene_job import Job
from prsc.sampling import compile_sampler

REPO = Path(__file__).resolve().parents[2]
# Before mujoco is first imported: it picks its GL backend then (no display here).
os.environ.setdefault("MUJOCO_GL", "egl")


@pytest.fixture
def handover(tmp_path) -> tuple[Path, Path]:
    """specs/table_cube.prs in its own folder, taking its tray gap from `lib.prs` in another folder."""
    lib = tmp_path / "lib"
    lib.mkdir()
    (lib / "lib.prs").write_text("tray_gap = 0.1\n")
    folder = tmp_path / "spec"
    folder.mkdir()
    text = (REPO / "specs" / "table_cube.prs").read_text()
    text = text.replace("from tabletop import *\n", "from tabletop import *\nfrom lib import *\n").replace("by 0.1,", "by tray_gap,")
    spec = folder / "handover.prs"
    spec.write_text(text)
    return spec, lib


def _not_found(spec: Path) -> str:
    """The first line of the error for the unresolved `from lib import *`."""
    line = spec.read_text().splitlines().index("from lib import *") + 1
    return f"{spec}:{line}:6: error: import not found: no file lib.prs"


def test_compile_finds_imports_through_include(handover, tmp_path, capsys):
    import mujoco

    spec, lib = handover
    out = tmp_path / "out"
    assert main(["compile", str(spec), "--target", "json,mjcf", "-o", str(out)]) == 2
    assert capsys.readouterr().err.startswith(_not_found(spec))
    assert not out.exists()
    assert main(["compile", str(spec), "--target", "json,mjcf", "-n", "3", "-o", str(out), "-I", str(lib)]) == 0
    root = out / "handover"
    expected = compile_sampler(str(spec), [str(lib)])
    for k in range(3):
        assert json.loads((root / "json" / f"{k:05d}.json").read_text()) == json.loads(json.dumps(expected.scene(0, k)))
    mujoco.MjModel.from_xml_path(str(root / "mjcf" / "00000.xml"))
    parallel = tmp_path / "parallel"
    assert main(["compile", str(spec), "-n", "3", "-o", str(parallel), "--include", str(lib), "--jobs", "2"]) == 0
    for k in range(3):
        name = f"json/{k:05d}.json"
        assert (parallel / "handover" / name).read_text() == (root / name).read_text()
    # The manifest's digest covers the file found through --include: editing it makes the scenes stale.
    (lib / "lib.prs").write_text("tray_gap = 0.15\n")
    assert main(["compile", str(spec), "-n", "1", "-o", str(out), "-I", str(lib)]) == 2
    assert main(["compile", str(spec), "-n", "1", "-o", str(out), "-I", str(lib), "--force"]) == 0
    again = compile_sampler(str(spec), [str(lib)]).scene(0, 0)
    assert again != expected.scene(0, 0)
    assert json.loads((root / "json" / "00000.json").read_text()) == json.loads(json.dumps(again))


def test_a_compile_job_carries_the_include_dirs(handover, tmp_path):
    """A worker that compiles the spec again (a spawned process) resolves the same imports."""
    spec, lib = handover
    job = Job(spec=str(spec), seed=3, targets=("json",), root=str(tmp_path), width=5, include_dirs=(str(lib),))
    assert job.scene(2) == compile_sampler(str(spec), [str(lib)]).scene(3, 2)


def test_run_finds_imports_through_include(handover, tmp_path, capsys):
    spec, lib = handover
    out = tmp_path / "run"
    assert main(["run", str(spec), "-n", "1", "-o", str(out)]) == 2
    assert capsys.readouterr().err.startswith(_not_found(spec))
    assert not out.exists()
    assert main(["run", str(spec), "-n", "1", "-o", str(out), "-I", str(lib)]) == 0
    [result] = [json.loads(line) for line in (out / "results.jsonl").read_text().splitlines()]
    assert result["index"] == 0 and (out / "handover" / "mjcf" / "00000.xml").is_file()


def test_preview_finds_imports_through_include(handover, tmp_path, capsys):
    spec, lib = handover
    sheet = tmp_path / "sheet.png"
    assert main(["preview", str(spec), "-n", "1", "-o", str(sheet)]) == 2
    assert capsys.readouterr().err.startswith(_not_found(spec))
    assert not sheet.exists()
    assert main(["preview", str(spec), "-n", "1", "-o", str(sheet), "-I", str(lib)]) == 0
    assert sheet.read_bytes().startswith(b"\x89PNG")


@pytest.mark.parametrize("command", ["compile", "run", "preview"])
def test_an_include_folder_that_does_not_exist(handover, tmp_path, capsys, command):
    spec, _ = handover
    missing = tmp_path / "nowhere"
    out = tmp_path / ("sheet.png" if command == "preview" else "out")
    assert main([command, str(spec), "-o", str(out), "--include", str(missing)]) == 2
    assert capsys.readouterr().err == f"prsc: error: --include {missing}: no such folder\n"
    assert not out.exists()
