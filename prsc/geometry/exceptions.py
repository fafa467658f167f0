"""Geometric failure results that callers turn into user-facing errors."""

from __future__ import annotations


class GeometryError(ValueError):
    """Base class of geometric failures (no prsc error formatting: pure math)."""


class EmptyRegionError(GeometryError):
    """The region (or what remains of it after obstacles) is empty or has measure zero.

    `labels` holds the row labels involved when they are known (use
    `prsc.geometry.iis.irreducible_infeasible_subset` for a minimal conflicting set).
    """

    def __init__(self, message: str, labels: tuple[int, ...] = ()) -> None:
        super().__init__(message)
        self.labels = labels


class UnboundedRegionError(GeometryError):
    """The region is unbounded (or larger than the sampling bound), so no uniform law."""
