"""`prsc falsify`: spend an episode budget where a controller fails, still inside the spec.

    prsc falsify FILE --controller TARGET --budget N --seed S [-o DIR] [--jobs J]
                 [--executor local|ray] [--method failure-tree|cross-entropy|uniform] [--rounds R] [--resume]

runs the budget in rounds. Every round's scenes are drawn by the exact sequential sampler
from a proposal that only reweights the feasible set (prsc/sampling/proposal.py: a defensive
mixture of the spec's law and components that redraw each object position and range draw
on grid cells of its exact region), compiled as `prsc compile --target json,mjcf` does
(DIR/round_RR/), and simulated; then the proposal moves toward the failed scenes (a
failure-rate tree over the inputs, or a cross-entropy step per input).
Each episode of DIR/results.jsonl carries `round`, `weight` (the spec's sequential-law
density over the proposal's) and `law`; the summary gives the importance-weighted
failure probability under the spec's sequential law with a 95 % interval. Also in DIR:
proposal.json (for `prsc sample|compile|run --proposal`), clusters.json, falsify.png.
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import replace
from pathlib import Path
from typing import Any, Callable, Sequence

from prsc.pipeline.executors import add_executor_arguments
from prsc.pipeline.seed_jobs import check_seed_and_jobs
from prsc.pipeline.tables import print_table
from prsc.commands.falsify_property import STEERS, Verdict, check_property, episode_verdict
from prsc.constraints.polytope_ir import COLLISION
from prsc.errors import PrscError

METHODS = ("failure-tree", "cross-entropy", "uniform")
STRATA_STREAM = 0x5354  # entropy word that keeps a round's offset apart from scene_rng(seed, index)


def add_parser(subparsers: Any) -> None:
    """Register `prsc falsify`."""
    from prsc.runner.controller import DEFAULT_CONTROLLER
    from prsc.runner.episode_records import DEFAULT_MAX_SIM_SECONDS

    parser = subparsers.add_parser("falsify", help="search a spec for the scenes where a controller fails",
                                   description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("file", metavar="FILE", help="a .prs spec")
    parser.add_argument("--controller", default=DEFAULT_CONTROLLER, metavar="TARGET",
                        help=f"package.module:name or path/to/file.py:name (default {DEFAULT_CONTROLLER})")
    parser.add_argument("--budget", type=int, default=100, help="episodes in all (default 100)")
    parser.add_argument("--rounds", type=int, default=10, help="rounds the budget is split into (default 10)")
    parser.add_argument("--seed", type=int, default=0, help="sampling seed (default 0)")
    parser.add_argument("--method", choices=METHODS, default="failure-tree",
                        help="failure-tree (default: a mixture over the leaves of a failure-rate tree and the "
                             "failures found), cross-entropy (VerifAI's, per input), or uniform (the spec's own law)")
    parser.add_argument("--property", default=None, metavar="LABEL",
                        help="with a task in the spec: search for `fail \"LABEL\" when ...` only, or `goal` (the task "
                             "not succeeding); default: every task outcome but success (without a task: every "
                             "controller outcome but success)")
    parser.add_argument("--steer", choices=STEERS, default="robustness",
                        help="what moves the proposal: robustness (default: the episodes nearest to failing, by the "
                             "task's robustness; the labels alone when the spec states no task) or label")
    parser.add_argument("-o", "--output", type=Path, default=None, help="output folder (default out/falsify-<name>)")
    parser.add_argument("--max-sim-seconds", type=float, default=DEFAULT_MAX_SIM_SECONDS, metavar="S",
                        help="end an episode past S simulated seconds as outcome `timeout`")
    parser.add_argument("--jobs", "-j", type=int, default=1, help="worker processes (default 1)")
    add_executor_arguments(parser)
    parser.add_argument("--include", "-I", action="append", default=[], metavar="DIR", help="also search DIR for imports")
    parser.add_argument("--force", action="store_true", help="replace the scenes of another run in DIR")
    parser.add_argument("--resume", action="store_true",
                        help="continue a killed campaign in DIR (same spec, seed, method, budget and rounds): "
                             "its finished rounds are kept, their scenes redrawn only to rebuild the proposal")


def round_sizes(budget: int, rounds: int) -> list[int]:
    """The budget split into `rounds` near-equal rounds (earlier rounds take the remainder)."""
    base, extra = divmod(budget, rounds)
    return [base + (1 if r < extra else 0) for r in range(rounds) if base + (1 if r < extra else 0) > 0]


def draw_round(sampler: Any, seed: int, start: int, count: int) -> tuple[list[dict], list[dict], dict]:
    """Scenes start..start+count-1 from the proposal: (scene JSON, per-scene weight info, cell masses by site).

    `spec_draw` says the scene came from the spec's own law (the proposal's defensive share, or
    a proposal without components): those scenes alone are plain draws of the target law."""
    scenes, info, masses = [], [], {}
    for index in range(start, start + count):
        result = sampler.sample(seed, index)
        scenes.append(sampler.to_json(result, seed, index))
        state = result.context.proposal if result.context is not None else None
        if state is None:
            info.append({"weight": 1.0, "features": {}, "collision_rejections": 0, "spec_draw": True})
            continue
        masses.update(state.masses)
        info.append({"weight": state.weight(), "features": state.features(),
                     "collision_rejections": int(result.stats.counts.get(COLLISION, 0)),
                     "spec_draw": state.component is None})
    return scenes, info, masses


def round_strata(seed: int, number: int, start: int, size: int) -> Any:
    """Round `number`'s systematic component choice: one offset from its own Generator (not any scene's)."""
    import numpy as np

    from prsc.sampling.proposal import Strata

    return Strata(start, size, float(np.random.default_rng([seed, number, STRATA_STREAM]).random()))


def verdicts(records: Sequence[dict], prop: str | None) -> list[Verdict]:
    """Every record judged against the property (prsc/commands/falsify_property.py)."""
    return [episode_verdict(r, prop) for r in records]


def next_proposal(method: str, steer: str, prop: str | None, proposal: Any, masses: dict, records: list[dict]) -> Any:
    """The proposal for the next round, learnt from every episode so far (the same one under uniform)."""
    from prsc.sampling.proposal_search import Episode, cross_entropy_step, failure_tree_step, near_failures

    if method == "uniform":
        return proposal
    judged = verdicts(records, prop)
    elite = near_failures([v.failed for v in judged], [v.robustness if steer == "robustness" else None for v in judged])
    episodes = [Episode(r["features"], r["weight"], e, v.failed) for r, e, v in zip(records, elite, judged)]
    return (cross_entropy_step if method == "cross-entropy" else failure_tree_step)(proposal, masses, episodes)


RoundRunner = Callable[[int, list[dict], list[dict]], list[dict]]
"""(round number, its scenes, their extras) -> the round's records in index order, each with its extras."""


def falsify_rounds(sampler: Any, seed: int, budget: int, rounds: int, method: str, steer: str, prop: str | None,
                   run_round: RoundRunner) -> tuple[list[dict], Any, dict]:
    """The campaign's rounds on any episode function: (records, the learnt proposal, cell masses by site).

    `sampler` is compiled with a proposal (any: round 0 draws from an empty one, the spec's law
    draw for draw); each later round's proposal is fixed from the earlier rounds' records
    before it draws."""
    from prsc.sampling.proposal import Proposal

    proposal, masses, records, start = Proposal(), {}, [], 0
    for number, size in enumerate(round_sizes(budget, rounds)):
        sampler.set_proposal(replace(proposal, strata=round_strata(seed, number, start, size)) if proposal.components
                             else proposal)
        scenes, info, seen = draw_round(sampler, seed, start, size)
        masses.update(seen)
        records += run_round(number, scenes, [{"round": number, "law": proposal.law, **e} for e in info])
        start += size
        proposal = next_proposal(method, steer, prop, proposal, masses, records)
    return records, proposal, masses


def run(args: argparse.Namespace) -> int:
    """Run the rounds, then write the summary, clusters, plots and the proposal."""
    if args.budget < 1:
        raise PrscError(f"--budget must be >= 1, got {args.budget}")
    if args.rounds < 1:
        raise PrscError(f"--rounds must be >= 1, got {args.rounds}")
    check_seed_and_jobs(args.seed, args.jobs)
    if not args.max_sim_seconds > 0:
        raise PrscError(f"--max-sim-seconds must be > 0, got {args.max_sim_seconds:g}")
    from prsc.runner.gl import choose_gl_backend

    gl_backend = choose_gl_backend()  # before anything imports mujoco
    from rich.console import Console

    from prsc.runner.controller import declared_outcomes, load_controller, parse_target
    from prsc.runner.worker import WorkerConfig
    from prsc.pipeline.campaign import RESULTS, Results, episode_tasks, refuse_foreign_results, run_episodes
    from prsc.commands.compile import compile_scenes
    from prsc.pipeline.executors import executor_from_arguments, worker_count
    from prsc.pipeline.output_folder import folder_before, restore_folder
    from prsc.commands.falsify_report import write_report
    from prsc.files import atomic_write
    from prsc.sampling import compile_sampler
    from prsc.sampling.proposal import Proposal

    source = Path(args.file)
    if source.suffix != ".prs":
        raise PrscError(f"{source}: prsc falsify needs a .prs spec (it draws new scenes every round)")
    controller_ref = parse_target(args.controller)
    controller = load_controller(controller_ref)
    declared = declared_outcomes(controller)
    jobs = worker_count(args.jobs)
    executor = executor_from_arguments(args, jobs, start="spawn")
    out = args.output or Path("out") / f"falsify-{source.stem}"
    refuse_foreign_results(out, "falsify", args.force)
    results = Results(out, {"command": "falsify", "spec": str(source), "seed": args.seed, "method": args.method,
                            "budget": args.budget, "rounds": args.rounds, "controller": args.controller,
                            "property": args.property, "steer": args.steer,
                            "controller_sha256": controller_ref.digest, "max_sim_seconds": args.max_sim_seconds})
    before = folder_before(out)  # put back if the campaign fails before its first episode
    kept: dict[int, dict] = {}
    if args.resume:
        if results.stored_key() is None:
            raise PrscError(f"--resume: {out} holds no prsc falsify campaign to continue")
        if results.stored_key() != results.key:
            raise PrscError(f"--resume: {out} holds another campaign ({results.stored_key()}); resume it with the "
                            "same spec, --seed, --method, --budget, --rounds, --property, --steer, --controller "
                            "and --max-sim-seconds")
        kept = results.recorded()
    (out / "scenes").mkdir(parents=True, exist_ok=True)
    results.begin(kept)
    console = Console(stderr=True)
    config = WorkerConfig(gl_backend, one_raster_thread=jobs > 1 or args.executor == "ray")

    def run_round(number: int, scenes: list[dict], extras: list[dict]) -> list[dict]:
        """Compile the round's scenes and run the controller over them (a killed campaign's records are kept)."""
        start = scenes[0]["index"]
        indices = range(start, start + len(scenes))
        if all(k in results.records for k in indices):  # a finished round of the killed campaign
            console.print(f"round {number}: {len(scenes)} episodes kept from {out / RESULTS}")
            return [results.records[k] for k in indices]
        check = getattr(controller, "check", None)
        if check is not None:
            for scene in scenes:
                check(scene)
        listing = out / "scenes" / f"round_{number:02d}.jsonl"
        atomic_write(listing, "".join(json.dumps(s, separators=(",", ":")) + "\n" for s in scenes))
        root = compile_scenes(str(listing), ["json", "mjcf"], None, args.seed, str(out), jobs=jobs,
                              include_dirs=args.include,
                              executor=executor_from_arguments(args, jobs, start="fork"),
                              force=args.force, assets_dir=str(out / "assets"))
        tasks, _ = episode_tasks(root, None, args.seed, controller_ref, args.max_sim_seconds, first=start)
        run_episodes(executor, config, [t for t in tasks if t.index not in results.records], results.add,
                     extras=lambda index: extras[index - start])
        judged = verdicts([results.records[k] for k in indices], args.property)
        console.print(f"round {number}: {len(scenes)} episodes, {sum(v.failed for v in judged)} failed")
        return [results.records[k] for k in indices]

    # An empty proposal draws exactly as the spec's (sequential) law does, recording where each
    # draw fell (for the clusters). Later rounds swap the proposal into the same compiled sampler.
    try:
        sampler = compile_sampler(str(source), args.include, law="sequential", proposal=Proposal())
        task = sampler.program.task
        check_property(args.property, tuple(f.label for f in task.failures) if task else None)  # before any episode
        _, proposal, masses = falsify_rounds(sampler, args.seed, args.budget, args.rounds, args.method, args.steer,
                                             args.property, run_round)
    except Exception:
        results.close()
        if not results.records:
            restore_folder(before)  # failed before its first episode: the folder as it was
        raise
    results.close()
    records = results.finish()
    atomic_write(out / "proposal.json", json.dumps(proposal.to_json(), indent=1) + "\n")
    table = write_report(records, verdicts(records, args.property), proposal, masses, out,
                         f"{source.name}: falsify ({args.method}, steered by {args.steer}"
                         f"{', property ' + args.property if args.property else ''}), "
                         f"budget {args.budget}, seed {args.seed}", declared)
    print_table(table)
    console.print(f"results in {out / 'results.jsonl'}; proposal in {out / 'proposal.json'}")
    sys.stdout.flush()
    return 0
