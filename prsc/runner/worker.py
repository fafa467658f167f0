"""The worker side of a campaign: module-level entry points any executor can call in any process.

Nothing here imports mujoco at import time: `run_task` first adopts the driver's GL backend.
Returns ("ok", record), ("ok", record, recorded episode) when the campaign records a dataset,
or ("fault", message), so infrastructure faults cross process lines (and Ray) as plain data.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any

from prsc.runner.episode_records import EpisodeTask


@dataclass(frozen=True)
class WorkerConfig:
    """What every episode worker shares: the GL backend the driver chose, and whether the
    software rasteriser gets one thread (with a worker per core, llvmpipe's extra threads
    only contend: about 10% less CPU per episode measured)."""

    gl_backend: str
    one_raster_thread: bool = False
    record: Any = None  # prsc.runner.demo_dataset.RecordSettings: record each episode for a dataset


def run_task(config: WorkerConfig, task: EpisodeTask) -> tuple:
    """Run one episode: ("ok", EpisodeResult[, RecordedEpisode]) or ("fault", message)."""
    from prsc.runner.faults import InfrastructureError
    from prsc.runner.gl import use_gl_backend

    if config.one_raster_thread:
        os.environ.setdefault("LP_NUM_THREADS", "1")  # read when the first GL context is made
    try:
        use_gl_backend(config.gl_backend)
        from prsc.runner.harness import run_episode

        if config.record is None:
            return "ok", run_episode(task)
        return ("ok", *_recorded(config.record, task))
    except InfrastructureError as error:
        return "fault", error.message


def _recorded(settings: Any, task: EpisodeTask) -> tuple[Any, Any]:
    """(result, its RecordedEpisode) of an episode recorded frame by frame from the step hook."""
    from prsc.runner.episode_encoding import encode_episode
    from prsc.runner.demo_frames import DemoRecorder
    from prsc.runner.harness import run_episode

    monitors: list = []  # the episode's task monitor, once the harness builds it: each frame's status
    recorder = DemoRecorder(task.scene, settings.fps, images=settings.images,
                            task_status=lambda: monitors[0].latest if monitors else None)
    try:
        result = run_episode(task, step_callbacks=[recorder.periodic], monitor_ready=monitors.append)
    finally:
        recorder.close()
    if recorder.frames is None:  # the controller never stepped: nothing to record
        return result, None
    return result, encode_episode(recorder.frames, settings, task.scene, result.to_json(), mjcf_path=task.mjcf_path)
