"""One random generator per (seed, scene index): scene k is the same whatever -n, the
order scenes are drawn in, or the number of workers."""

from __future__ import annotations

import numpy as np

from prsc.errors import PrscError


def scene_rng(seed: int, index: int) -> np.random.Generator:
    """The Generator of scene `index` under `seed` (PCG64 seeded with the entropy (seed, index))."""
    _check(seed, index)
    return np.random.default_rng([int(seed), int(index)])


def _check(seed: int, index: int) -> None:
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise PrscError(f"the seed must be a non-negative integer, got {seed!r}")
    if isinstance(index, bool) or not isinstance(index, (int, np.integer)) or index < 0:
        raise PrscError(f"the scene index must be a non-negative integer, got {index!r}")


class LazySceneRng:
    """`scene_rng(seed, index)`, built when first read (a Gibbs round's scene whose properties draw nothing
    never builds its PCG64, ~20 us a scene); the same stream when it is read. Seed and index are checked now."""

    __slots__ = ("_seed", "_index", "_rng")

    def __init__(self, seed: int, index: int) -> None:
        _check(seed, index)
        self._seed, self._index = int(seed), int(index)
        self._rng: np.random.Generator | None = None

    def __getattr__(self, name: str):
        rng = self._rng
        if rng is None:
            rng = self._rng = np.random.default_rng([self._seed, self._index])
        return getattr(rng, name)
