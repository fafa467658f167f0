"""Per-object state shared by the samplers: building an object's value in a scene."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from prsc.constraints.build import excluded_cells
from prsc.constraints.context import SceneContext
from prsc.constraints.polytope_ir import ConstraintProgram, ObjectPlan
from prsc.constraints.orientation import orientation_of
from prsc.constraints.support import Support
from prsc.constraints.values import DIMENSIONS, ObjectValue, dimension, static_dims
from prsc.geometry.polytope import Polytope
from prsc.sampling.collisions import PlacedBox, aabb_reach
from prsc.sampling.prepared_regions import RegionProvider

# A point counts as inside an excluded cell only this far (m) inside every row: the free-space
# pieces touch the cells' faces, and a point on a face is out of the (open) cell.
EXCLUDED_TOL = 1e-9


def inside_any(cells: Sequence[Polytope], p: np.ndarray) -> bool:
    """Whether p lies inside one of the excluded cells (`not visible from C`)."""
    return any(bool(cell.contains(p, -EXCLUDED_TOL)) for cell in cells)


@dataclass(eq=False)
class ObjectRuntime:
    """One object's plan plus what does not change between scenes."""

    plan: ObjectPlan
    provider: RegionProvider
    dims: tuple[float, float, float] | None
    half: np.ndarray | None
    rotation: np.ndarray | None  # static rotation (identity when there is no orientation rule)
    support: Support | None  # static support function
    reach: tuple[float, float, float] | None  # static AABB half extents (bound if rotation comes later)
    after_position: bool
    allow_static: bool | None  # allowCollisions when static
    static_box: PlacedBox | None = None

    @classmethod
    def build(cls, plan: ObjectPlan) -> ObjectRuntime:
        """Digest a plan."""
        props = plan.static_props
        dims = static_dims(props)
        half = None if dims is None else np.array(dims) * 0.5
        orient = plan.orientation
        after = orient is not None and orient.after_position
        rotation = np.eye(3) if orient is None else orient.static_value
        support = plan.static_support
        reach = None
        if half is not None:
            if rotation is not None:
                reach = aabb_reach(rotation, half)
            elif after:
                reach = aabb_reach(None, half, orient.bound_mode)  # type: ignore[union-attr]
        if "allowCollisions" in props:
            allow: bool | None = bool(props["allowCollisions"])
        else:
            allow = False if "allowCollisions" not in plan.property_fns else None
        return cls(
            plan,
            RegionProvider(plan.region),
            dims,
            half,
            rotation,
            support,
            reach,
            after,
            allow,
        )

    def new_value(self, ctx: SceneContext) -> tuple[ObjectValue, np.ndarray, Support]:
        """A fresh value of the object (size and pre-position rotation set), registered in ctx."""
        plan = self.plan
        obj = ObjectValue(plan.name, plan.class_name, plan.span, None, None, self.dims, dict(plan.static_props), plan.property_fns)
        ctx.objects[plan.name] = obj
        half = self.half
        if half is None:
            dims = tuple(dimension(obj.get(d, ctx, obj.span), d, obj.name, obj.span) for d in DIMENSIONS)
            obj.dims = dims  # type: ignore[assignment]
            half = np.array(dims) * 0.5
        if self.rotation is not None:
            obj.rotation = self.rotation
        elif not self.after_position:
            obj.rotation = np.asarray(orientation_of(plan.orientation, ctx, obj), dtype=float)  # type: ignore[arg-type]
        support = self.support
        if support is None:
            if obj.rotation is not None:
                support = Support(obj.rotation, half, "exact")
            else:
                support = Support(None, half, plan.orientation.bound_mode)  # type: ignore[union-attr]
        return obj, half, support

    def excluded(self, ctx: SceneContext, support: Support) -> list[Polytope]:
        """The cells its centre must stay out of in this scene (`not visible from C`): extra obstacles."""
        return excluded_cells(self.plan.exclusions, ctx, support) if self.plan.exclusions else []

    @property
    def static_exclusions(self) -> bool:
        """Whether its excluded cells are the same in every scene."""
        return all(rule.static for rule in self.plan.exclusions)

    def allows_collisions(self, obj: ObjectValue, ctx: SceneContext) -> bool:
        """The object's allowCollisions."""
        if self.allow_static is not None:
            return self.allow_static
        return bool(obj.get("allowCollisions", ctx))

    def late_rotation(self, obj: ObjectValue, ctx: SceneContext) -> None:
        """Set the rotation of an object whose rotation depends on its position (`facing toward`)."""
        if self.after_position:
            obj.rotation = np.asarray(orientation_of(self.plan.orientation, ctx, obj), dtype=float)  # type: ignore[arg-type]

    def finish(self, obj: ObjectValue, ctx: SceneContext) -> None:
        """Evaluate every property (draws happen at this object's level) and the late rotation."""
        for prop in self.plan.property_fns:
            if prop not in obj.props:
                obj.get(prop, ctx, self.plan.span)

    def placed_box(self, obj: ObjectValue, half: np.ndarray, ctx: SceneContext) -> PlacedBox:
        """The object's box for later collision checks (the same object every scene when static)."""
        assert obj.position is not None and obj.rotation is not None
        if self.static_box is not None:
            return self.static_box
        box = PlacedBox(obj.name, self.plan.index, obj.position, obj.rotation, half, self.allows_collisions(obj, ctx))
        if (
            self.plan.static_position is not None and self.rotation is not None
            and self.half is not None and self.allow_static is not None
        ):
            self.static_box = box
        return box


def build_runtimes(cprog: ConstraintProgram) -> list[ObjectRuntime]:
    """One runtime per object, in placement order."""
    return [ObjectRuntime.build(plan) for plan in cprog.objects]


def draw_soft_requires(cprog: ConstraintProgram, ctx: SceneContext) -> frozenset[int]:
    """Which soft requires this scene enforces (require[p]: each with probability p)."""
    if not cprog.soft_requires:
        return frozenset()
    return frozenset(s.index for s in cprog.soft_requires if ctx.uniform() < s.probability)


def evaluate_params(cprog: ConstraintProgram, ctx: SceneContext) -> dict[str, Any]:
    """The scene's parameter values."""
    return {name: fn(ctx) for name, fn in cprog.params}
