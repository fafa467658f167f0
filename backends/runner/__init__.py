"""The MuJoCo runner: the paper's camera + IK handover controller over compiled scenes.

`run_episode(scene, mjcf_path, seed) -> EpisodeResult` runs one episode; `prsc run`
(prsc/commands/run.py) compiles scenes, runs them in worker processes and reports.
"""

from __future__ import annotations

from prsc.backends.runner.episode import OUTCOMES, EpisodeResult, run_episode

__all__ = ["OUTCOMES", "EpisodeResult", "run_episode"]
