"""A counter-based random stream: uniform k of draw site s in scene i under seed is a pure
function of (seed, i, s, k), computed for many scenes at once with numpy.

The batched sampler (batched.py) reads it instead of one `Generator` per scene: building a
PCG64 per (seed, index) costs about 27 µs, more than a whole batched scene. Each uniform
is SplitMix64's output mixer (Steele, Lea and Flood, "Fast splittable pseudorandom number
generators", OOPSLA 2014) applied in turn to the seed, the scene index and the draw's
counter, each step keyed by the one before; its top 53 bits give the float in [0, 1).
Integer arithmetic only (wrapping uint64), so a scene's numbers do not depend on how many
scenes share the call. docs/sampling.md, "Batched sampling", gives its statistical tests.
"""

from __future__ import annotations

import functools

import numpy as np

_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_M1 = np.uint64(0xBF58476D1CE4E5B9)
_M2 = np.uint64(0x94D049BB133111EB)
_S30, _S27, _S31, _S11 = np.uint64(30), np.uint64(27), np.uint64(31), np.uint64(11)
_UNIT = 2.0 ** -53
# Uniforms per draw site: a site's counter k runs over [0, SITE_WIDTH).
SITE_WIDTH = 1 << 16


_G, _MASK = int(_GOLDEN), (1 << 64) - 1


def _mix_int(z: int) -> int:
    """`_mix` on one Python integer in [0, 2^64): the same bits."""
    z ^= z >> 30
    z = (z * 0xBF58476D1CE4E5B9) & _MASK
    z ^= z >> 27
    z = (z * 0x94D049BB133111EB) & _MASK
    return z ^ (z >> 31)


def _unit(key: int, counter: int) -> float:
    """One uniform of a scene key and a counter (times the golden gamma), as `uniforms` computes it."""
    z = (key ^ _mix_int(counter & _MASK)) * _G & _MASK
    return (_mix_int(z) >> 11) * _UNIT


def _mix(z: np.ndarray) -> np.ndarray:
    """SplitMix64's output mixer (a bijection of uint64), in place."""
    z ^= z >> _S30
    z *= _M1
    z ^= z >> _S27
    z *= _M2
    z ^= z >> _S31
    return z


def scene_keys(seed: int, indices: np.ndarray) -> np.ndarray:
    """One uint64 key per scene index under `seed` (the stream of each scene)."""
    seed_key = _mix(np.array([seed], dtype=np.uint64) * _GOLDEN + _GOLDEN)
    keys = np.asarray(indices, dtype=np.uint64) * _GOLDEN
    keys ^= seed_key
    return _mix(keys)


_CACHED_WIDTH = 64  # sites this narrow keep their mixed counters (4,096 of them: at most 2 MiB)


def _mixed_counters(site: int, width: int) -> np.ndarray:
    """The mixed counters of a draw site's first `width` uniforms: the same for every scene."""
    with np.errstate(over="ignore"):  # numpy wraps uint64 arrays silently; a product of scalars it would warn of
        counters = (np.uint64(site) * np.uint64(SITE_WIDTH) + np.arange(width, dtype=np.uint64)) * _GOLDEN + _GOLDEN
    return _mix(counters)


@functools.lru_cache(maxsize=4096)
def _site_counters(site: int, width: int) -> np.ndarray:
    """`_mixed_counters`, read-only and kept: a Gibbs round's many small draws from one site mix them once."""
    counters = _mixed_counters(site, width)
    counters.flags.writeable = False
    return counters


def uniforms(keys: np.ndarray, site: int, width: int) -> np.ndarray:
    """`width` uniforms in [0, 1) of draw site `site` per scene key: shape (len(keys), width)."""
    if not 0 <= width <= SITE_WIDTH:
        raise ValueError(f"a draw site holds at most {SITE_WIDTH} uniforms, not {width}")
    if len(keys) == 1:  # one scene (a reset, a compile job): plain integers cost less than numpy calls
        key = int(keys[0])
        first = (site * SITE_WIDTH) * _G + _G
        return np.array([[_unit(key, first + j * _G) for j in range(width)]])
    # Arrays only (uint64 arrays wrap without a warning): no errstate context, 3 us a call, a round's many calls.
    counters = _site_counters(site, width) if width <= _CACHED_WIDTH else _mixed_counters(site, width)
    z = keys[:, None] ^ counters[None, :]
    z *= _GOLDEN
    _mix(z)
    return (z >> _S11).astype(np.float64) * _UNIT


def candidate_keys(keys: np.ndarray, first: int, count: int) -> np.ndarray:
    """Keys of candidates first .. first+count-1 of each scene key, scene major: shape (len(keys) * count,).

    The same mixer keyed by the scene's key, so candidate c of a scene depends on (key, c) alone."""
    counters = (np.arange(first, first + count, dtype=np.uint64) + np.uint64(1)) * _GOLDEN
    z = np.asarray(keys, dtype=np.uint64)[:, None] ^ _mix(counters)[None, :]  # arrays only, as in `uniforms`
    z *= _GOLDEN
    _mix(z)
    return z.reshape(-1)
