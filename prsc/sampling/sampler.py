"""The library entry point: compile a spec once, then draw scene JSON by (seed, index).

    sampler = compile_sampler("specs/table_cube.prs")
    scene = sampler.scene(seed=0, index=7)          # one scene JSON dict
    for scene in sampler.scenes(seed=0, n=100): ...  # scenes 0..99

Scene k depends only on (spec, seed, k): the same whatever n, order or worker count.
"""

from __future__ import annotations

import functools
import os
from typing import Any, Callable, Iterator, Sequence

from prsc.constraints.lower import lower_program
from prsc.constraints.model import ConstraintProgram
from prsc.errors import PrscError
from prsc.ir.program import Program
from prsc.sampling.gibbs import DEFAULT_SWEEPS
from prsc.sampling.engine import Limits, SceneResult, SequentialSampler
from prsc.sampling.proposal import Proposal
from prsc.sampling.rejection import DEFAULT_ATTEMPTS, RejectionSampler
from prsc.sampling.scene_json import object_template, scene_json

SAMPLERS = ("exact", "hit-and-run", "rejection")
# The law of a scene (docs/sampling.md): the joint one by Gibbs sweeps (default), objects one
# at a time (sequential), or the joint one by whole-scene rejection (the exact reference).
LAWS = ("joint", "sequential", "rejection")


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

    def set_proposal(self, proposal: Proposal) -> None:
        """Draw the next scenes from `proposal` instead (a sampler built with one), keeping the compiled spec and its cut cells."""
        if not isinstance(self._engine, SequentialSampler) or self._engine.proposal is None:
            raise PrscError("only a sampler built with a proposal draws from another one")
        self._engine.proposal = proposal

    def sample(self, seed: int, index: int) -> SceneResult:
        """Scene `index` under `seed` with its rejection statistics."""
        return self._engine.sample(seed, index)

    def scene(self, seed: int, index: int) -> dict[str, Any]:
        """Scene `index` under `seed` as scene JSON (docs/scene-json.md)."""
        return self.to_json(self._engine.sample(seed, index), seed, index)

    def to_json(self, result: SceneResult, seed: int, index: int) -> dict[str, Any]:
        """The scene JSON of a sampled scene (for callers that also keep its statistics)."""
        return scene_json(self.spec, int(seed), int(index), result.params, result.objects, self.templates, self.classes)

    def scenes(self, seed: int, n: int, start: int = 0) -> Iterator[dict[str, Any]]:
        """Scenes start .. start+n-1 under `seed`, lazily."""
        for index in range(start, start + n):
            yield self.scene(seed, index)


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
