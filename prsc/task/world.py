"""The world state at one time, as any simulator gives it: poses, velocities and geom distances."""

from __future__ import annotations

from collections.abc import Mapping
from typing import NamedTuple, Protocol

import numpy as np


class DistanceFn(Protocol):
    """(object or `object/link`, object) -> the minimum signed distance between their geoms in metres
    (negative: penetration; contact: <= 0), capped above at DISTANCE_CAP.

    `enough` lets a simulator stop early: when the distance is at most `enough`, any value between
    the distance and `enough` is a right answer (the caller only needs to know it is no further).
    A function that always returns the distance is right too."""

    def __call__(self, a: str, b: str, enough: float | None = None) -> float: ...


DISTANCE_CAP = 1.0  # m: a distance above this is reported as this (the robustness of `touches` saturates)


class Pose(NamedTuple):
    """An object's box centre and rotation (box frame -> world), with its velocities (world frame).
    (Immutable; a tuple because the monitor makes a few at every control step.)"""

    position: np.ndarray
    rotation: np.ndarray
    linear: np.ndarray
    angular: np.ndarray


class WorldState(NamedTuple):
    """Every object's pose at `time`, and distances between objects' (or links') geoms. (Immutable.)"""

    time: float
    poses: Mapping[str, Pose]
    distance: DistanceFn
