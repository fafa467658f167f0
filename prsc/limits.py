"""Sizes and masses a simulator can represent: checked by `prsc check` on constant values,
when a scene is sampled (naming the object's line) and when scene JSON is read."""

from __future__ import annotations

import math

MIN_SIZE = 1e-6  # m: smaller boxes underflow MuJoCo's and USD's mass properties
MAX_SIZE = 1e6  # m: larger boxes overflow them (a volume of 1e18 m^3 is already absurd)
MAX_MASS = 1e12  # kg


def size_problem(value: float) -> str | None:
    """Why a width, length or height cannot be simulated, or None when it can."""
    if size_fits(value):
        return None
    if not math.isfinite(value) or value <= 0.0:
        return f"must be positive, got {value:g}"
    return f"is {value:g} m, outside what a simulator can represent ({MIN_SIZE:g} to {MAX_SIZE:g} m)"


def mass_problem(value: float) -> str | None:
    """Why a mass cannot be simulated, or None when it can."""
    if mass_fits(value):
        return None
    if not math.isfinite(value) or value < 0.0:
        return f"must be a number >= 0 (kg), got {value!r}"
    return f"is {value:g} kg, more than a simulator can represent ({MAX_MASS:g} kg)"


def size_fits(value: float) -> bool:
    """Whether a size can be simulated (a NaN fails both comparisons): `size_problem` says why not."""
    return MIN_SIZE <= value <= MAX_SIZE


def mass_fits(value: float) -> bool:
    """Whether a mass can be simulated (a NaN fails both comparisons): `mass_problem` says why not."""
    return 0.0 <= value <= MAX_MASS
