"""One random generator per (seed, scene index): scene k is the same whatever -n, the
order scenes are drawn in, or the number of workers."""

from __future__ import annotations

import numpy as np

from prsc.errors import PrscError


def scene_rng(seed: int, index: int) -> np.random.Generator:
    """The Generator of scene `index` under `seed` (PCG64 seeded with the entropy (seed, index))."""
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise PrscError(f"the seed must be a non-negative integer, got {seed!r}")
    if isinstance(index, bool) or not isinstance(index, (int, np.integer)) or index < 0:
        raise PrscError(f"the scene index must be a non-negative integer, got {index!r}")
    return np.random.default_rng([int(seed), int(index)])
