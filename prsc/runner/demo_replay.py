"""Replay a recorded episode (docs/datasets.md): its model rebuilt from the stored MJCF (or
MuJoCo binary), each frame's stored MuJoCo state set and forward-computed, the objects'
poses compared with the recorded ones and every camera re-rendered and compared with the
recorded images."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np

from prsc.errors import PrscError

from prsc.runner import lerobot_format as lerobot
from prsc.runner import robomimic_format as robomimic
from prsc.runner.demo_frames import STATE_SPEC, DemoLayout


@dataclass(frozen=True)
class StoredEpisode:
    """What a dataset holds of one episode, as replay needs it."""

    model_path: Path
    scene: dict
    states: np.ndarray  # (T, S) MuJoCo integration states
    objects: np.ndarray  # (T, 7 per object) recorded poses
    images: dict[str, np.ndarray]  # camera -> (T, H, W, 3), as decoded


@dataclass(frozen=True)
class ReplayReport:
    """How a replay compares with the recording."""

    episode: int
    scene_index: int
    frames: int
    position_error: float  # m (and quaternion units): largest difference of any object's pose
    image_error: dict[str, float]  # camera -> largest difference of any pixel channel (0-255)
    image_mean_error: dict[str, float]
    replayed: dict[str, np.ndarray]  # camera -> the re-rendered frames


def _dataset_state(root: Path) -> dict:
    from prsc.runner.demo_dataset import STATE_FILE

    try:
        return json.loads((root / STATE_FILE).read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise PrscError(f"{root} is not a dataset prsc recorded (no {STATE_FILE})") from None
    except (OSError, ValueError) as error:
        raise PrscError(f"cannot read {root / STATE_FILE}: {error}") from None


def read_episode(root: Path | str, episode: int) -> StoredEpisode:
    """Episode `episode` (0-based, the dataset's order) of a LeRobot or robomimic dataset prsc wrote."""
    root = Path(root)
    stored = _dataset_state(root)
    entries = stored.get("episodes", [])
    if not 0 <= episode < len(entries):
        raise PrscError(f"{root} holds {len(entries)} episodes; --episode must be 0..{len(entries) - 1}, got {episode}")
    entry = entries[episode]
    if stored["key"]["format"] == "lerobot":
        import pyarrow.parquet as pq

        files = lerobot.chunk_file(episode)
        table = pq.read_table(root / lerobot.DATA_PATH.format(**files))
        frames = len(table)

        def column(key: str, width: int) -> np.ndarray:
            if key not in table.column_names:
                return np.zeros((frames, 0))
            return np.asarray(table.column(key).combine_chunks().flatten()).reshape(frames, width)

        states = column("mujoco.state", entry["state_size"])
        objects = column("observation.environment_state", len(entry["names"]["object"]))
        images = {c["name"]: lerobot.decode_video(root / lerobot.VIDEO_PATH.format(
            video_key=lerobot.IMAGE_PREFIX + c["name"], **files)) for c in entry["cameras"]}
        scene = json.loads(entry["extras"]["prsc/scene"])
    else:
        import h5py

        with h5py.File(root / robomimic.INDEX_FILE, "r") as f:
            demo = f[f"data/demo_{episode}"]
            states, objects = demo["states"][()], demo["obs/object"][()]
            images = {c["name"]: demo[f"obs/{c['name']}_image"][()] for c in entry["cameras"]
                      if f"{c['name']}_image" in demo["obs"]}
            scene = json.loads(demo.attrs["prsc_scene"])
    return StoredEpisode(root / entry["model"], scene, states, objects, images)


def load_stored_model(path: Path) -> mujoco.MjModel:
    """The episode's model from its stored MJCF or MuJoCo binary."""
    try:
        if path.suffix == ".mjb":
            return mujoco.MjModel.from_binary_path(str(path))
        return mujoco.MjModel.from_xml_path(str(path))
    except (ValueError, mujoco.FatalError) as error:
        raise PrscError(f"MuJoCo cannot load the stored model {path}: {str(error).strip()}") from None


def replay(root: Path | str, episode: int) -> ReplayReport:
    """Set each stored state, forward-compute, compare poses and re-rendered images with the recording."""
    from prsc.runner.rendering import OffscreenRenderer

    stored = read_episode(root, episode)
    model = load_stored_model(stored.model_path)
    data = mujoco.MjData(model)
    layout = DemoLayout.of(stored.scene, model)
    renderers = {c.name: (OffscreenRenderer(model, c.width, c.height), c.camera_id) for c in layout.cameras
                 if c.name in stored.images}
    poses, replayed = [], {name: [] for name in renderers}
    try:
        for state in stored.states:
            mujoco.mj_setState(model, data, state, STATE_SPEC)
            mujoco.mj_forward(model, data)
            poses.append(layout.objects(data))
            for name, (renderer, camera) in renderers.items():
                replayed[name].append(renderer.rgb(data, camera))
    finally:
        for renderer, _ in renderers.values():
            renderer.close()
    poses = np.array(poses).reshape(stored.objects.shape)
    frames = {name: np.array(images) for name, images in replayed.items()}
    differences = {name: np.abs(frames[name].astype(np.int16) - stored.images[name].astype(np.int16)) for name in frames}
    return ReplayReport(
        episode=episode, scene_index=int(stored.scene.get("index", -1)), frames=len(stored.states),
        position_error=float(np.abs(poses - stored.objects).max()) if poses.size else 0.0,
        image_error={name: float(d.max()) for name, d in differences.items()},
        image_mean_error={name: float(d.mean()) for name, d in differences.items()}, replayed=frames)
