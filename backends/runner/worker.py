"""The worker side of a campaign: module-level entry points any executor can call in any process.

Nothing here imports mujoco at import time: `run_task` first adopts the driver's GL backend.
Returns ("ok", record) or ("fault", message) so infrastructure faults cross process lines
(and Ray) as plain data.
"""

from __future__ import annotations

from dataclasses import dataclass

from prsc.backends.runner.tasks import EpisodeTask


@dataclass(frozen=True)
class WorkerConfig:
    """What every episode worker shares: the GL backend the driver chose."""

    gl_backend: str


def run_task(config: WorkerConfig, task: EpisodeTask) -> tuple[str, object]:
    """Run one episode: ("ok", EpisodeResult) or ("fault", message)."""
    from prsc.backends.runner.faults import InfrastructureError
    from prsc.backends.runner.gl import use_gl_backend

    try:
        use_gl_backend(config.gl_backend)
        from prsc.backends.runner.harness import run_episode

        return "ok", run_episode(task)
    except InfrastructureError as error:
        return "fault", error.message
