"""`prsc run`: simulate a controller in MuJoCo over sampled scenes and classify the outcomes.

    prsc run FILE -n 100 --seed 0 -o OUT [--controller TARGET] [--jobs J]
             [--executor local|ray [--address ADDR]] [--max-sim-seconds S] [--video K]

compiles the scenes as `prsc compile --target json,mjcf` does (under OUT/<stem>/), calls the
controller once per scene with a fresh MjModel/MjData of its MJCF file, and appends each
finished episode to OUT/results.jsonl. A killed campaign re-run with the same arguments
skips the episodes already recorded; the finished file lists every episode in index order,
identical (wall-clock times aside) to one an uninterrupted run writes. Then a summary
table, OUT/outcomes.png and the controller's own plots.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from contextlib import nullcontext
from pathlib import Path
from typing import Any

from prsc.pipeline.campaign import RESULTS, Results, episode_tasks, refuse_foreign_results, run_episodes
from prsc.pipeline.executors import add_executor_arguments, cpu_seconds
from prsc.pipeline.scene_sources import add_law_argument, add_proposal_argument, read_proposal
from prsc.pipeline.seed_jobs import check_seed_and_jobs
from prsc.errors import PrscError

STRIPS = "strips.json"  # in failures/: the strips prsc wrote there, the only ones it replaces


def add_parser(subparsers) -> None:
    """Register `prsc run`."""
    from prsc.runner.controller import DEFAULT_CONTROLLER
    from prsc.runner.episode_records import DEFAULT_MAX_SIM_SECONDS

    parser = subparsers.add_parser(
        "run",
        help="run a controller in MuJoCo over N scenes and classify the outcomes",
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("file", metavar="FILE", help="a .prs spec, or scenes from `prsc sample` (.jsonl) or one scene (.json)")
    parser.add_argument("-n", type=int, default=None, help="number of scenes (default 10 for a spec, all for JSON)")
    parser.add_argument("--seed", type=int, default=0, help="sampling seed (default 0)")
    parser.add_argument("-o", "--output", type=Path, default=None, help="output folder (default out/run-<name>)")
    parser.add_argument("--controller", default=DEFAULT_CONTROLLER, metavar="TARGET",
                        help="package.module:name or path/to/file.py:name, called as name(scene, model, data) "
                             f"per episode (default {DEFAULT_CONTROLLER}, the two-arm handover)")
    parser.add_argument("--max-sim-seconds", type=float, default=DEFAULT_MAX_SIM_SECONDS, metavar="S",
                        help=f"end an episode past S simulated seconds as outcome `timeout` (default {DEFAULT_MAX_SIM_SECONDS:g})")
    parser.add_argument("--jobs", "-j", type=int, default=1, help="worker processes (default 1)")
    add_executor_arguments(parser)
    add_proposal_argument(parser)
    add_law_argument(parser)
    parser.add_argument("--video", type=int, default=0, metavar="K",
                        help="write a frame strip (PNG) of each of the first K episodes that did not succeed")
    parser.add_argument("--include", "-I", action="append", default=[], metavar="DIR", help="also search DIR for imports")
    parser.add_argument("--force", action="store_true",
                        help="replace the scenes of another spec, imported file, seed, law or proposal in the output folder (only files prsc listed)")


def _scenes_to_check(source: Path, count: int | None, seed: int, compiled: Any) -> list[dict]:
    """The scenes a controller's `check` sees before anything is written: every scene of a JSON
    input, the first of a spec (all scenes of a spec have the same objects and classes)."""
    from prsc.pipeline.scene_sources import read_scene_file

    if compiled is None:
        return read_scene_file(source)[:count or None]
    return [compiled.scene(seed=seed, index=0)]


def _campaign_key(manifest: dict, args: argparse.Namespace, controller_digest: str) -> dict:
    """What makes two runs the same campaign: the compiled scenes, the controller and its limit."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        prsc_version = version("prsc")
    except PackageNotFoundError:
        prsc_version = "unknown"
    return {"command": "run", "prsc": prsc_version, "spec_sha256": manifest["spec_sha256"],
            "sources_sha256": manifest["sources_sha256"],
            "seed": args.seed, "controller": args.controller, "controller_sha256": controller_digest,
            "max_sim_seconds": args.max_sim_seconds}


def _validate(args: argparse.Namespace) -> None:
    if args.n is not None and args.n < 1:
        raise PrscError(f"-n must be >= 1, got {args.n}")
    check_seed_and_jobs(args.seed, args.jobs)
    if args.video < 0:
        raise PrscError(f"--video must be >= 0, got {args.video}")
    if not args.max_sim_seconds > 0:
        raise PrscError(f"--max-sim-seconds must be > 0, got {args.max_sim_seconds:g}")


def run(args: argparse.Namespace) -> int:
    """Run the episodes and report; exit code 0 whatever the outcomes, 2 on an infrastructure fault."""
    _validate(args)
    from prsc.runner.gl import choose_gl_backend

    # Before anything imports mujoco: MuJoCo fixes its GL backend at import.
    gl_backend = choose_gl_backend()
    from rich.console import Console

    from prsc.runner.controller import declared_outcomes, load_controller, parse_target
    from prsc.runner.worker import WorkerConfig
    from prsc.commands.compile import MANIFEST, compile_scenes
    from prsc.pipeline.executors import make_executor, worker_count
    from prsc.pipeline.progress import progress_bar
    from prsc.pipeline.scene_sources import proposal_from_json
    from prsc.pipeline.static_checks import compile_checked

    source = Path(args.file)
    proposal = read_proposal(args.proposal, args.file)
    controller_ref = parse_target(args.controller)
    controller = load_controller(controller_ref)
    declared = declared_outcomes(controller)
    jobs = worker_count(args.jobs)
    executor = make_executor(args.executor, jobs, args.address, start="spawn")
    is_json = source.suffix in (".json", ".jsonl")
    # The spec is compiled once, here: the scenes checked below and those written are its.
    compiled = None if is_json else compile_checked(str(source), args.include, law=args.law,
                                                   proposal=proposal_from_json(proposal))
    check = getattr(controller, "check", None)
    if check is not None:
        for scene in _scenes_to_check(source, args.n, args.seed, compiled):
            check(scene)  # before anything is written
    console = Console(stderr=True)
    out = args.output or Path("out") / f"run-{source.stem}"
    refuse_foreign_results(out, "run", args.force)
    started = time.perf_counter()
    # Scenes and MJCF files as `prsc compile --target json,mjcf` writes them, under out/<stem>/.
    count = args.n if args.n is not None else (0 if is_json else 10)
    root = compile_scenes(str(source), ["json", "mjcf"], count, args.seed, str(out), jobs=jobs, include_dirs=args.include,
                          executor=make_executor(args.executor, jobs, args.address, start="fork"), force=args.force,
                          proposal=proposal, law=args.law, compiled=compiled)
    manifest = json.loads((root / MANIFEST).read_text(encoding="utf-8"))
    tasks, scenes = episode_tasks(root, range(count) if count else None, args.seed, controller_ref, args.max_sim_seconds)
    if check is not None and not is_json:  # a JSON input's scenes, and scene 0 of a spec, were checked above
        for scene in scenes[1:]:
            check(scene)
    compiled = time.perf_counter()

    results = Results(out, _campaign_key(manifest, args, controller_ref.digest))
    kept = {k: r for k, r in results.recorded().items() if k < len(tasks)}
    todo = [t for t in tasks if t.index not in kept]
    results.begin(kept)
    if kept:
        console.print(f"resuming: {len(kept)} of {len(tasks)} episodes already in {out / RESULTS}")
    progress = progress_bar(len(todo), "episodes", "episodes")
    try:
        with progress if progress else nullcontext():
            bar = progress.add_task("episodes", total=len(todo)) if progress else None

            def finished(record: dict) -> None:
                results.add(record)
                if progress:
                    progress.advance(bar)

            cpu_before = cpu_seconds()
            run_episodes(executor, WorkerConfig(gl_backend, one_raster_thread=jobs > 1 or args.executor == "ray"),
                         todo, finished)
            cpu_used = cpu_seconds() - cpu_before
    finally:
        results.close()
    finished_at = time.perf_counter()
    ordered = results.finish()  # index order, as a clean run writes

    title = f"{source.name}: {len(ordered)} episodes, seed {args.seed}"
    from prsc.runner.report import plot_outcomes, summary_table
    from prsc.pipeline.tables import print_table

    plot_outcomes(ordered, out / "outcomes.png", title, declared)
    report = getattr(controller, "report", None)
    if report is not None:
        report(ordered, scenes, out, title)
    _write_strips(tasks, ordered, out, args.video)

    print_table(summary_table(ordered, title, declared))
    episodes = f"{len(todo)} episodes {finished_at - compiled:.1f} s"
    if todo and args.executor == "local":
        episodes += f", {cpu_used / len(todo):.2f} CPU s each"
    console.print(f"compile {compiled - started:.1f} s, {episodes} ({jobs} job(s), {args.executor}); "
                  f"results in {out / RESULTS}")
    sys.stdout.flush()
    return 0



def _write_strips(tasks: list, records: list[dict], out: Path, count: int) -> None:
    """Frame strips of the first `count` episodes whose outcome is not `success` (re-run while recording)."""
    from prsc.runner.frames import record_episode, write_strip

    folder = out / "failures"
    for name in _strips_written(folder):
        (folder / name).unlink(missing_ok=True)  # strips an earlier run into this folder wrote
    failures = [(t, r) for t, r in zip(tasks, records) if r["outcome"] != "success"]
    written = []
    for task, record in failures[:count]:
        again, frames = record_episode(task, record["sim_seconds"])
        note = "" if again.outcome == record["outcome"] else f" (re-run gave {again.outcome}!)"
        name = f"episode_{record['index']:04d}_{record['outcome']}.png"
        write_strip(frames, f"episode {record['index']}: {record['outcome']}{note}: {record['reason']} "
                            "(overview from the +y side looking back: +x is on the left)", folder / name)
        written.append(name)
    if written or (folder / STRIPS).exists():
        from prsc.files import atomic_write

        atomic_write(folder / STRIPS, json.dumps(written) + "\n")


def _strips_written(folder: Path) -> list[str]:
    """The strip files prsc recorded writing into `folder` (never anything else found there)."""
    try:
        names = json.loads((folder / STRIPS).read_text())
    except (OSError, ValueError):
        return []
    if not isinstance(names, list):
        return []
    return [n for n in names if isinstance(n, str) and n.startswith("episode_") and "/" not in n and n.endswith(".png")]
