"""`prsc run`: simulate a controller in MuJoCo over sampled scenes and classify the outcomes.

    prsc run FILE -n 100 --seed 0 -o OUT [--controller TARGET] [--jobs J]
             [--executor local|ray [--address ADDR]] [--max-sim-seconds S] [--video K]
             [--record DIR [--format lerobot|robomimic] [--fps F] [--keep all|success]]

compiles the scenes as `prsc compile --target json,mjcf` does (under OUT/<stem>/), calls the
controller once per scene with a fresh MjModel/MjData of its MJCF file, and appends each
finished episode to OUT/results.jsonl. A killed campaign re-run with the same arguments
skips the episodes already recorded; the finished file lists every episode in index order,
identical (wall-clock times aside) to one an uninterrupted run writes. Then a summary
table, OUT/outcomes.png and the controller's own plots.

--record DIR also records every episode as a demonstration dataset (docs/datasets.md): the
robots' joints and grippers, the controls sent, every camera object's images, the MuJoCo
state, F frames per simulated second; resumable like the results, the same with any --jobs.
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
    record = parser.add_argument_group("recording a dataset (docs/datasets.md)")
    record.add_argument("--record", type=Path, default=None, metavar="DIR",
                        help="record every episode into the dataset folder DIR (resumed when it holds this recording)")
    record.add_argument("--format", default="lerobot", choices=("lerobot", "robomimic"),
                        help="LeRobot v3 (parquet + mp4, default) or robomimic (HDF5)")
    record.add_argument("--fps", type=int, default=20, metavar="F", help="frames per simulated second (default 20)")
    record.add_argument("--keep", default="all", choices=("all", "success"),
                        help="keep every episode (default) or those whose task succeeded")
    record.add_argument("--no-images", dest="images", action="store_false",
                        help="record no camera images (a spec without a camera object needs this)")
    record.add_argument("--lossless", action="store_true",
                        help="LeRobot videos encoded losslessly (libx264rgb, crf 0): replay matches bit for bit")
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
    if args.record is None and any(getattr(args, k) != v for k, v in RECORD_DEFAULTS.items()):
        raise PrscError("--format, --fps, --keep, --no-images and --lossless need --record DIR")
    if args.fps < 1:
        raise PrscError(f"--fps must be >= 1, got {args.fps}")


RECORD_DEFAULTS = {"format": "lerobot", "fps": 20, "keep": "all", "images": True, "lossless": False}


def _open_dataset(args: argparse.Namespace, key: dict, tasks: list, scenes: list[dict]) -> Any:
    """The --record dataset, checked against the campaign before anything in it is touched."""
    import mujoco

    from prsc.runner.demo_dataset import DemoDataset

    if not tasks:
        raise PrscError("--record: the campaign has no episodes")
    timestep = mujoco.MjModel.from_xml_path(tasks[0].mjcf_path).opt.timestep
    if args.fps > 1.0 / timestep + 1e-9:
        raise PrscError(f"--fps {args.fps} is above the control rate, {1.0 / timestep:g} steps per simulated second "
                        f"(timestep {timestep:g} s): a frame per step at most")
    if args.images and not any(o.get("camera") is not None for o in scenes[0].get("objects", [])):
        raise PrscError(f"--record: {args.file} has no camera object for images; add one "
                        "(e.g. `Camera at Vector3D(0, -1, 1.5), with resolution [128, 128]`) or pass --no-images")
    record_key = {**key, "format": args.format, "fps": args.fps, "images": args.images, "lossless": args.lossless}
    # robomimic's env_args: a Gymnasium env (its type 2) that steps a frame at a time: prsc.SceneEnv
    env_args = {"env_name": "prsc/SceneEnv-v0", "type": 2, "env_kwargs": {
        "spec": str(args.file), "frame_skip": max(1, round(1.0 / (args.fps * timestep)))},
        "prsc": {"seed": args.seed, "controller": args.controller, "fps": args.fps}}
    return DemoDataset(args.record, record_key, args.keep, env_args).open()


def run(args: argparse.Namespace) -> int:
    """Run the episodes and report; exit code 0 whatever the outcomes, 2 on an infrastructure fault."""
    _validate(args)
    from prsc.runner.gl import choose_gl_backend

    # Before anything imports mujoco: MuJoCo fixes its GL backend at import.
    gl_backend = choose_gl_backend()
    if args.record is not None:
        from prsc.runner.demo_dataset import require_libraries

        require_libraries()  # before anything is compiled
    from rich.console import Console

    from prsc.runner.controller import declared_outcomes, load_controller, parse_target
    from prsc.runner.worker import WorkerConfig
    from prsc.commands.compile import MANIFEST, compile_scenes
    from prsc.pipeline.executors import executor_from_arguments, worker_count
    from prsc.pipeline.output_folder import folder_before, restore_folder
    from prsc.pipeline.progress import progress_bar
    from prsc.pipeline.scene_sources import proposal_from_json
    from prsc.pipeline.static_checks import compile_checked

    source = Path(args.file)
    proposal = read_proposal(args.proposal, args.file)
    controller_ref = parse_target(args.controller)
    controller = load_controller(controller_ref)
    declared = declared_outcomes(controller)
    jobs = worker_count(args.jobs)
    executor = executor_from_arguments(args, jobs, start="spawn")
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
    before = folder_before(out)  # put back if the campaign fails before its first episode
    results: Results | None = None
    dataset = None
    try:
        # Scenes and MJCF files as `prsc compile --target json,mjcf` writes them, under out/<stem>/.
        count = args.n if args.n is not None else (0 if is_json else 10)
        root = compile_scenes(str(source), ["json", "mjcf"], count, args.seed, str(out), jobs=jobs,
                              include_dirs=args.include, executor=executor_from_arguments(args, jobs, start="fork"),
                              force=args.force, proposal=proposal, law=args.law, compiled=compiled)
        manifest = json.loads((root / MANIFEST).read_text(encoding="utf-8"))
        tasks, scenes = episode_tasks(root, range(count) if count else None, args.seed, controller_ref,
                                      args.max_sim_seconds)
        if check is not None and not is_json:  # a JSON input's scenes, and scene 0 of a spec, were checked above
            for scene in scenes[1:]:
                check(scene)
        compiled = time.perf_counter()

        key = _campaign_key(manifest, args, controller_ref.digest)
        dataset = _open_dataset(args, key, tasks, scenes) if args.record is not None else None
        results = Results(out, key)
        # with --record, an episode is done once the dataset holds it (or left it out by --keep)
        done = len(tasks) if dataset is None else min(len(tasks), dataset.processed)
        kept = {k: r for k, r in results.recorded().items() if k < done}
        todo = [t for t in tasks if t.index not in kept]
        results.begin(kept)
        if kept:
            console.print(f"resuming: {len(kept)} of {len(tasks)} episodes already in {out / RESULTS}")
        record_settings = None
        if dataset is not None:
            from prsc.runner.episode_records import RecordSettings

            record_settings = RecordSettings(args.format, args.fps, lossless=args.lossless, images=args.images)
        progress = progress_bar(len(todo), "episodes", "episodes")
        try:
            with progress if progress else nullcontext():
                bar = progress.add_task("episodes", total=len(todo)) if progress else None

                def finished(record: dict) -> None:
                    results.add(record)
                    if progress:
                        progress.advance(bar)

                cpu_before = cpu_seconds()
                run_episodes(executor, WorkerConfig(gl_backend, one_raster_thread=jobs > 1 or args.executor == "ray",
                                                    record=record_settings),
                             todo, finished, on_recording=None if dataset is None else lambda k, e: dataset.add(e, k))
                cpu_used = cpu_seconds() - cpu_before
        finally:
            results.close()
            if dataset is not None:
                dataset.close()
    except Exception:
        if results is None or not results.records:
            restore_folder(before)  # failed before its first episode: the folder as it was
        raise
    finished_at = time.perf_counter()
    ordered = results.finish()  # index order, as a clean run writes

    title = f"{source.name}: {len(ordered)} episodes, seed {args.seed}"
    from prsc.runner.report import plot_outcomes, plot_task_outcomes, summary_table, task_table
    from prsc.pipeline.tables import print_table

    plot_outcomes(ordered, out / "outcomes.png", title, declared)
    with_task = any(r.get("task") for r in ordered)
    if with_task:  # the spec's task (docs/tasks.md) beside the controller's own outcome
        plot_task_outcomes(ordered, out / "task_outcomes.png", title, declared)
    report = getattr(controller, "report", None)
    if report is not None:
        report(ordered, scenes, out, title)
    _write_strips(tasks, ordered, out, args.video)

    print_table(summary_table(ordered, title, declared))
    if with_task:
        print_table(task_table(ordered, title, declared))
    episodes = f"{len(todo)} episodes {finished_at - compiled:.1f} s"
    if todo and args.executor == "local":
        episodes += f", {cpu_used / len(todo):.2f} CPU s each"
    console.print(f"compile {compiled - started:.1f} s, {episodes} ({executor.summary()}); "
                  f"results in {out / RESULTS}")
    if dataset is not None:
        frames = sum(e["frames"] for e in dataset.episodes)
        size = sum(p.stat().st_size for p in Path(args.record).rglob("*") if p.is_file())
        console.print(f"dataset {args.record} ({args.format}): {len(dataset.episodes)} episodes, {frames} frames, "
                      f"{size / 1e6:.1f} MB")
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
