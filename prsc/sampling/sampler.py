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
from prsc.constraints.values import DIMENSIONS
from prsc.errors import PrscError
from prsc.ir.program import Program
from prsc.task.bind import bind_task
from prsc.sampling.baseline_sampler import DEFAULT_ATTEMPTS, BaselineSampler
from prsc.sampling.batched import BatchedSampler
from prsc.sampling.candidates import CHUNK, CandidateSampler, Drawn
from prsc.sampling.engine import Limits, SceneResult, SequentialSampler
from prsc.sampling.gibbs import DEFAULT_SWEEPS
from prsc.sampling.group_gibbs import GroupGibbs
from prsc.sampling.proposal import Proposal
from prsc.sampling.runtime import ObjectRuntime
from prsc.sampling.sampler_plan import (
    BASELINE, BATCHED, CANDIDATE_ROUNDS, GIBBS_ROUNDS, HIT_AND_RUN, REJECTION, SamplerPlan, sampler_plan,
)
from prsc.sampling.scene_json import (
    SizedTemplate, json_value, object_template, placed_template, quaternion_wxyz, scene_dict, scene_json, sized_template,
)
from prsc.sampling.scene_text import SceneText, scene_encoder
from prsc.sampling.stats import RejectionStats

SAMPLERS = ("exact", HIT_AND_RUN, BASELINE)
# The law of a scene (docs/sampling.md): the joint one (default), objects one at a time
# (sequential), or the joint one by whole-scene rejection (the exact reference).
LAWS = ("joint", "sequential", REJECTION)
BATCH = 1024  # scenes per batch when drawing many (memory grows with it, not with n)


class Sampler:
    """A compiled spec that samples scenes; `plan` names the path its scenes take and why."""

    def __init__(
        self,
        program: Program,
        sampler: str = "exact",
        *,
        walk_length: int = 100,
        law: str | None = None,
        sweeps: int = DEFAULT_SWEEPS,
        limits: Limits | None = None,
        max_attempts: int = DEFAULT_ATTEMPTS,
        spec: str | None = None,
        constraints: ConstraintProgram | None = None,
        proposal: Proposal | None = None,
        batched: bool = True,
    ) -> None:
        if sampler == "rejection":
            raise PrscError("--sampler rejection is now --sampler baseline (the paper's naive baseline); "
                            "the joint law by whole-scene rejection is --law rejection")
        if proposal is not None and (sampler != "exact" or law not in (None, "sequential")):
            raise PrscError("--proposal draws with the exact sequential sampler (not with --sampler or another --law)")
        if sampler not in SAMPLERS:
            raise PrscError(f"unknown sampler {sampler!r} (choose from {', '.join(SAMPLERS)})")
        if walk_length < 1:
            raise PrscError(f"the hit-and-run walk length must be >= 1, got {walk_length}")
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
        # Objects whose properties never change get their JSON built once.
        self.templates: list[dict[str, Any] | None] = [
            object_template(plan.name, plan.class_name, plan.static_props, plan.span) if set(plan.property_fns) <= set(plan.static_props) else None
            for plan in self.constraints.objects
        ]
        # Objects whose properties change only in size (a part of random size) get all the rest built once.
        self._sized: list[dict[str, Any] | SizedTemplate | None] = [
            template if template is not None else sized_template(plan.name, plan.class_name, plan.static_props, plan.span)
            if set(plan.property_fns) - set(plan.static_props) <= set(DIMENSIONS) else None
            for template, plan in zip(self.templates, self.constraints.objects)
        ]
        self.classes: dict[str, list[str]] = {o.class_name: list(o.class_chain[1:]) for o in program.objects}
        self._engine: SequentialSampler | BaselineSampler
        if sampler == BASELINE:
            self._engine = BaselineSampler(self.constraints, max_attempts)
        else:
            self._engine = SequentialSampler(
                self.constraints, sampler, walk_length, law == REJECTION, limits, proposal, sweeps if law == "joint" else 0
            )
        self.runtimes: list[ObjectRuntime] = self._engine.runtimes
        self.plan: SamplerPlan = sampler_plan(self.constraints, self.runtimes, sampler, law, sweeps, proposal is not None, batched)
        # What the plan's path draws with (the sequential sampler `_engine` draws every other path,
        # and the scenes candidate rounds give up on).
        self._batch = BatchedSampler(self.plan.batch) if self.plan.batch is not None else None
        self._candidates = CandidateSampler(self.plan.candidates, self.constraints, self.runtimes) \
            if self.plan.candidates is not None else None
        self._group = GroupGibbs(self.plan.group, self.constraints, self.runtimes, self.plan.sweeps) \
            if self.plan.group is not None else None
        self._text: SceneText | None = None  # the batched spec's JSON line template, built on first use
        if self._batch is not None:  # batched objects keep one rotation in every scene
            self._quaternions = [quaternion_wxyz(o.rotation) for o in self._batch.plan.objects]

    @property
    def batched(self) -> bool:
        """Whether scenes are drawn in batches (`plan.why` says why not)."""
        return self.plan.path == BATCHED

    @property
    def chunked(self) -> bool:
        """Whether `results` draws many scenes at once (candidate or Gibbs rounds)."""
        return self.plan.chunked

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
        return self.results(seed, [index])[0]

    def results(self, seed: int, indices: Sequence[int]) -> list[SceneResult]:
        """Scenes `indices` under `seed` with their statistics (candidate and Gibbs rounds draw them at once)."""
        path = self.plan.path
        if path == BATCHED:
            assert self._batch is not None
            state = self._batch.draw(seed, indices)
            params = self._batch.params(state)
            return [self._batch_result(state, i, params[i]) for i in range(len(indices))]
        if path == CANDIDATE_ROUNDS:
            assert self._candidates is not None
            return [self._settle(drawn, seed, index) for drawn, index in zip(self._candidates.draw(seed, indices), indices)]
        if path == GIBBS_ROUNDS:
            assert self._group is not None
            return self._group.draw(seed, indices)
        return [self._engine.sample(seed, index) for index in indices]

    def _batch_result(self, state: Any, i: int, params: dict[str, Any]) -> SceneResult:
        """Scene i of a batch as the sequential sampler returns it."""
        assert self._batch is not None
        objects, ctx = self._batch.objects(state, i, self.runtimes)
        return SceneResult(objects, params, RejectionStats(scenes=1), ctx)

    def each_result(self, seed: int, indices: Sequence[int]) -> Iterator[tuple[int, SceneResult]]:
        """(index, result) for scenes `indices`, lazily: a chunk of scenes at a time on a chunked or
        batched path, else one at a time."""
        step = {CANDIDATE_ROUNDS: CHUNK, BATCHED: BATCH}.get(self.plan.path, 1) if self._group is None else self._group.chunk
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
        return self.batch(seed, [index])[0]

    def batch(self, seed: int, indices: Sequence[int]) -> list[dict[str, Any]]:
        """Scenes `indices` under `seed` as scene JSON, drawn at once on a batched or chunked path."""
        if self.plan.path != BATCHED:
            return [self.to_json(result, seed, index) for result, index in zip(self.results(seed, indices), indices)]
        scene = self._batch_scenes(seed, indices)
        return [scene(i) for i in range(len(indices))]

    def _batch_scenes(self, seed: int, indices: Sequence[int]) -> Callable[[int], dict[str, Any]]:
        """Draw scenes `indices` as one batch; i -> the JSON of the i-th, made when asked for (a drawer
        holding many keeps a few arrays, not thousands of dicts for the garbage collector to walk)."""
        assert self._batch is not None
        state = self._batch.draw(seed, indices)
        names = [o.name for o in self._batch.plan.objects]
        positions = [state.positions[name].tolist() for name in names]
        spec, seed, classes = self.spec, int(seed), self.classes
        parts = list(zip(self.templates, positions, self._quaternions))
        values = self._batch.params(state)

        def scene(i: int) -> dict[str, Any]:
            params = {"ground": True}
            params.update({k: json_value(v) for k, v in values[i].items()})
            objects = [placed_template(t, p[i], list(q)) for t, p, q in parts]  # type: ignore[arg-type]
            return self._with_task(scene_dict(spec, seed, int(indices[i]), params, objects, classes))

        return scene

    def to_json(self, result: SceneResult, seed: int, index: int) -> dict[str, Any]:
        """The scene JSON of a sampled scene (for callers that also keep its statistics)."""
        return self._with_task(scene_json(self.spec, int(seed), int(index), result.params, result.objects,
                                          self._sized, self.classes))

    def _with_task(self, scene: dict[str, Any]) -> dict[str, Any]:
        """The scene with its compiled task (key "task", docs/tasks.md) when the spec states one."""
        if self.program.task:
            scene["task"] = bind_task(self.program.task, scene).to_json()
        return scene

    def drawer(self, seed: int, ahead: int = 64, grow_to: int | None = None) -> Callable[[int], dict[str, Any]]:
        """index -> scene JSON under `seed`; a batched or chunked path draws the next indices at once
        and hands them out as asked (a compile worker's chunk of consecutive scenes), each scene once.
        With `grow_to`, each draw after the first takes twice as many as the last, up to `grow_to`
        (a reset loop: its first scene soon, then the rate of large batches); scene k is the same."""
        path = self.plan.path
        if path != BATCHED and not self.plan.chunked:
            return functools.partial(self.scene, seed)
        drawn: dict[int, Any] = {}  # index -> what makes its scene JSON or result (batched, Gibbs rounds), or a Drawn
        size = [ahead]  # how many the next draw takes

        def scene(index: int) -> dict[str, Any]:
            if index not in drawn:
                drawn.clear()
                # Candidate rounds and sweeps take 16 ahead: a worker asked for a few scenes draws few more.
                # Batches and Gibbs rounds take all `ahead`: their cost is numpy calls per round, not scenes.
                wide = path in (BATCHED, GIBBS_ROUNDS)
                chunk = range(index, index + (size[0] if wide else min(size[0], 16)))
                if grow_to is not None:
                    size[0] = max(size[0], min(2 * size[0], grow_to))
                # They hand over results, each made JSON (or its error raised) only when asked for: a scene
                # that cannot be written does not take the scenes before it in the chunk with it.
                if path == BATCHED:
                    made = self._batch_scenes(seed, chunk)
                    drawn.update((index, functools.partial(made, i)) for i, index in enumerate(chunk))
                elif path == CANDIDATE_ROUNDS:
                    assert self._candidates is not None
                    drawn.update(zip(chunk, self._candidates.draw(seed, chunk)))
                elif path == GIBBS_ROUNDS:
                    assert self._group is not None
                    drawn.update(zip(chunk, self._group.draw_lazily(seed, chunk)))
                else:
                    drawn.update(zip(chunk, self.results(seed, chunk)))
            value = drawn.pop(index)
            if path == GIBBS_ROUNDS:
                return self.to_json(value(), seed, index)
            return value() if path == BATCHED else self.to_json(self._settle(value, seed, index), seed, index)

        return scene

    def batch_lines(self, seed: int, indices: Sequence[int]) -> list[str]:
        """Scenes `indices` under `seed` as scene JSON lines, each ending in a newline (what `prsc sample` writes)."""
        encode = scene_encoder()
        if self.plan.path != BATCHED or not self._batch.plan.fixed_params:  # type: ignore[union-attr]
            return [encode(scene) + "\n" for scene in self.batch(seed, indices)]
        assert self._batch is not None
        objects = self._batch.plan.objects
        if self._text is None:
            self._text = SceneText(self.batch(0, [0])[0], [k for k, o in enumerate(objects) if o.fixed is None], encode)
        state = self._batch.draw(seed, indices)
        return self._text.lines(int(seed), indices, [state.positions[o.name] for o in objects])

    def scenes(self, seed: int, indices: Iterable[int] | int, start: int = 0) -> Iterator[dict[str, Any]]:
        """Scenes `indices` (or `start .. start+n-1` for an int n) under `seed`, lazily, in batches."""
        chosen = range(start, start + indices) if isinstance(indices, int) else indices
        if self.plan.path != BATCHED and not self.plan.chunked:
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
    """Compile a .prs file into a Sampler (opts: walk_length, law, sweeps, limits, max_attempts, proposal, batched)."""
    from prsc.ir import compile_program

    program = compile_program(path, include_dirs)
    return Sampler(program, sampler, spec=str(path), **opts)


def scene_sampler(
    path: str | os.PathLike[str], seed: int, include_dirs: Sequence[str | os.PathLike[str]] = (), sampler: str = "exact", **opts: Any
) -> Callable[[int], dict[str, Any]]:
    """A function index -> scene JSON of `path` under `seed` (for workers that draw by index)."""
    return functools.partial(compile_sampler(path, include_dirs, sampler, **opts).scene, int(seed))
