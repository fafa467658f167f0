"""`prsc sample FILE -n N --seed S`: scene JSON, one scene per line.

Writes to stdout, or with -o to a file (via a temporary file renamed at the end, so a
failed run leaves no partial file). Scenes are streamed: memory does not grow with -n.
"""

from __future__ import annotations

import argparse
import sys
from typing import IO, Any

from prsc.pipeline.outputs import output_file, write_error
from prsc.pipeline.scene_sources import add_law_argument, add_proposal_argument, proposal_from_json, read_proposal
from prsc.errors import PrscError


def add_parser(subparsers: Any) -> None:
    """Register `prsc sample`."""
    parser = subparsers.add_parser(
        "sample", help="sample scenes as scene JSON lines", description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("file", metavar="FILE", help="a .prs spec")
    parser.add_argument("-n", "--scenes", type=int, default=1, help="number of scenes (default 1)")
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    parser.add_argument("--start", type=int, default=0, help="index of the first scene (default 0)")
    parser.add_argument("--include", "-I", action="append", default=[], metavar="DIR", help="also search DIR for imports")
    parser.add_argument("--sampler", default="exact", metavar="{exact,hit-and-run,baseline}",
                        help="exact (default), hit-and-run (the paper's), or baseline (the paper's naive baseline)")
    parser.add_argument("--walk-length", type=int, default=100, help="hit-and-run steps per sample (default 100)")
    parser.add_argument("--joint", action="store_true", help=argparse.SUPPRESS)  # gone: said why in run()
    add_law_argument(parser)
    add_proposal_argument(parser)
    parser.add_argument("-o", "--output", metavar="PATH", help="write to PATH instead of stdout")
    parser.add_argument("--stats", action="store_true", help="print rejection counts by cause to stderr at the end")


def write_scenes(sampler: Any, seed: int, start: int, n: int, out: IO[str]) -> Any:
    """Write n scenes as JSON lines; returns the merged rejection statistics."""
    from contextlib import nullcontext

    from prsc.pipeline.progress import progress_bar
    from prsc.sampling.sampler import BATCH
    from prsc.sampling.scene_text import scene_encoder
    from prsc.sampling.stats import RejectionStats

    total = RejectionStats()
    dumps = scene_encoder()
    bar = progress_bar(n if n >= 100 else 0, "sampling")  # short runs need none
    task = bar.add_task("sample", total=n) if bar else None
    with bar if bar else nullcontext():
        if sampler.batched:  # many scenes per numpy call; a batched scene is never rejected
            for first in range(start, start + n, BATCH):
                chunk = range(first, min(first + BATCH, start + n))
                # Line by line: a reader that goes away (`| head`) is then seen at the next write, where
                # one large write to a closed pipe can end short without an error.
                out.writelines(sampler.batch_lines(seed, chunk))
                if bar:
                    bar.advance(task, len(chunk))
            total.scenes += n
            return total
        for index, result in sampler.each_result(seed, range(start, start + n)):
            total.merge(result.stats)
            out.write(dumps(sampler.to_json(result, seed, index)))
            out.write("\n")
            if bar:
                bar.advance(task)
    return total



def run(args: argparse.Namespace) -> int:
    """Sample and write the scenes."""
    from prsc.sampling import compile_sampler

    if args.joint:
        raise PrscError("--joint is gone: the joint law is the default (--law joint); "
                        "whole-scene rejection, its exact reference, is --law rejection")
    if args.scenes < 0:
        raise PrscError(f"-n must be >= 0, got {args.scenes}")
    for option, value in (("--seed", args.seed), ("--start", args.start)):
        if value < 0:
            raise PrscError(f"{option} must be >= 0, got {value}")
    target = None if args.output is None else output_file(args.output)
    proposal = proposal_from_json(read_proposal(args.proposal, args.file))
    sampler = compile_sampler(args.file, args.include, args.sampler, walk_length=args.walk_length, law=args.law,
                              proposal=proposal)
    if target is None:
        stats = write_scenes(sampler, args.seed, args.start, args.scenes, sys.stdout)
        sys.stdout.flush()
    else:
        from prsc.files import atomic_text, remove_stale_temporaries

        try:
            # A run killed by a signal could not remove its temporary: do it now.
            remove_stale_temporaries(target.absolute().parent, of=target.name)
            with atomic_text(target) as out:
                stats = write_scenes(sampler, args.seed, args.start, args.scenes, out)
        except OSError as error:
            raise write_error(error, args.output) from None
    if args.stats:
        n = max(args.scenes, 1)
        per = ", ".join(f"{cause} {count / n:.3g}" for cause, count in stats.by_cause().items())
        sys.stderr.write(f"prsc: {args.scenes} scenes; rejections per scene: {per}\n")
    return 0
