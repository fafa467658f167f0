"""The paper's naive baseline (`--sampler baseline`): whole-scene rejection from base regions.

Each object's position is drawn uniformly from its base region: the workspace's bounding
box, cut by its equalities (`at`, `aligned with`, ...) and, for `on X`, X's surface (as
the original sampled `on`). Every other relation is a test on that draw: containment
(`completely`, `in`, the workspace, `[not] visible from`), relative position (`left of`,
...), collisions with the objects before it, and every `require` (none is lowered here).
The first failed test rejects the whole scene, counted by cause as in the paper's Table II.
"""

from __future__ import annotations

from prsc.constraints.context import SceneContext
from prsc.constraints.diagnostics import numeric_failure
from prsc.constraints.polytope_ir import COLLISION, CONTAINMENT, REQUIRE, ConstraintProgram, RequireCheck, RowLabel
from prsc.errors import PrscError
from prsc.geometry.exceptions import EmptyRegionError, GeometryError, UnboundedRegionError
from prsc.sampling.baseline import baseline_region
from prsc.sampling.collisions import PlacedBox, first_hit, near
from prsc.sampling.engine import SceneResult
from prsc.sampling.prepared_regions import RegionProvider, violated_rule
from prsc.sampling.runtime import build_runtimes, draw_soft_requires, evaluate_params, inside_any
from prsc.sampling.seeds import scene_rng
from prsc.sampling.stats import RejectionStats

DEFAULT_ATTEMPTS = 1_000_000


class BaselineSampler:
    """Whole-scene rejection from base regions, counting rejections by cause."""

    def __init__(self, cprog: ConstraintProgram, max_attempts: int = DEFAULT_ATTEMPTS) -> None:
        self.cprog = cprog
        self.max_attempts = int(max_attempts)
        self.runtimes = build_runtimes(cprog)
        self.base_providers = [RegionProvider(baseline_region(cprog, plan)) for plan in cprog.objects]
        # Requires to test after each object (all of them: nothing is lowered here).
        after: list[list[RequireCheck]] = [[] for _ in self.runtimes]
        self._scene_tests: list[RequireCheck] = []
        for last, check in cprog.require_tests:
            (after[last] if last >= 0 else self._scene_tests).append(check)
        self._tests_after = [tuple(t) for t in after]

    def sample(self, seed: int, index: int) -> SceneResult:
        """Scene `index` under `seed`; PrscError after max_attempts rejections."""
        ctx = SceneContext(scene_rng(seed, index))
        stats = RejectionStats(scenes=1)
        labels = self.cprog.labels
        for _ in range(self.max_attempts):
            ctx.rollback(-1)
            ctx.objects.clear()
            ctx.level = -1
            ctx.active_requires = draw_soft_requires(self.cprog, ctx)
            cause = self._first_failure(ctx, self._scene_tests)
            placed: list[PlacedBox] = []
            k = 0
            while cause is None and k < len(self.runtimes):
                try:
                    cause = self._place(k, ctx, placed, labels)
                except GeometryError as error:  # empty and unbounded regions are handled in _place
                    plan = self.runtimes[k].plan
                    raise numeric_failure(plan.name, plan.span, error) from error
                k += 1
            if cause is None:
                ctx.level = len(self.runtimes)
                params = evaluate_params(self.cprog, ctx)
                return SceneResult([ctx.objects[rt.plan.name] for rt in self.runtimes], params, stats, ctx)
            stats.add(cause)
        raise PrscError(
            f"the baseline found no scene {index} (seed {seed}) in {self.max_attempts} attempts; "
            f"rejections: {stats.summary()}"
        )

    def _first_failure(self, ctx: SceneContext, tests: tuple[RequireCheck, ...] | list[RequireCheck]) -> str | None:
        for check in tests:
            if (check.soft is None or check.soft in ctx.active_requires) and not check.test(ctx):
                return REQUIRE
        return None

    def _place(self, k: int, ctx: SceneContext, placed: list[PlacedBox], labels: tuple[RowLabel, ...]) -> str | None:
        """Draw object k and test it; the cause of the first failed test, or None."""
        rt = self.runtimes[k]
        ctx.level = k
        obj, half, support = rt.new_value(ctx)
        try:
            region, shift = self.base_providers[k].region(ctx, support, rt.support is not None)
        except EmptyRegionError:
            return CONTAINMENT  # its equalities put it outside the workspace's bounding box
        except UnboundedRegionError as error:
            raise PrscError(
                f"the baseline needs a bounded region to draw {rt.plan.name} from: add a workspace", rt.plan.span
            ) from error
        p = region.draw(ctx.rng, "exact", 0)
        obj.position = p if shift is None else p + shift
        rt.late_rotation(obj, ctx)
        label = violated_rule(rt.provider, ctx, support, obj.position)
        if label is not None:
            return labels[label].cause
        if inside_any(rt.excluded(ctx, support), obj.position):
            return CONTAINMENT  # wholly in the view of a camera it must not be visible from
        rt.finish(obj, ctx)
        box = rt.placed_box(obj, half, ctx)
        if not box.allow and placed:
            candidates = near(placed, obj.position, obj.position, box.reach, containers=rt.plan.rests_in)
            if first_hit(candidates, obj.position, obj.rotation, half, box.reach) is not None:
                return COLLISION
        placed.append(box)
        return self._first_failure(ctx, self._tests_after[k])
