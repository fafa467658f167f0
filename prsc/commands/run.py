"""`prsc run`: simulate the Table-Cube handover controller in MuJoCo over sampled scenes."""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Sequence

from prsc.errors import PrscError


def add_parser(subparsers) -> None:
    """Register `prsc run`."""
    parser = subparsers.add_parser(
        "run",
        help="run the handover controller in MuJoCo over N scenes and classify the outcomes",
        description=(
            "Sample N scenes (or read them from scene JSON), compile each to MJCF, run the "
            "camera + IK handover controller headless, and write OUTPUT/results.jsonl, a summary "
            "table and plots. The scenes must each hold two Robots (Pandas), two Trays, one Cube "
            "and one Camera."
        ),
    )
    parser.add_argument("file", metavar="FILE", help="a .prs spec, or scenes from `prsc sample` (.jsonl) or one scene (.json)")
    parser.add_argument("-n", type=int, default=None, help="number of scenes (default 10 for a spec, all for JSON)")
    parser.add_argument("--seed", type=int, default=0, help="sampling seed (default 0)")
    parser.add_argument("-o", "--output", type=Path, default=None, help="output folder (default out/run-<name>)")
    parser.add_argument("--jobs", "-j", type=int, default=1, help="worker processes (default 1)")
    parser.add_argument("--video", type=int, default=0, metavar="K",
                        help="write a frame strip (PNG) of each of the first K failures")
    parser.add_argument("--include", "-I", action="append", default=[], metavar="DIR", help="also search DIR for imports")


def _compile(source: Path, count: int | None, seed: int, out: Path, jobs: int,
             include_dirs: Sequence[str] = ()) -> list[tuple[dict, Path]]:
    """Compile the scenes exactly as `prsc compile --target json,mjcf` does; (scene, MJCF path) pairs."""
    from prsc.commands.compile import MANIFEST, compile_scenes

    is_json = source.suffix in (".json", ".jsonl")
    if count is None:
        count = 0 if is_json else 10  # 0: every scene of a JSON file
    root = compile_scenes(str(source), ["json", "mjcf"], count, seed, str(out), jobs, include_dirs)
    manifest = json.loads((root / MANIFEST).read_text(encoding="utf-8"))
    pairs = []
    for entry in sorted(manifest["scenes"], key=lambda e: e["index"]):
        if count and entry["index"] >= count:
            continue
        scene = json.loads((root / entry["files"]["json"]).read_text(encoding="utf-8"))
        pairs.append((scene, root / entry["files"]["mjcf"]))
    return pairs


def _check_roles(source: Path, count: int | None, seed: int, include_dirs: Sequence[str] = ()) -> None:
    """Refuse scenes that are not handover scenes before anything is compiled or written."""
    from prsc.backends.runner.roles import find_roles
    from prsc.commands.compile import _read_scene_file, _spec_sampler

    if source.suffix in (".json", ".jsonl"):
        scenes = _read_scene_file(source)[:count]
    else:
        # Every scene of a spec has the same objects and classes: its first one tells.
        scenes = [_spec_sampler(str(source), seed, include_dirs)(0)]
    for scene in scenes:
        find_roles(scene)


def run(args: argparse.Namespace) -> int:
    """Run the episodes and report; exit code 0 whatever the outcomes."""
    from rich.console import Console

    if args.n is not None and args.n < 1:
        raise PrscError(f"-n must be >= 1, got {args.n}")
    if args.jobs < 1:
        raise PrscError(f"--jobs must be >= 1, got {args.jobs}")
    if args.video < 0:
        raise PrscError(f"--video must be >= 0, got {args.video}")
    if args.seed < 0:
        raise PrscError(f"--seed must be >= 0, got {args.seed}")
    source = Path(args.file)
    _check_roles(source, args.n, args.seed, args.include)
    console = Console(stderr=True)
    from prsc.backends.runner.batch import EpisodeTask, choose_gl_backend, run_tasks
    from prsc.backends.runner.frames import record_episode, write_strip
    from prsc.backends.runner.report import plot_cube_map, plot_outcomes, summary_table, write_results
    from prsc.backends.runner.roles import find_roles

    choose_gl_backend()
    out = args.output or Path("out") / f"run-{source.stem}"
    started = time.perf_counter()
    # Scenes and MJCF files as `prsc compile --target json,mjcf` writes them, under out/<stem>/.
    pairs = _compile(source, args.n, args.seed, out, args.jobs, args.include)
    roles = [find_roles(scene) for scene, _ in pairs]  # a scene without the roles stops here
    tasks = [EpisodeTask(scene, str(mjcf), int(scene.get("seed", args.seed))) for scene, mjcf in pairs]
    compiled = time.perf_counter()

    from rich.progress import Progress

    with Progress(console=console, transient=True) as progress:
        bar = progress.add_task("episodes", total=len(tasks))
        results = run_tasks(tasks, args.jobs, on_result=lambda _: progress.advance(bar))
    finished = time.perf_counter()

    out.mkdir(parents=True, exist_ok=True)
    write_results(results, out / "results.jsonl")
    title = f"{source.name}: {len(results)} episodes, seed {args.seed}"
    plot_outcomes(results, out / "outcomes.png", title)
    plot_cube_map(results, [r.source_tray for r in roles], out / "cube_map.png", title)
    failures = [(task, result) for task, result in zip(tasks, results) if result.outcome != "success"]
    for stale in (out / "failures").glob("episode_*.png"):
        stale.unlink()  # strips of an earlier run into the same folder
    for task, result in failures[: args.video]:
        again, frames = record_episode(task.scene, task.mjcf_path, task.seed)
        note = "" if again.outcome == result.outcome else f" (re-run gave {again.outcome}!)"
        write_strip(frames, f"episode {result.index}: {result.outcome}{note}: {result.reason} "
                            "(overview from the robots' front: the left robot is on the right)",
                    out / "failures" / f"episode_{result.index:04d}_{result.outcome}.png")

    Console().print(summary_table(results, title))
    console.print(
        f"compile {compiled - started:.1f} s, episodes {finished - compiled:.1f} s "
        f"({(finished - compiled) / max(1, len(results)):.2f} s each with {args.jobs} job(s)); "
        f"results in {out}/results.jsonl"
    )
    sys.stdout.flush()
    return 0
