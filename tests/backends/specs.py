"""The specs every backend test compiles: the originals (../shared) and ours (specs/)."""

from __future__ import annotations

from pathlib import Path

from tests.original import ORIGINAL, original_params

REPO = Path(__file__).resolve().parents[2]
SCENES_PER_SPEC = 6  # per spec and format (10 until the suite passed 4 min); the relation checks cover 400 scenes a spec


def all_specs() -> list[Path]:
    """Every .prs file of the original ProbRobScene specs (a skipped parameter when absent) and of specs/."""
    # table_cube_naive.prs writes the same scenes as table_cube.prs (only how it is sampled
    # differs): the backends have nothing more to show on it.
    ours = [p for p in sorted((REPO / "specs").glob("*.prs")) if p.name != "table_cube_naive.prs"]
    return original_params() + ours


def spec_id(path: Path) -> str:
    """A readable test id: `original/tableCube` or `specs/table_cube`."""
    if not isinstance(path, Path):  # the skipped stand-in for absent originals
        return path.id
    return f"{'original' if path.parent.resolve() == ORIGINAL.resolve() else 'specs'}/{path.stem}"


def compiled(tmp_root: Path, spec: Path, targets: list[str]) -> tuple[Path, list[dict]]:
    """Compile SCENES_PER_SPEC scenes of a spec; the output folder and the scene JSONs."""
    import json

    from prsc.commands.compile import compile_scenes

    out = tmp_root / spec_id(spec).replace("/", "_")
    root = compile_scenes(str(spec), ["json"] + targets, SCENES_PER_SPEC, 0, str(out))
    manifest = json.loads((root / "manifest.json").read_text())
    scenes = [json.loads((root / s["files"]["json"]).read_text()) for s in manifest["scenes"]]
    assert len(scenes) == SCENES_PER_SPEC
    return root, scenes
