"""The worker side of a campaign: module-level entry points any executor can call in any process.

Nothing here imports mujoco at import time: `run_task` first adopts the driver's GL backend.
Returns ("ok", record) or ("fault", message) so infrastructure faults cross process lines
(and Ray) as plain data.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

from prsc.runner.episode_records import EpisodeTask


@dataclass(frozen=True)
class WorkerConfig:
    """What every episode worker shares: the GL backend the driver chose, and whether the
    software rasteriser gets one thread (with a worker per core, llvmpipe's extra threads
    only contend: about 10% less CPU per episode measured)."""

    gl_backend: str
    one_raster_thread: bool = False


def run_task(config: WorkerConfig, task: EpisodeTask) -> tuple[str, object]:
    """Run one episode: ("ok", EpisodeResult) or ("fault", message)."""
    from prsc.runner.faults import InfrastructureError
    from prsc.runner.gl import use_gl_backend

    if config.one_raster_thread:
        os.environ.setdefault("LP_NUM_THREADS", "1")  # read when the first GL context is made
    try:
        use_gl_backend(config.gl_backend)
        from prsc.runner.harness import run_episode

        return "ok", run_episode(task)
    except InfrastructureError as error:
        return "fault", error.message
