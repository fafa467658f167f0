"""Draw functions of the distributions (one uniform or normal per draw, from the scene's stream)."""

from __future__ import annotations

from typing import Any, Callable

import numpy as np

from prsc.constraints.context import SceneContext
from prsc.constraints.operations import error_at, as_number
from prsc.errors import PrscError
from prsc.ir import model as ir

Fn = Callable[[SceneContext], Any]


def truncated_normal_mass(mean: float, sd: float, low: float, high: float) -> tuple[float, float]:
    """(Phi(a), Phi(b)) of TruncatedNormal(mean, sd, low, high); ValueError when it has none."""
    from scipy.special import ndtr  # here, not at the top: 0.15 s of every CLI start-up

    if not (sd > 0 and low < high):
        raise ValueError("TruncatedNormal needs sd > 0 and low < high")
    pa, pb = float(ndtr((low - mean) / sd)), float(ndtr((high - mean) / sd))
    if not pb > pa:
        raise ValueError("TruncatedNormal's interval has no probability mass")
    return pa, pb


def truncated_normal(mean: float, sd: float, low: float, high: float, mass: tuple[float, float], u: Any) -> Any:
    """TruncatedNormal(mean, sd, low, high) at uniforms u (a float or an array), by the inverse CDF on
    [Phi(a), Phi(b)] (`mass`): exact, one uniform per draw. The one implementation, scalar and vectorised."""
    from scipy.special import ndtri

    pa, pb = mass
    return np.clip(mean + sd * ndtri(pa + (pb - pa) * u), low, high)


def sampler_for(e: ir.Distribution, args: list[Fn], weights: list[Fn]) -> Fn:
    """The draw function of one distribution node (no memoisation)."""
    kind, span = e.kind, e.span

    def num(f: Fn, ctx: SceneContext, what: str) -> float:
        return as_number(f(ctx), what, span)

    if kind == "range":
        lo_f, hi_f = args
        site = "?" if span is None else f"{span.line}:{span.column}"  # a proposal's key for this range

        def draw_range(ctx: SceneContext) -> float:
            lo, hi = num(lo_f, ctx, "a range bound"), num(hi_f, ctx, "a range bound")
            if hi < lo:
                raise error_at(f"empty range ({lo}, {hi})", span)
            u = ctx.uniform() if ctx.proposal is None else ctx.proposal.unit(site, ctx)
            return lo + (hi - lo) * u

        return draw_range
    if kind == "normal":
        mean_f, sd_f = args

        def draw_normal(ctx: SceneContext) -> float:
            mean, sd = num(mean_f, ctx, "a mean"), num(sd_f, ctx, "a standard deviation")
            if sd < 0:
                raise error_at("a standard deviation must be >= 0", span)
            return mean + sd * ctx.normal()

        return draw_normal
    if kind == "truncnormal":
        mean_f, sd_f, lo_f, hi_f = args

        def draw_truncnormal(ctx: SceneContext) -> float:
            mean, sd = num(mean_f, ctx, "a mean"), num(sd_f, ctx, "a standard deviation")
            lo, hi = num(lo_f, ctx, "a bound"), num(hi_f, ctx, "a bound")
            try:
                mass = truncated_normal_mass(mean, sd, lo, hi)
            except ValueError as error:
                raise error_at(str(error), span) from None
            return float(truncated_normal(mean, sd, lo, hi, mass, ctx.uniform()))

        return draw_truncnormal
    if kind == "uniform":
        if not args:
            raise PrscError("Uniform needs at least one option", span)
        options = args

        def draw_option(ctx: SceneContext) -> Any:
            return options[min(int(ctx.uniform() * len(options)), len(options) - 1)](ctx)

        return draw_option
    if kind == "discrete":
        if not args or len(args) != len(weights):
            raise PrscError("Discrete needs one weight per option", span)
        options = args

        def draw_discrete(ctx: SceneContext) -> Any:
            w = [num(f, ctx, "a weight") for f in weights]
            total = sum(w)
            if any(x < 0 for x in w) or not total > 0:
                raise error_at("Discrete weights must be >= 0 and not all 0", span)
            u = ctx.uniform() * total
            acc = 0.0
            for option, weight in zip(options, w):
                acc += weight
                if u < acc:
                    return option(ctx)
            return options[-1](ctx)

        return draw_discrete
    raise PrscError(f"unknown distribution {kind!r}", span)
