"""The MuJoCo runner: any controller over compiled scenes (see controller.py for the interface).

`run_episode(task)` runs one episode in this process; `prsc run` (prsc/commands/run.py)
compiles scenes, runs their episodes on an executor (local processes or Ray) and reports.
`handover` is the paper's controller and the default; `pick_place` a small example.
"""

from __future__ import annotations

from prsc.runner.controller import DEFAULT_CONTROLLER, ControllerRef, parse_target
from prsc.runner.faults import InfrastructureError
from prsc.runner.episode_records import EpisodeResult, EpisodeTask

__all__ = ["DEFAULT_CONTROLLER", "ControllerRef", "EpisodeResult", "EpisodeTask", "InfrastructureError", "parse_target"]
