"""`prsc bench FILE... [--json]`: every sampler side by side on each spec.
`prsc bench --backends FILE [-n 1000] [--jobs 1,2]`: files written per second per format.
`prsc bench --episodes FILE [-n 21] [--controller TARGET]`: CPU seconds per `prsc run` episode.
`prsc bench --resets FILE... [-n 200]`: resets per CPU-second, `scenario.apply` against a compile per scene.

For each spec and sampler (exact under each law: joint, sequential, rejection; hit-and-run;
the paper's naive baseline; for a batched spec, each exact law also one scene at a time, as
`batched=False` draws it): scenes per second on one core
(scene JSON dicts, measured in process CPU time so other load on the machine does not
count; wall-clock rate shown too), rejections per scene by cause (the paper's Table II
causes: collision, relative position, containment, require; plus dead ends), and the peak
resident memory of the process that sampled, and the distance of its object positions to
the joint law's exact reference (`exact/rejection`, when it sampled at least 200 scenes): the
largest per-coordinate two-sample KS statistic and the smallest p-value. Each measurement
runs in a fresh forked process so peaks do not carry over.
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import os
import resource
import sys
import time
from typing import Any

from prsc.errors import PrscError
from prsc.pipeline.seed_jobs import check_seed_and_jobs

SAMPLERS = ("exact", "hit-and-run", "baseline")
LAWS = ("joint", "sequential", "rejection")
DEFAULT_SCENES = {"exact": 5000, "hit-and-run": 200, "baseline": 100}
REFERENCE = "exact/rejection"  # the joint law by whole-scene rejection
MIN_REFERENCE = 200  # scenes the reference needs before a distance means anything
REFERENCE_SEED_OFFSET = 1_000_003  # the reference's scenes are independent of the rows' (seed + this)


def add_parser(subparsers: Any) -> None:
    """Register `prsc bench`."""
    parser = subparsers.add_parser(
        "bench", help="compare the samplers on specs (speed, rejections, memory)", description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("files", nargs="+", metavar="FILE", help=".prs specs")
    parser.add_argument("--include", "-I", action="append", default=[], metavar="DIR", help="also search DIR for imports")
    parser.add_argument("--json", action="store_true", help="print the results as JSON")
    parser.add_argument("--samplers", default=",".join(SAMPLERS), help="comma-separated subset of exact,hit-and-run,baseline")
    parser.add_argument("--laws", default=",".join(LAWS), help="comma-separated laws of the exact sampler (default all)")
    parser.add_argument("-n", "--scenes", type=int, default=None,
                        help="scenes per sampler (default: exact 5000, hit-and-run 200, rejection 100)")
    parser.add_argument("--seconds", type=float, default=20.0, help="stop a measurement after this much CPU time (default 20)")
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    parser.add_argument("--walk-length", type=int, default=100, help="hit-and-run steps per sample (default 100)")
    parser.add_argument("--backends", action="store_true",
                        help="time `prsc compile` per output format instead (default -n 1000)")
    parser.add_argument("--jobs", default="1,2", help="with --backends: comma-separated job counts (default 1,2)")
    parser.add_argument("--target", default=None, help="with --backends: comma-separated targets (default all)")
    parser.add_argument("--episodes", action="store_true",
                        help="time `prsc run` episodes instead: CPU s per episode and where it goes (default -n 21)")
    parser.add_argument("--resets", action="store_true",
                        help="time RL resets instead: scenario.apply against a model compiled per scene (default -n 200)")
    parser.add_argument("--controller", default="prsc.runner.handover:handover", metavar="TARGET",
                        help="with --episodes: the controller (default the handover)")


def measure(
    path: str, include: list[str], sampler_name: str, n: int, seconds: float, seed: int, walk_length: int, law: str = "joint",
    batched: bool = True,
) -> dict[str, Any]:
    """Sample up to n scenes (or `seconds` of CPU time): rates, rejections, memory, positions.
    A batched spec is drawn in batches (`batched=False`: one scene at a time, from per-scene Generators)."""
    from prsc.sampling import compile_sampler
    from prsc.sampling.mixing import coordinates
    from prsc.sampling.sampler import BATCH
    from prsc.sampling.stats import RejectionStats

    sampler = compile_sampler(path, include, sampler_name, walk_length=walk_length, law=law, batched=batched)
    # One scene first: imports and lazily prepared regions are set-up, not per-scene cost.
    sampler.scene(seed, 10**9)
    stats = RejectionStats()
    cpu0, wall0 = time.process_time(), time.perf_counter()
    done = 0
    positions = []
    for first in range(0, n, BATCH) if sampler.batched else ():
        for scene in sampler.batch(seed, range(first, min(first + BATCH, n))):
            positions.append([v for o in scene["objects"] for v in o["position"]])
        done = len(positions)
        stats.scenes = done
        if time.process_time() - cpu0 > seconds:
            break
    for index, result in sampler.each_result(seed, range(n)) if not sampler.batched else ():
        sampler.to_json(result, seed, index)
        stats.merge(result.stats)
        positions.append(coordinates(result).tolist())
        done += 1
        if time.process_time() - cpu0 > seconds:
            break
    cpu = max(time.process_time() - cpu0, 1e-9)
    wall = max(time.perf_counter() - wall0, 1e-9)
    by_cause = stats.by_cause()
    return {
        "scenes": done,
        "scenes_per_s": done / cpu,
        "wall_scenes_per_s": done / wall,
        "rejections_per_scene": sum(by_cause.values()) / done,
        "rejections_by_cause": {cause: count / done for cause, count in by_cause.items()},
        "peak_memory_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
        "positions": positions,
    }


def _child(conn: Any, args: tuple) -> None:
    try:
        conn.send(("ok", measure(*args)))
    except PrscError as error:
        # The parts, not the exception: the parent rebuilds it with its span and notes.
        conn.send(("error", (error.message, error.span, error.notes)))
    except Exception as error:  # report, do not hang the parent
        conn.send(("bug", f"{type(error).__name__}: {error}"))
    finally:
        conn.close()


class BenchmarkProcessError(RuntimeError):
    """The measuring process failed in a way that is prsc's fault (reported as an internal error)."""


def measure_isolated(*args: Any) -> dict[str, Any]:
    """`measure` in a fresh forked process (its own peak memory); PrscError on failure."""
    ctx = multiprocessing.get_context("fork")
    parent, child = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=_child, args=(child, args))
    proc.start()
    child.close()
    try:
        status, payload = parent.recv()
    except EOFError:
        status, payload = "bug", f"the benchmark process died (exit code {proc.exitcode})"
    proc.join()
    if status == "error":
        message, span, notes = payload
        raise PrscError(message, span, notes)
    if status != "ok":
        raise BenchmarkProcessError(payload)
    return payload


def _table(results: dict[str, dict[str, dict[str, Any]]]) -> None:
    from rich.console import Console
    from rich.table import Table

    table = Table(title="prsc bench: samplers side by side (one core)")
    for col in ("spec", "sampler", "scenes", "scenes/s", "wall/s", "rejections/scene",
                "collision", "relative", "containment", "require", "dead end", "peak MB", "KS D", "KS p"):
        table.add_column(col, justify="left" if col in ("spec", "sampler") else "right")
    for spec, per in results.items():
        for name, r in per.items():
            c = r["rejections_by_cause"]
            table.add_row(
                os.path.basename(spec), name, str(r["scenes"]), f"{r['scenes_per_s']:,.1f}", f"{r['wall_scenes_per_s']:,.1f}",
                f"{r['rejections_per_scene']:.2f}", f"{c.get('collision', 0):.2f}", f"{c.get('relative position', 0):.2f}",
                f"{c.get('containment', 0):.2f}", f"{c.get('require', 0):.2f}", f"{c.get('dead end', 0):.2f}",
                f"{r['peak_memory_mb']:.0f}",
                "-" if r.get("ks_statistic") is None else f"{r['ks_statistic']:.3f}",
                "-" if r.get("ks_pvalue") is None else f"{r['ks_pvalue']:.2g}",
            )
    console = Console()
    if not console.is_terminal:
        console = Console(width=170)  # a pipe or file: do not squeeze the columns to 80
    console.print(table)


def run(args: argparse.Namespace) -> int:
    """Benchmark every spec with every chosen sampler."""
    names = [s.strip() for s in args.samplers.split(",") if s.strip()]
    unknown = [s for s in names if s not in SAMPLERS]
    if "rejection" in unknown:
        raise PrscError("the sampler `rejection` is now `baseline` (the paper's naive baseline); "
                        "whole-scene rejection of the joint law is the law `rejection` (--laws)")
    if unknown or not names:
        raise PrscError(f"unknown sampler {unknown[0] if unknown else '(none)'!r} (choose from {', '.join(SAMPLERS)})")
    if args.scenes is not None and args.scenes < 1:
        raise PrscError(f"-n must be >= 1, got {args.scenes}")
    if not args.seconds > 0:  # also refuses nan, which would never stop a measurement
        raise PrscError(f"--seconds must be > 0, got {args.seconds}")
    check_seed_and_jobs(args.seed)
    if args.episodes:
        from prsc.runner.gl import choose_gl_backend

        choose_gl_backend()  # before compiling: a file arm's compile imports mujoco, which fixes its GL backend then
    from prsc.ir import compile_program

    for path in args.files:
        compile_program(path, args.include)  # report spec errors before forking
    if args.backends:
        return _run_backends(args)
    if args.resets:
        from prsc.commands.bench_resets import print_resets

        print_resets(args.files, args.scenes or 200, args.include)
        return 0
    if args.episodes:
        from prsc.commands.bench_episodes import print_episodes

        for path in args.files:
            print_episodes(path, args.scenes or 21, args.controller, args.include)
        return 0
    laws = [s.strip() for s in args.laws.split(",") if s.strip()]
    if not laws or any(law not in LAWS for law in laws):
        raise PrscError(f"--laws takes a comma-separated subset of {', '.join(LAWS)}, got {args.laws!r}")
    from prsc.sampling import compile_sampler

    batched = {path: compile_sampler(path, args.include).batched for path in args.files}
    results: dict[str, dict[str, dict[str, Any]]] = {}
    for path in args.files:
        results[path] = {}
        for name in names:
            n = args.scenes if args.scenes is not None else DEFAULT_SCENES[name]
            for law in laws if name == "exact" else ["sequential"]:
                row = f"exact/{law}" if name == "exact" else name
                # The reference draws from another seed: scene k of one seed is scene k under every
                # law whose draws agree, so a shared seed would hide or fake a distance.
                seed = args.seed + REFERENCE_SEED_OFFSET if row == REFERENCE else args.seed
                results[path][row] = measure_isolated(path, args.include, name, n, args.seconds, seed, args.walk_length, law)
                if name == "exact" and law != "rejection" and batched[path]:  # side by side: the same law unbatched
                    results[path][row + ", one at a time"] = measure_isolated(
                        path, args.include, name, n, args.seconds, seed, args.walk_length, law, False)
        _distances(results[path])
    if args.json:
        json.dump({"specs": results}, sys.stdout, indent=1)
        sys.stdout.write("\n")
    else:
        _table(results)
    return 0


def _distances(rows: dict[str, dict[str, Any]]) -> None:
    """Add each row's KS distance to the rejection reference (None without one); drop positions."""
    import numpy as np

    from prsc.sampling.mixing import distance

    reference = rows.get(REFERENCE)
    ref = np.array(reference["positions"]) if reference is not None and reference["scenes"] >= MIN_REFERENCE else None
    for name, r in rows.items():
        mine = np.array(r.pop("positions"))
        r["ks_statistic"] = r["ks_pvalue"] = None
        if ref is not None and name != REFERENCE and len(mine) and mine.shape[1] == ref.shape[1]:
            d = distance(mine, ref, [str(c) for c in range(ref.shape[1])])
            r["ks_statistic"], r["ks_pvalue"] = d.statistic, d.pvalue


def _run_backends(args: argparse.Namespace) -> int:
    """`prsc bench --backends`: the compile throughput per format of each spec."""
    from prsc.backends import TARGETS
    from prsc.commands.bench_backends import print_backends

    try:
        jobs = [int(j) for j in args.jobs.split(",") if j.strip()]
    except ValueError:
        raise PrscError(f"--jobs takes comma-separated counts, got {args.jobs!r}") from None
    if not jobs:
        raise PrscError(f"--jobs takes comma-separated counts, got {args.jobs!r}")
    check_seed_and_jobs(args.seed, jobs)
    targets = [t.strip() for t in (args.target or ",".join(TARGETS)).split(",") if t.strip()]
    unknown = [t for t in targets if t not in TARGETS]
    if unknown or not targets:
        raise PrscError(f"unknown target {', '.join(unknown) or '(none)'}; choose from {', '.join(TARGETS)}")
    for path in args.files:
        print_backends(path, args.scenes or 1000, jobs, targets, args.include)
    return 0
