"""The library entry point: compile a spec once, then draw scene JSON by (seed, index).

    sampler = compile_sampler("specs/table_cube.prs")
    scene = sampler.scene(seed=0, index=7)          # one scene JSON dict
    for scene in sampler.scenes(seed=0, indices=100): ...  # scenes 0..99

Scene k depends only on (spec, seed, k): the same whatever n, order, batch or worker count.
A spec whose plan allows it is drawn in batches (batched.py), vectorised over scenes.
"""

from __future__ import annotations

import functools
import os
from typing import Any, Callable, Iterable, Iterator, Sequence

from prsc.constraints.lower import lower_program
from prsc.constraints.polytope_ir import ConstraintProgram
from prsc.errors import PrscError
from prsc.ir.program import Program
from prsc.sampling.batch_values import Unbatchable
from prsc.sampling.batched import BatchedSampler, batch_plan
from prsc.sampling.candidate_plan import candidate_plan
from prsc.sampling.candidates import CHUNK, CandidateSampler, Drawn
from prsc.sampling.gibbs import DEFAULT_SWEEPS
from prsc.sampling.group_gibbs import SWEEPS as GROUP_SWEEPS, GroupGibbs, group_plan
from prsc.sampling.engine import Limits, SceneResult, SequentialSampler
from prsc.sampling.proposal import Proposal
from prsc.sampling.rejection import DEFAULT_ATTEMPTS, RejectionSampler
from prsc.sampling.scene_json import json_value, object_template, placed_template, quaternion_wxyz, scene_dict, scene_json
from prsc.sampling.scene_text import SceneText, scene_encoder
from prsc.sampling.stats import RejectionStats

SAMPLERS = ("exact", "hit-and-run", "rejection")
# The law of a scene (docs/sampling.md): the joint one by Gibbs sweeps (default), objects one
# at a time (sequential), or the joint one by whole-scene rejection (the exact reference).
LAWS = ("joint", "sequential", "rejection")
BATCH = 1024  # scenes per batch when drawing many (memory grows with it, not with n)


class Sampler:
    """A compiled spec that samples scenes."""

    def __init__(
        self,
        program: Program,
        sampler: str = "exact",
        *,
        walk_length: int = 100,
        joint: bool = False,
        law: str | None = None,
        sweeps: int = DEFAULT_SWEEPS,
        limits: Limits | None = None,
        max_attempts: int = DEFAULT_ATTEMPTS,
        spec: str | None = None,
        constraints: ConstraintProgram | None = None,
        proposal: Proposal | None = None,
        batched: bool = True,
    ) -> None:
        if proposal is not None and (sampler != "exact" or joint or law not in (None, "sequential")):
            raise PrscError("--proposal draws with the exact sequential sampler (not with --sampler, --joint or another --law)")
        if sampler not in SAMPLERS:
            raise PrscError(f"unknown sampler {sampler!r} (choose from {', '.join(SAMPLERS)})")
        if walk_length < 1:
            raise PrscError(f"the hit-and-run walk length must be >= 1, got {walk_length}")
        if joint and law not in (None, "rejection"):
            raise PrscError(f"--joint is --law rejection: it does not combine with --law {law}")
        law = "rejection" if joint else law  # `joint=True` is the older spelling
        if law is None:  # Gibbs sweeps need exact draws: hit-and-run (the paper's sampler) stays
            # sequential, and a falsification proposal reweights the sequential law (proposal.py)
            law = "joint" if proposal is None and sampler == "exact" else "sequential"
        if law not in LAWS:
            raise PrscError(f"unknown law {law!r} (choose from {', '.join(LAWS)})")
        if sweeps < 1:
            raise PrscError(f"the number of Gibbs sweeps must be >= 1, got {sweeps}")
        self.law = law
        self.program = program
        self.method = sampler
        self.spec = spec if spec is not None else program.path
        self.constraints = constraints if constraints is not None else lower_program(program)
        self._engine: SequentialSampler | RejectionSampler
        # Objects whose properties never change get their JSON built once.
        self.templates: list[dict[str, Any] | None] = [
            object_template(plan.name, plan.class_name, plan.static_props, plan.span) if set(plan.property_fns) <= set(plan.static_props) else None
            for plan in self.constraints.objects
        ]
        self.classes: dict[str, list[str]] = {o.class_name: list(o.class_chain[1:]) for o in program.objects}
        if sampler == "rejection":
            self._engine = RejectionSampler(self.constraints, max_attempts)
        else:
            self._engine = SequentialSampler(
                self.constraints, sampler, walk_length, law == "rejection", limits, proposal, sweeps if law == "joint" else 0
            )
        # The batched sampler draws the same law (batched.py) from its own stream: every exact
        # sequential or joint spec it can prove batchable (`batched=False`: one scene at a time).
        self._batch: BatchedSampler | None = None
        self._text: SceneText | None = None  # the batched spec's JSON line template, built on first use
        self.unbatched_because = "not asked for" if not batched else "only the exact sampler's sequential and joint laws batch"
        if batched and isinstance(self._engine, SequentialSampler) and sampler == "exact" and law != "rejection" \
                and proposal is None:
            try:
                self._batch = BatchedSampler(batch_plan(self.constraints, self._engine.runtimes))
                self.unbatched_because = ""
                # Batched objects keep one rotation in every scene.
                self._quaternions = [quaternion_wxyz(o.rotation) for o in self._batch.plan.objects]
            except Unbatchable as reason:
                self.unbatched_because = str(reason)
        # The joint law of a spec that does not batch: whole-scene rejection vectorised over
        # candidates (candidates.py), Gibbs sweeps for the scenes where no candidate passes.
        self._planned: CandidateSampler | None = None
        self._group: GroupGibbs | None = None  # a packed spec's sweeps over many scenes, when the pilot fails
        self._sweeps = sweeps
        self._paying: bool | None = None  # whether candidate rounds pay: decided by a pilot on first use
        self.no_candidates_because = "" if self._batch is not None else "not the joint law of the exact sampler"
        if self._batch is None and batched and isinstance(self._engine, SequentialSampler) and sampler == "exact" \
                and law == "joint" and proposal is None:
            try:
                runtimes = self._engine.runtimes
                self._planned = CandidateSampler(candidate_plan(self.constraints, runtimes), self.constraints, runtimes)
                self.no_candidates_because = ""
            except Unbatchable as reason:
                self.no_candidates_because = str(reason)

    @property
    def _candidates(self) -> CandidateSampler | None:
        """The candidate sampler when candidate rounds draw this spec: planned, and paying (its pilot
        draws scenes, so it runs when scenes are first asked for, not when a spec is checked)."""
        if self._planned is None:
            return None
        if self._paying is None:
            self._paying = self._planned.pays()
            if not self._paying:
                self.no_candidates_because = "too few candidates pass (a pilot of 8 scenes found fewer than 4)"
                # A packed spec of fixed boxes: the Gibbs sweeps vectorised over scenes (group_gibbs.py).
                try:
                    objects = group_plan(self._planned.plan, self._planned.runtimes)
                    sweeps = max(GROUP_SWEEPS, self._sweeps)
                    self._group = GroupGibbs(objects, self.constraints, self._planned.runtimes, sweeps)
                except Unbatchable as reason:
                    self.no_candidates_because += f"; Gibbs sweeps one scene at a time: {reason}"
        return self._planned if self._paying else None

    @property
    def gibbs_rounds(self) -> bool:
        """Whether the joint law is drawn by Gibbs sweeps vectorised over scenes (group_gibbs.py)."""
        return self._candidates is None and self._group is not None

    @property
    def chunked(self) -> bool:
        """Whether `results` draws many scenes at once (candidate rounds or vectorised Gibbs sweeps)."""
        return self._candidates is not None or self._group is not None

    @property
    def candidates(self) -> bool:
        """Whether the joint law is drawn by candidate rounds first (`no_candidates_because` says why not)."""
        return self._candidates is not None

    @property
    def batched(self) -> bool:
        """Whether scenes are drawn in batches (`unbatched_because` says why not)."""
        return self._batch is not None

    @property
    def proposal(self) -> Proposal | None:
        """The proposal the next scenes are drawn from (None: a sampler built without one)."""
        return getattr(self._engine, "proposal", None)

    def set_proposal(self, proposal: Proposal) -> None:
        """Draw the next scenes from `proposal` instead (a sampler built with one), keeping the compiled spec and its cut cells."""
        if not isinstance(self._engine, SequentialSampler) or self._engine.proposal is None:
            raise PrscError("only a sampler built with a proposal draws from another one")
        self._engine.proposal = proposal

    def sample(self, seed: int, index: int) -> SceneResult:
        """Scene `index` under `seed` with its rejection statistics."""
        if self._batch is None:
            return self.results(seed, [index])[0]
        state = self._batch.draw(seed, [index])
        objects, ctx = self._batch.objects(state, 0, self._engine.runtimes)  # type: ignore[union-attr]
        return SceneResult(objects, self._batch.params(state)[0], RejectionStats(scenes=1), ctx)

    def results(self, seed: int, indices: Sequence[int]) -> list[SceneResult]:
        """Scenes `indices` under `seed` with their statistics (an unbatched spec; candidate rounds at once)."""
        if self._candidates is None:
            if self._group is not None:
                return self._group.draw(seed, indices)
            return [self._engine.sample(seed, index) for index in indices]
        return [self._settle(drawn, seed, index) for drawn, index in zip(self._candidates.draw(seed, indices), indices)]

    def each_result(self, seed: int, indices: Sequence[int]) -> Iterator[tuple[int, SceneResult]]:
        """(index, result) for scenes `indices` of an unbatched spec, lazily: a chunk of scenes at a time
        when candidate rounds or vectorised sweeps draw them, else one at a time."""
        step = CHUNK if self.chunked else 1
        for first in range(0, len(indices), step):
            chunk = indices[first:first + step]
            yield from zip(chunk, self.results(seed, chunk))

    def _settle(self, drawn: Drawn, seed: int, index: int) -> SceneResult:
        """A candidate round's scene: itself, its error raised, or (no candidate passed) the Gibbs sampler's."""
        if isinstance(drawn, PrscError):
            raise drawn
        return self._engine.sample(seed, index) if drawn is None else drawn

    def scene(self, seed: int, index: int) -> dict[str, Any]:
        """Scene `index` under `seed` as scene JSON (docs/scene-json.md)."""
        if self._batch is not None:
            return self.batch(seed, [index])[0]
        return self.to_json(self.sample(seed, index), seed, index)

    def batch(self, seed: int, indices: Sequence[int]) -> list[dict[str, Any]]:
        """Scenes `indices` under `seed` as scene JSON, drawn at once when the spec is batched."""
        if self._batch is None:
            return [self.to_json(result, seed, index) for result, index in zip(self.results(seed, indices), indices)]
        state = self._batch.draw(seed, indices)
        names = [o.name for o in self._batch.plan.objects]
        positions = [state.positions[name].tolist() for name in names]
        spec, seed, classes = self.spec, int(seed), self.classes
        parts = list(zip(self.templates, positions, self._quaternions))
        out = []
        for i, (index, values) in enumerate(zip(indices, self._batch.params(state))):
            params = {"ground": True}
            params.update({k: json_value(v) for k, v in values.items()})
            objects = [placed_template(t, p[i], list(q)) for t, p, q in parts]  # type: ignore[arg-type]
            out.append(scene_dict(spec, seed, int(index), params, objects, classes))
        return out

    def to_json(self, result: SceneResult, seed: int, index: int) -> dict[str, Any]:
        """The scene JSON of a sampled scene (for callers that also keep its statistics)."""
        return scene_json(self.spec, int(seed), int(index), result.params, result.objects, self.templates, self.classes)

    def drawer(self, seed: int, ahead: int = 64) -> Callable[[int], dict[str, Any]]:
        """index -> scene JSON under `seed`; a batched spec draws the next `ahead` indices at once and
        hands them out as asked (a compile worker's chunk of consecutive scenes), each scene once."""
        drawn: dict[int, Any] = {}  # index -> scene JSON (batched) or a candidate round's Drawn

        def scene(index: int) -> dict[str, Any]:
            if self._batch is None and not self.chunked:
                return self.scene(seed, index)
            if index not in drawn:
                drawn.clear()
                # Candidate rounds and sweeps take 16 ahead: a worker asked for a few scenes draws few more.
                chunk = range(index, index + (ahead if self._batch is not None else min(ahead, 16)))
                # They hand over results, each made JSON (or its error raised) only when asked for: a scene
                # that cannot be written does not take the scenes before it in the chunk with it.
                if self._batch is not None:
                    drawn.update(zip(chunk, self.batch(seed, chunk)))
                elif self._candidates is not None:
                    drawn.update(zip(chunk, self._candidates.draw(seed, chunk)))
                else:
                    drawn.update(zip(chunk, self.results(seed, chunk)))
            value = drawn.pop(index)
            return value if self._batch is not None else self.to_json(self._settle(value, seed, index), seed, index)

        return scene

    def batch_lines(self, seed: int, indices: Sequence[int]) -> list[str]:
        """Scenes `indices` under `seed` as scene JSON lines, each ending in a newline (what `prsc sample` writes)."""
        encode = scene_encoder()
        if self._batch is None or not self._batch.plan.fixed_params:
            return [encode(scene) + "\n" for scene in self.batch(seed, indices)]
        objects = self._batch.plan.objects
        if self._text is None:
            self._text = SceneText(self.batch(0, [0])[0], [k for k, o in enumerate(objects) if o.fixed is None], encode)
        state = self._batch.draw(seed, indices)
        return self._text.lines(int(seed), indices, [state.positions[o.name] for o in objects])

    def scenes(self, seed: int, indices: Iterable[int] | int, start: int = 0) -> Iterator[dict[str, Any]]:
        """Scenes `indices` (or `start .. start+n-1` for an int n) under `seed`, lazily, in batches."""
        chosen = range(start, start + indices) if isinstance(indices, int) else indices
        if self._batch is None and not self.chunked:
            for index in chosen:
                yield self.scene(seed, index)
            return
        chunk: list[int] = []
        for index in chosen:
            chunk.append(index)
            if len(chunk) == BATCH:
                yield from self.batch(seed, chunk)
                chunk = []
        if chunk:
            yield from self.batch(seed, chunk)


def compile_sampler(
    path: str | os.PathLike[str], include_dirs: Sequence[str | os.PathLike[str]] = (), sampler: str = "exact", **opts: Any
) -> Sampler:
    """Compile a .prs file into a Sampler (opts: walk_length, law, sweeps, joint, limits, max_attempts, proposal)."""
    from prsc.ir import compile_program

    program = compile_program(path, include_dirs)
    return Sampler(program, sampler, spec=str(path), **opts)


def scene_sampler(
    path: str | os.PathLike[str], seed: int, include_dirs: Sequence[str | os.PathLike[str]] = (), sampler: str = "exact", **opts: Any
) -> Callable[[int], dict[str, Any]]:
    """A function index -> scene JSON of `path` under `seed` (for workers that draw by index)."""
    return functools.partial(compile_sampler(path, include_dirs, sampler, **opts).scene, int(seed))
