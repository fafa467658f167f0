"""`prsc compile --settle-check`: the compiled scenes stepped in MuJoCo, and what moved."""

from __future__ import annotations

from pathlib import Path

from prsc.errors import PrscError

SETTLE_HELP = "step each MJCF 1 s in MuJoCo, robots at home; list free objects moving > 2 mm (exit 1 if any)"


def settle_targets(targets: list[str], settle: bool) -> None:
    """Refuse --settle-check without the files it reads."""
    if settle and not {"json", "mjcf"} <= set(targets):
        raise PrscError("--settle-check reads each scene's JSON and MJCF: use --target json,mjcf (and any others)")


def settle_check(root: Path, scenes: int | None, scene_input: bool) -> int:
    """Report the settle check of the scenes just compiled into `root`; 1 when one is not at rest.

    The scenes are those of this run: the first `scenes` (default 1 for a spec; every
    scene of a scene-JSON input when not given)."""
    from rich.console import Console

    from prsc.runner.settle_check import report_lines, settle_scenes
    from prsc.pipeline.output_folder import compiled_scenes

    indices = range(scenes if scenes else 1) if not scene_input or scenes else None
    results = settle_scenes(compiled_scenes(root, indices))
    console = Console(highlight=False, soft_wrap=True)
    for line in report_lines(results):
        console.print(line, markup=False)
    return 1 if any(r.drifts for r in results) else 0
