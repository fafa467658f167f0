"""Prepared feasible regions of one object, cached by the concrete values they depend on.

Three cases, decided by the constraint stage:
- static: every rule gives the same rows in every scene: prepared once;
- anchored: the non-static rows move rigidly with one earlier object (e.g. `on tr_1`):
  prepared once with that object at the origin, translated by its position per scene
  (when the static rows, e.g. the workspace, do not cut the translated region);
- general: rows built per scene; a point (`at`: the region's `point_rule`) is checked
  directly, anything else is prepared (vertex enumeration + triangulation), with a
  small cache on the exact rows.
The sample is a function of the scene's rows and random stream only, never of which
scenes filled a cache first. Gibbs sweeps (gibbs.py) also ask for `translates`: rows that
are a translate of rows prepared earlier in the same scene (a part's region in a bin that
moved) reuse that preparation, shifted; the cache lives in the scene's context
(`SceneContext.prepared`), so the sample is still a function of the scene alone.
"""

from __future__ import annotations

from collections import OrderedDict

import numpy as np

from prsc.constraints.build import rule_rows
from prsc.constraints.context import SceneContext
from prsc.constraints.polytope_ir import RegionRules, Rule
from prsc.constraints.support import Support
from prsc.geometry.exceptions import EmptyRegionError, UnboundedRegionError
from prsc.geometry.polytope import Polytope, intersect
from prsc.sampling.prepared import TOL, Prepared, prepare, row_norms, satisfies

_CACHE_SIZE = 256
_TRANSLATES = 4  # preparations kept per row directions and scene (tried in order)
_SLACK = 1e-7  # metres: a row within this of a vertex counts as tight there


def _empty(poly: Polytope) -> EmptyRegionError:
    """An EmptyRegionError carrying the rows (for explaining the conflict)."""
    error = EmptyRegionError("the region is empty")
    error.rows = poly  # type: ignore[attr-defined]
    return error


class _Translatable:
    """A region prepared in this scene, and which of its rows are tight at a vertex."""

    __slots__ = ("prepared", "b", "d", "tight", "slack", "directions", "slack_rows", "slack_at_vertices")

    def __init__(self, prepared: Prepared, b: np.ndarray, d: np.ndarray, tight: np.ndarray,
                 directions: np.ndarray, slack_rows: np.ndarray, slack_at_vertices: np.ndarray) -> None:
        self.prepared, self.b, self.d, self.tight, self.slack = prepared, b, d, tight, ~tight
        self.directions, self.slack_rows, self.slack_at_vertices = directions, slack_rows, slack_at_vertices

    @staticmethod
    def of(poly: Polytope, prepared: Prepared) -> "_Translatable":
        """The rows of `poly` sorted into tight (at some vertex of `prepared`) and slack."""
        vertices = prepared.point[None, :] if prepared.point is not None else prepared.sampler.vertices()  # type: ignore[union-attr]
        norms = np.maximum(np.linalg.norm(poly.A, axis=1), 1.0)
        tight = np.any(poly.A @ vertices.T >= (poly.b - _SLACK * norms)[:, None], axis=1)
        slack = ~tight
        return _Translatable(prepared, poly.b, poly.d, tight, np.vstack([poly.A[tight], poly.C]),
                             poly.A[slack], poly.A[slack] @ vertices.T)

    def shift_to(self, poly: Polytope) -> np.ndarray | None:
        """t such that `poly`'s region is this one's plus t, or None."""
        offsets = np.concatenate([(poly.b - self.b)[self.tight], poly.d - self.d])
        if len(offsets):
            shift = np.linalg.lstsq(self.directions, offsets, rcond=None)[0]
            if np.any(np.abs(self.directions @ shift - offsets) > TOL):
                return None
        else:
            shift = np.zeros(poly.A.shape[1])
        if np.any(self.slack_at_vertices + (self.slack_rows @ shift)[:, None] >= (poly.b[self.slack] - TOL)[:, None]):
            return None  # a slack row of `poly` would cut the translated region
        return shift


class RegionProvider:
    """The feasible region of one object in one scene (before collisions)."""

    def __init__(self, plan: RegionRules) -> None:
        self.plan = plan
        self.static_rows = plan.static_rows
        self.dynamic = plan.dynamic
        # The rule fixing p to a point (`at V`), when there is one: its rows are p = point.
        self.point_rule: Rule | None = None if plan.point_rule is None else plan.rules[plan.point_rule]
        self._static: Prepared | None = None
        self._anchored: Prepared | None = None
        self._anchored_state = "new"  # new | ok | none
        self._slack: tuple[np.ndarray, np.ndarray] | None = None  # (S.A @ vertices.T, S.b - margin)
        self._cache: OrderedDict[bytes, Prepared | None] = OrderedDict()
        self._norms: tuple[np.ndarray, np.ndarray] | None = None

    def _static_norms(self) -> tuple[np.ndarray, np.ndarray]:
        if self._norms is None:
            assert self.static_rows is not None
            self._norms = row_norms(self.static_rows)
        return self._norms

    @property
    def static_prepared(self) -> Prepared | None:
        """The region prepared once for every scene (static rows only), if already prepared."""
        return self._static

    @property
    def anchored_prepared(self) -> Prepared | None:
        """The anchored rows' region prepared with the anchor at the origin, once `fixed_bounds` found
        that the static rows never cut it (None otherwise)."""
        return self._anchored if self._anchored_state == "ok" else None

    @property
    def mode(self) -> str:
        """static, anchored or general."""
        if not self.dynamic:
            return "static"
        if self.plan.anchor is not None and self.plan.anchored_rows is not None:
            return "anchored"
        return "general"

    def rows(self, ctx: SceneContext, support: Support) -> Polytope:
        """All rows of this scene (static and dynamic), e.g. to explain an empty region."""
        polys = [] if self.static_rows is None else [self.static_rows]
        polys += [rule_rows(r, ctx, support) for r in self.dynamic if r.soft is None or r.soft in ctx.active_requires]
        if not polys:
            return Polytope.everything()
        return intersect(*polys)

    def region(self, ctx: SceneContext, support: Support, support_static: bool,
               translates: bool = False) -> tuple[Prepared, np.ndarray | None]:
        """(prepared region, translation to add to its draws or None); EmptyRegionError if empty.
        With `translates`, per-scene rows that translate rows prepared earlier in this scene reuse them."""
        if not self.dynamic and support_static:
            if self._static is None:
                self._static = prepare(self.static_rows if self.static_rows is not None else Polytope.everything())
            return self._static, None
        if support_static and self.plan.anchor is not None:
            shift = ctx.objects[self.plan.anchor].position
            fast = self._anchored_region(shift)
            if fast is not None:
                return fast, shift
            assert self.plan.anchored_rows is not None
            polys = [self.plan.anchored_rows.translate(shift)]
            if self.static_rows is not None:
                polys.append(self.static_rows)
            return self._per_scene(ctx, translates, intersect(*polys))
        if support_static:
            active = [r for r in self.dynamic if r.soft is None or r.soft in ctx.active_requires]
            dynamic = [rule_rows(r, ctx, support) for r in active]
            if self.point_rule is not None:
                # `at V` with a random V: no preparation, just check the point.
                which = next(i for i, r in enumerate(active) if r is self.point_rule)
                point = dynamic[which].d
                ok = all(satisfies(poly, point, skip_eq=(i == which)) for i, poly in enumerate(dynamic))
                if ok and self.static_rows is not None:
                    ok = satisfies(self.static_rows, point, self._static_norms())
                if not ok:
                    raise _empty(intersect(*dynamic, *([] if self.static_rows is None else [self.static_rows])))
                return Prepared(dynamic[which], None, point), None
            polys = dynamic if self.static_rows is None else [self.static_rows, *dynamic]
            return self._per_scene(ctx, translates, intersect(*polys) if polys else Polytope.everything())
        # The object's own size or rotation is random: every rule is rebuilt.
        polys = [rule_rows(r, ctx, support) for r in self.plan.rules if r.soft is None or r.soft in ctx.active_requires]
        return self._per_scene(ctx, translates, intersect(*polys) if polys else Polytope.everything())

    def fixed_bounds(self) -> tuple[np.ndarray, np.ndarray] | None:
        """Bounds of the region in every scene (relative to the anchor's position when anchored),
        for an object with a static support; None when only a scene can tell."""
        try:
            if not self.dynamic:
                if self._static is None:
                    self._static = prepare(self.static_rows if self.static_rows is not None else Polytope.everything())
                return self._static.lo, self._static.hi
            if self.mode == "anchored":
                if self._anchored_state == "new":
                    self._prepare_anchored()
                if self._anchored is not None:  # the static rows only cut the translated region
                    return self._anchored.lo, self._anchored.hi
        except (EmptyRegionError, UnboundedRegionError):
            pass
        return None

    def _anchored_region(self, shift: np.ndarray) -> Prepared | None:
        """The anchored rows' region if the static rows do not cut it once translated, else None."""
        if self._anchored_state == "new":
            self._prepare_anchored()
        if self._anchored_state != "ok":
            return None
        if self._slack is not None:
            av, b = self._slack
            # Every vertex of the translated region inside the static rows (with a margin):
            # by convexity the static rows do not cut it.
            if np.any(av + (self.static_rows.A @ shift)[:, None] > b[:, None]):  # type: ignore[union-attr]
                return None
        return self._anchored

    def _prepare_anchored(self) -> None:
        assert self.plan.anchored_rows is not None
        try:
            self._anchored = prepare(self.plan.anchored_rows)
        except (EmptyRegionError, UnboundedRegionError):
            self._anchored_state = "none"  # the general path decides, scene by scene
            return
        self._anchored_state = "ok"
        s = self.static_rows
        if s is not None:
            if len(s.d):
                self._anchored_state = "none"  # static equalities always cut a translated region
                return
            a = self._anchored
            verts = a.point[None, :] if a.point is not None else a.sampler.vertices()  # type: ignore[union-attr]
            an = np.maximum(np.linalg.norm(s.A, axis=1), 1.0)
            self._slack = (s.A @ verts.T, s.b - TOL * an)

    def _per_scene(self, ctx: SceneContext, translates: bool, poly: Polytope) -> tuple[Prepared, np.ndarray | None]:
        """Rows built for this scene, prepared: shifted from this scene's earlier ones with `translates`."""
        return self._translated(poly, ctx) if translates else (self._general(poly), None)

    def _translated(self, poly: Polytope, ctx: SceneContext) -> tuple[Prepared, np.ndarray | None]:
        """(prepared, shift): a preparation of this scene whose region `poly`'s is, translated by
        `shift`, else `poly` prepared (and remembered for this scene).

        The region P of rows (A, b0, C, d0) is the region of its rows tight at some vertex
        (a row slack at every vertex of a bounded polytope cuts nothing). So rows (A, b1, C, d1)
        give P + t when the tight rows and the equalities move by t (b1 = b0 + A t) and the
        slack rows stay slack at every vertex of P + t, a workspace's far walls for instance."""
        key = (id(self), poly.A.tobytes(), poly.C.tobytes())
        seen = ctx.prepared.setdefault(key, [])
        for known in seen:
            shift = known.shift_to(poly)
            if shift is not None:
                return known.prepared, shift
        prepared = self._general(poly)
        if len(seen) < _TRANSLATES:
            seen.append(_Translatable.of(poly, prepared))
        return prepared, None

    def _general(self, poly: Polytope) -> Prepared:
        """Prepare per-scene rows, reusing an identical earlier preparation."""
        key = poly.A.tobytes() + poly.b.tobytes() + b"|" + poly.C.tobytes() + poly.d.tobytes()
        if key in self._cache:
            hit = self._cache[key]
            self._cache.move_to_end(key)
            if hit is None:
                raise _empty(poly)
            return hit
        try:
            prepared: Prepared | None = prepare(poly)
        except EmptyRegionError:
            prepared = None
        self._cache[key] = prepared
        if len(self._cache) > _CACHE_SIZE:
            self._cache.popitem(last=False)
        if prepared is None:
            raise _empty(poly)
        return prepared


def first_violation(poly: Polytope, p: np.ndarray, tol: float = TOL) -> int | None:
    """The label of the first row of poly that p violates by more than tol metres, else None."""
    if len(poly.b):
        an = np.sqrt(np.einsum("ij,ij->i", poly.A, poly.A))
        bad = np.nonzero(poly.A @ p - poly.b > tol * np.maximum(an, 1.0))[0]
        if len(bad):
            return int(poly.labels[bad[0]])
    if len(poly.d):
        cn = np.sqrt(np.einsum("ij,ij->i", poly.C, poly.C))
        bad = np.nonzero(np.abs(poly.C @ p - poly.d) > tol * np.maximum(cn, 1.0))[0]
        if len(bad):
            return int(poly.eq_labels[bad[0]])
    return None


def violated_rule(provider: RegionProvider, ctx: SceneContext, support: Support, p: np.ndarray) -> int | None:
    """The label of a rule of the provider's region that p violates, else None (the baseline's test)."""
    plan = provider.plan
    if plan.static_rows is not None:
        label = first_violation(plan.static_rows, p)
        if label is not None:
            return label
    if not provider.dynamic:
        return None
    if plan.anchor is not None and plan.anchored_rows is not None:
        return first_violation(plan.anchored_rows, p - ctx.objects[plan.anchor].position)
    for rule in provider.dynamic:
        if rule.soft is not None and rule.soft not in ctx.active_requires:
            continue
        label = first_violation(rule_rows(rule, ctx, support), p)
        if label is not None:
            return label
    return None
