"""The sampler plan: which path draws a spec's scenes, and why (docs/sampling.md, "Which path").

Decided once per compiled spec, in one place, as a frozen value; every Sampler method
dispatches on its `path`, and `prsc explain` prints it. The paths:

- **batched**: objects that never interact, drawn many scenes at a time (batched.py);
- **candidate rounds**: the joint law by whole-scene rejection vectorised over candidate
  scenes (candidates.py), the sequential sampler and its sweeps for a scene none passes;
- **Gibbs rounds**: the joint law by Gibbs sweeps vectorised over scenes (group_gibbs.py);
- **sequential + sweeps**: the joint law by the scalar Gibbs sweeps over a sequential sample (gibbs.py);
- **sequential**: the sequential law, one object at a time (engine.py);
- **hit-and-run**: the paper's sampler (the sequential law, each draw a walk);
- **rejection**: the joint law by whole-scene rejection, one scene at a time (`--law rejection`: the exact reference);
- **baseline**: the paper's naive baseline (`--sampler baseline`, baseline_sampler.py).

Where candidate rounds could draw a spec, a pilot decides whether they pay: 8 scenes of a
fixed pilot seed, read from the counter stream under that seed alone, so it draws no
scene's numbers and shifts no scene's stream; it is part of building the plan, so every
run (any -n, batch, --jobs or Ray worker) decides the same. Where Gibbs rounds could draw
it too and candidates pass often enough, the same 8 pilot scenes are drawn by Gibbs rounds
and the costs per scene of the two paths are weighed (path_costs.py).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

from prsc.constraints.polytope_ir import ConstraintProgram
from prsc.sampling.batch_values import Unbatchable
from prsc.sampling.batched import BatchPlan, batch_plan
from prsc.sampling.candidate_plan import CandidatePlan, candidate_plan
from prsc.sampling.candidates import BUDGET, PILOT_SCENES, PILOT_SEED, CandidateSampler
from prsc.sampling.group_gibbs import GroupGibbs
from prsc.sampling.group_members import GroupObject, group_plan, group_sweeps
from prsc.sampling.path_costs import path_costs
from prsc.sampling.runtime import ObjectRuntime

BATCHED = "batched"
CANDIDATE_ROUNDS = "candidate rounds"
GIBBS_ROUNDS = "Gibbs rounds"
SWEEPS = "sequential + sweeps"
SEQUENTIAL = "sequential"
HIT_AND_RUN = "hit-and-run"
REJECTION = "rejection"
BASELINE = "baseline"
PATHS = (BATCHED, CANDIDATE_ROUNDS, GIBBS_ROUNDS, SWEEPS, SEQUENTIAL, HIT_AND_RUN, REJECTION, BASELINE)
CHUNKED = (CANDIDATE_ROUNDS, GIBBS_ROUNDS)  # paths that draw many scenes per call, one at a time otherwise


@dataclass(frozen=True, eq=False)
class SamplerPlan:
    """The path a spec's scenes take, why, and what that path needs."""

    path: str
    why: str
    law: str  # joint | sequential | rejection
    batch: BatchPlan | None = None  # batched
    candidates: CandidatePlan | None = None  # candidate rounds
    group: tuple[GroupObject, ...] | None = None  # Gibbs rounds
    sweeps: int = 0  # the scalar chain's sweeps (sequential + sweeps, and candidate rounds' fallback); Gibbs rounds' own

    @property
    def chunked(self) -> bool:
        """Whether scenes are drawn many at a time by a chunked path (candidate or Gibbs rounds)."""
        return self.path in CHUNKED

    def describe(self) -> str:
        """One line: the path and why (what `prsc explain` prints)."""
        return f"path: {self.path} ({self.why})"


def sampler_plan(
    cprog: ConstraintProgram, runtimes: Sequence[ObjectRuntime], method: str, law: str, sweeps: int,
    proposal: bool, batched: bool,
) -> SamplerPlan:
    """The plan of a lowered spec for one sampler, law and options (the candidate pilot runs here)."""
    if method == BASELINE:
        return SamplerPlan(BASELINE, "--sampler baseline: the paper's naive baseline", law)
    if method == HIT_AND_RUN:  # its draws are walks: the sweeps and rejection of its law run one scene at a time
        return SamplerPlan(HIT_AND_RUN, f"--sampler hit-and-run: the paper's sampler, under the {law} law", law,
                           sweeps=sweeps if law == "joint" else 0)
    if law == REJECTION:
        return SamplerPlan(REJECTION, "--law rejection: the joint law by whole-scene rejection, the exact reference", law)
    if proposal:
        return SamplerPlan(SEQUENTIAL, "a falsification proposal reweights the sequential law", law)
    joint_sweeps = sweeps if law == "joint" else 0
    if not batched:
        why = "one scene at a time asked for (batched=False)"
        return SamplerPlan(SWEEPS if joint_sweeps else SEQUENTIAL, why, law, sweeps=joint_sweeps)
    try:
        return SamplerPlan(BATCHED, "no two objects interact and every value vectorises", law, batch=batch_plan(cprog, runtimes))
    except Unbatchable as reason:
        unbatched = f"not batched: {reason}"
    if law != "joint":
        return SamplerPlan(SEQUENTIAL, f"--law sequential; {unbatched}", law)
    try:
        plan = candidate_plan(cprog, runtimes)
    except Unbatchable as reason:
        return SamplerPlan(SWEEPS, f"{unbatched}; no candidate rounds: {reason}", law, sweeps=sweeps)
    try:
        group: tuple[GroupObject, ...] | None = group_plan(plan, runtimes)
    except Unbatchable as reason:
        group, no_group = None, reason
    # Where Gibbs rounds could draw it too, the pilot draws every candidate a scene would: what candidates cost.
    pilot = CandidateSampler(plan, cprog, runtimes).pilot((BUDGET,) if group is not None else (16, BUDGET))
    few = "too few candidates pass (a pilot of 8 scenes found fewer than 4)"
    if pilot.pays and group is None:
        return SamplerPlan(CANDIDATE_ROUNDS, f"{unbatched}; whole-scene candidates pass often enough (the pilot)",
                           law, candidates=plan, sweeps=sweeps)
    if group is None:
        return SamplerPlan(SWEEPS, f"{unbatched}; {few}; no Gibbs rounds: {no_group}", law, sweeps=sweeps)
    rounds = group_sweeps(group, sweeps)
    if pilot.pays:
        rows = GroupGibbs(group, cprog, runtimes, rounds).pilot_rows(PILOT_SEED, range(PILOT_SCENES))
        costs = path_costs(pilot, len(plan.objects), rows, PILOT_SCENES)
        if not costs.gibbs_pays:
            return SamplerPlan(CANDIDATE_ROUNDS, f"{unbatched}; whole-scene candidates pass often enough: "
                               f"{costs.describe()} (the pilots)", law, candidates=plan, sweeps=sweeps)
        few = f"whole-scene candidates pass, but {costs.describe()} (the pilots)"
    drawn = [o.name for o in group if o.drawn is not None]
    afresh = f"; {', '.join(drawn)} drawn afresh in each update (their size or yaw changes between scenes)" if drawn else ""
    return SamplerPlan(GIBBS_ROUNDS, f"{unbatched}; {few}; {rounds} sweeps{afresh}{_inside(group)}", law, group=group,
                       sweeps=rounds)


def _inside(group: tuple[GroupObject, ...]) -> str:
    """Which objects lie in their anchor's box, so that the anchor's tests against objects outside decide for them."""
    by_anchor: dict[str, list[GroupObject]] = {}
    for obj in group:
        if obj.inside and obj.anchor is not None:
            by_anchor.setdefault(obj.anchor, []).append(obj)
    return "".join(f"; {', '.join(o.name for o in inside)} lie in {anchor}'s box, whose tests against "
                   f"{', '.join(sorted({group[j].name for o in inside for j in o.inside}))} decide for them"
                   for anchor, inside in by_anchor.items())
