"""Scene sampling: exact sequential placement, hit-and-run, and the paper's naive baseline."""

from __future__ import annotations

from prsc.sampling.sampler import SAMPLERS, Sampler, compile_sampler, scene_sampler

__all__ = ["SAMPLERS", "Sampler", "compile_sampler", "scene_sampler"]
