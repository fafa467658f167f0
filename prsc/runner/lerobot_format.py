"""LeRobot v3.0 datasets with pyarrow and PyAV (docs/datasets.md): the files lerobot 0.4's
`LeRobotDataset` reads, written one episode at a time so the folder is a finished dataset after
every episode (lerobot's own writer needs `finalize()`: a killed recording lost everything).

    meta/info.json            features, fps, path templates, totals
    meta/stats.json           every feature's statistics, over all episodes
    meta/tasks.parquet        the task texts (index) and their task_index
    meta/episodes/chunk-CCC/file-FFF.parquet   one row per episode: lengths, file indices,
                                               per-episode stats, prsc's own `prsc/...` columns
    data/chunk-CCC/file-FFF.parquet            one file per episode: its frames
    videos/<key>/chunk-CCC/file-FFF.mp4        one file per episode and camera

v3 maps each episode to its data and video file through meta/episodes; lerobot's writer packs
several episodes in a file, prsc one per file, so an episode once written is never rewritten.
"""

from __future__ import annotations

import io
import json
from fractions import Fraction
from pathlib import Path

import numpy as np

CODEBASE_VERSION = "v3.0"
CHUNKS_SIZE = 1000  # files per chunk folder
_CHUNK_FILE = "chunk-{chunk_index:03d}/file-{file_index:03d}"
DATA_PATH = "data/" + _CHUNK_FILE + ".parquet"
VIDEO_PATH = "videos/{video_key}/" + _CHUNK_FILE + ".mp4"
EPISODES_PATH = "meta/episodes/" + _CHUNK_FILE + ".parquet"
QUANTILES = {"q01": 0.01, "q10": 0.10, "q50": 0.50, "q90": 0.90, "q99": 0.99}
IMAGE_PREFIX = "observation.images."
# lerobot's encode_video_frames: a keyframe every 2 frames (random access), crf 30.
LOSSY_OPTIONS = {"g": "2", "crf": "30"}
LOSSLESS_OPTIONS = {"g": "2", "crf": "0"}  # libx264rgb: RGB kept exactly (replay compares bit for bit)


def chunk_file(episode: int) -> dict[str, int]:
    """The chunk and file index of episode `episode`'s own files."""
    return {"chunk_index": episode // CHUNKS_SIZE, "file_index": episode % CHUNKS_SIZE}


def features(state_names, action_names, object_names, state_size: int, cameras) -> dict[str, dict]:
    """info.json's features, in the data files' column order (a feature of no numbers is left out)."""
    out: dict[str, dict] = {}
    for key, names, dtype in (("observation.state", state_names, "float32"), ("action", action_names, "float32"),
                              ("observation.environment_state", object_names, "float64")):
        if names:
            out[key] = {"dtype": dtype, "shape": [len(names)], "names": list(names)}
    for camera in cameras:
        out[IMAGE_PREFIX + camera.name] = {"dtype": "video", "shape": [camera.height, camera.width, 3],
                                           "names": ["height", "width", "channels"]}
    out["mujoco.state"] = {"dtype": "float64", "shape": [state_size], "names": None}
    for key, dtype in (("next.reward", "float32"), ("next.done", "bool"), ("next.success", "bool"),
                       ("timestamp", "float32"), ("frame_index", "int64"), ("episode_index", "int64"),
                       ("index", "int64"), ("task_index", "int64")):
        out[key] = {"dtype": dtype, "shape": [1], "names": None}
    return out


# ---------------------------------------------------------------- statistics (lerobot's compute_stats)

def _sample_indices(n: int) -> np.ndarray:
    """lerobot's sample_indices: the frames an image's statistics are computed on."""
    count = n if n < 100 else max(100, min(int(n ** 0.75), 10_000))
    return np.round(np.linspace(0, n - 1, count)).astype(int)


def feature_stats(values: np.ndarray, is_image: bool = False) -> dict[str, np.ndarray]:
    """min, max, mean, std (population), count and quantiles of one feature over an episode's
    frames; an image's per channel, in [0, 1], shaped (3, 1, 1), on lerobot's sampled frames
    (downsampled to about 150 px beyond 300)."""
    if is_image:
        sampled = values[_sample_indices(len(values))]
        if max(sampled.shape[1:3]) >= 300:
            stride = max(sampled.shape[1:3]) // 150
            sampled = sampled[:, ::stride, ::stride]
        flat = sampled.reshape(-1, sampled.shape[-1])
        count = len(sampled)
    else:
        flat = values.reshape(len(values), -1)
        count = len(values)
    number = flat.astype(np.float64)
    stats = {"min": flat.min(axis=0), "max": flat.max(axis=0), "mean": number.mean(axis=0), "std": number.std(axis=0),
             "count": np.array([count], dtype=np.int64)}
    for key, q in QUANTILES.items():
        stats[key] = np.quantile(number, q, axis=0)
    if is_image:
        stats = {k: v if k == "count" else (v.astype(np.float64) / 255.0).reshape(-1, 1, 1) for k, v in stats.items()}
    return stats


def aggregate_stats(per_episode: list[dict[str, dict[str, np.ndarray]]]) -> dict[str, dict[str, list]]:
    """lerobot's aggregate_stats: count-weighted means and quantiles, pooled std, min of mins."""
    out = {}
    for key in per_episode[0]:
        stats = [s[key] for s in per_episode]
        counts = np.stack([np.asarray(s["count"]) for s in stats]).astype(np.float64)
        means = np.stack([np.asarray(s["mean"], dtype=np.float64) for s in stats])
        while counts.ndim < means.ndim:
            counts = counts[..., None]
        total = counts.sum(axis=0)
        mean = (means * counts).sum(axis=0) / total
        stds = np.stack([np.asarray(s["std"], dtype=np.float64) for s in stats])
        variance = ((stds ** 2 + (means - mean) ** 2) * counts).sum(axis=0) / total
        merged = {"min": np.min(np.stack([np.asarray(s["min"]) for s in stats]), axis=0),
                  "max": np.max(np.stack([np.asarray(s["max"]) for s in stats]), axis=0),
                  "mean": mean, "std": np.sqrt(variance),
                  "count": np.stack([np.asarray(s["count"]) for s in stats]).sum(axis=0)}
        for q in QUANTILES:
            merged[q] = (np.stack([np.asarray(s[q], dtype=np.float64) for s in stats]) * counts).sum(axis=0) / total
        out[key] = {k: np.asarray(v).tolist() for k, v in merged.items()}
    return out


# ---------------------------------------------------------------- one episode (in the worker)

def encode_video(frames: np.ndarray, fps: float, lossless: bool) -> bytes:
    """An episode's frames (T, H, W, 3) as an mp4 (H.264; lossless: libx264rgb at crf 0)."""
    import av

    height, width = frames.shape[1:3]
    rate = Fraction(fps).limit_denominator(1000)
    buffer = io.BytesIO()
    with av.open(buffer, "w", format="mp4") as container:
        if lossless:
            stream = container.add_stream("libx264rgb", rate=rate, options=dict(LOSSLESS_OPTIONS))
            stream.pix_fmt = "rgb24"
        else:
            stream = container.add_stream("libx264", rate=rate, options=dict(LOSSY_OPTIONS))
            stream.pix_fmt = "yuv420p" if width % 2 == 0 and height % 2 == 0 else "yuv444p"
        stream.width, stream.height = width, height
        stream.codec_context.time_base = 1 / rate
        for k, image in enumerate(frames):
            frame = av.VideoFrame.from_ndarray(np.ascontiguousarray(image), format="rgb24")
            frame.pts = k
            frame.time_base = 1 / rate
            for packet in stream.encode(frame):
                container.mux(packet)
        for packet in stream.encode():
            container.mux(packet)
    return buffer.getvalue()


def decode_video(path: Path | bytes) -> np.ndarray:
    """Every frame of an mp4 as (T, H, W, 3) uint8 RGB."""
    import av

    source = io.BytesIO(path) if isinstance(path, bytes) else str(path)
    with av.open(source) as container:
        return np.stack([f.to_ndarray(format="rgb24") for f in container.decode(video=0)])


def video_info(path: Path) -> dict:
    """info.json's `info` of a video feature (the keys of lerobot's get_video_info)."""
    import av

    with av.open(str(path)) as container:
        stream = container.streams.video[0]
        return {"video.height": stream.height, "video.width": stream.width,
                "video.codec": stream.codec_context.codec.canonical_name, "video.pix_fmt": stream.pix_fmt,
                "video.is_depth_map": False, "video.fps": float(stream.base_rate) if stream.base_rate.denominator != 1
                else int(stream.base_rate), "video.channels": 3, "has_audio": len(container.streams.audio) > 0}


# ---------------------------------------------------------------- files (in the driver)

_ARROW = {"float32": "float32", "float64": "float64", "int64": "int64", "bool": "bool_"}


def data_table(columns: dict[str, np.ndarray], feature_map: dict[str, dict]):
    """One episode's frames as the pyarrow table of its data file (vectors as fixed-size lists)."""
    import pyarrow as pa

    arrays, fields, hf = [], [], {}
    for key, feature in feature_map.items():
        if feature["dtype"] == "video":
            continue
        kind = getattr(pa, _ARROW[feature["dtype"]])()
        values = np.asarray(columns[key])
        if feature["shape"] == [1]:
            array = pa.array(values.reshape(-1), kind)
            hf[key] = {"dtype": feature["dtype"], "_type": "Value"}
        else:
            array = pa.FixedSizeListArray.from_arrays(pa.array(values.reshape(-1), kind), feature["shape"][0])
            hf[key] = {"feature": {"dtype": feature["dtype"], "_type": "Value"}, "length": feature["shape"][0],
                       "_type": "List"}
        arrays.append(array)
        fields.append(pa.field(key, array.type))
    schema = pa.schema(fields, metadata={b"huggingface": json.dumps({"info": {"features": hf}}).encode()})
    return pa.Table.from_arrays(arrays, schema=schema)


def tasks_table(tasks: list[str]):
    """meta/tasks.parquet: the tasks as a pandas frame's index, with their task_index."""
    import pyarrow as pa

    pandas = {"index_columns": ["__index_level_0__"],
              "column_indexes": [{"name": None, "field_name": None, "pandas_type": "unicode", "numpy_type": "object",
                                  "metadata": {"encoding": "UTF-8"}}],
              "columns": [{"name": "task_index", "field_name": "task_index", "pandas_type": "int64",
                           "numpy_type": "int64", "metadata": None},
                          {"name": None, "field_name": "__index_level_0__", "pandas_type": "unicode",
                           "numpy_type": "object", "metadata": None}],
              "attributes": {}, "creator": {"library": "pyarrow", "version": "prsc"}, "pandas_version": "2.2.3"}
    table = pa.table({"task_index": pa.array(range(len(tasks)), pa.int64()),
                      "__index_level_0__": pa.array(tasks, pa.string())})
    return table.replace_schema_metadata({b"pandas": json.dumps(pandas).encode()})


def info_json(feature_map: dict, fps: float, episodes: int, frames: int, tasks: int, robot_type: str) -> dict:
    """meta/info.json."""
    return {"codebase_version": CODEBASE_VERSION, "robot_type": robot_type, "total_episodes": episodes,
            "total_frames": frames, "total_tasks": tasks, "chunks_size": CHUNKS_SIZE, "data_files_size_in_mb": 100,
            "video_files_size_in_mb": 200, "fps": int(fps) if float(fps).is_integer() else fps,
            "splits": {"train": f"0:{episodes}"}, "data_path": DATA_PATH,
            "video_path": VIDEO_PATH if any(f["dtype"] == "video" for f in feature_map.values()) else None,
            "features": feature_map}
