"""One recorded episode encoded for a dataset (docs/datasets.md): its columns, videos or HDF5
file, its model, its scene and outcome; made in the worker that ran it, written by DemoDataset."""

from __future__ import annotations

import hashlib
import json
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np


from prsc.runner import lerobot_format as lerobot
from prsc.runner import robomimic_format as robomimic
from prsc.runner.demo_frames import EpisodeFrames
from prsc.runner.episode_records import RecordSettings

MODELS = "models"
ASSET_REFERENCE = re.compile(r'file="\.\./assets/([^"]+)"')


@dataclass
class RecordedEpisode:
    """One episode encoded for the dataset (picklable: it crosses process lines and Ray)."""

    scene_index: int
    scene: dict
    seed: int
    result: dict  # the results.jsonl line without its wall-clock time
    task: str
    names: dict[str, list[str]]  # state, action, object names
    state_size: int
    cameras: list[dict]  # name, width, height
    columns: dict[str, np.ndarray]
    model_name: str  # models/<sha>.xml or .mjb
    model_text: str | None = None  # an MJCF file's text, asset paths relative to models/
    model_source: str | None = None  # that file, whose ../assets/ the driver copies
    model_binary: bytes | None = None  # an in-memory model (prsc.RecordEpisodes)
    videos: dict[str, bytes] = field(default_factory=dict)  # lerobot: camera -> mp4
    image_stats: dict[str, dict] = field(default_factory=dict)
    hdf5: bytes | None = None  # robomimic: the episode's file

    def drop_payload(self) -> None:
        """Free the frames and encoded files (once committed)."""
        self.columns = {"next.done": self.columns["next.done"], "next.success": self.columns["next.success"]}
        self.videos, self.hdf5, self.model_binary, self.model_text = {}, None, None, None

    @property
    def success(self) -> bool:
        """The task succeeded (its `next.success`), or the controller said `success`."""
        return bool(np.any(self.columns["next.success"])) or self.result.get("outcome") == "success"

    def __len__(self) -> int:
        return len(self.columns["next.done"])


def task_text(scene: dict) -> str:
    """The episode's task in words: the spec's `param task`, else its goal as the spec writes it, else the spec's name."""
    task = (scene.get("params") or {}).get("task")
    if isinstance(task, str) and task.strip():
        return task.strip()
    if scene.get("task"):
        from prsc.task.describe import format_term
        from prsc.task.terms import Task

        goals = Task.from_json(scene["task"]).statements.goals
        if goals:
            return "achieve " + " and ".join(format_term(g.expr) for g in goals)
    return Path(str(scene.get("spec") or "scene")).stem


def model_file_text(mjcf_text: str) -> tuple[str, str]:
    """(text, models/<sha>.xml) of a compiled MJCF as stored: its ../assets/ become assets/ beside it."""
    text = ASSET_REFERENCE.sub(lambda m: f'file="assets/{m.group(1)}"', mjcf_text)
    return text, f"{MODELS}/{hashlib.sha256(text.encode()).hexdigest()[:20]}.xml"


def encode_episode(frames: EpisodeFrames, settings: RecordSettings, scene: dict, result: dict, *,
                   mjcf_path: str | None = None, model_binary: bytes | None = None) -> RecordedEpisode:
    """The episode's frames as the dataset stores them (videos or HDF5 encoded here, in the worker)."""
    layout = frames.layout
    columns = frames.columns()
    names = {"state": list(layout.state_names), "action": list(layout.action_names), "object": list(layout.object_names)}
    if mjcf_path is not None:
        text, model_name = model_file_text(Path(mjcf_path).read_text(encoding="utf-8"))
    else:
        text, model_name = None, f"{MODELS}/{hashlib.sha256(model_binary).hexdigest()[:20]}.mjb"
    episode = RecordedEpisode(
        scene_index=int(scene.get("index", 0)), scene=scene, seed=int(scene.get("seed", 0)),
        result={k: v for k, v in result.items() if k != "wall_seconds"}, task=settings.task or task_text(scene),
        names=names, state_size=layout.state_size,
        cameras=[{"name": c.name, "width": c.width, "height": c.height} for c in layout.cameras if settings.images],
        columns=columns, model_name=model_name, model_text=text, model_source=mjcf_path, model_binary=model_binary)
    images = {c.name: frames.image_stack(c.name) for c in layout.cameras if frames.images.get(c.name)}
    if settings.format == "lerobot":
        for camera, stack in images.items():
            episode.videos[camera] = lerobot.encode_video(stack, settings.fps, settings.lossless)
            episode.image_stats[camera] = lerobot.feature_stats(stack, is_image=True)
    else:
        attrs = {"model_file": text if text is not None else "", "prsc_model_path": model_name,
                 "prsc_scene": json.dumps(scene), "prsc_seed": episode.seed, "prsc_scene_index": episode.scene_index,
                 "prsc_result": json.dumps(episode.result), "prsc_task": episode.task}
        episode.hdf5 = robomimic.episode_file(columns, images, names, attrs)
    return episode


