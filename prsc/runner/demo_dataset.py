"""A demonstration dataset folder (LeRobot v3 or robomimic, docs/datasets.md): episodes encoded
where they ran (`encode_episode`, in the worker), then committed by one writer in scene-index
order (`DemoDataset`), so any number of workers write the same dataset as one.

The folder is a finished dataset after every committed episode: an episode's own files
first, then the metadata that lists it, then `prsc-dataset.json` (what the folder is, and how
many scenes of the campaign it has taken); Ctrl-C waits for a commit to end. Opening the
folder again drops what a hard kill left beyond the last finished commit, and resumes.
"""

from __future__ import annotations

import fcntl
import json
import os
import re
import shutil
import signal
from pathlib import Path

import numpy as np

from prsc.backends.names import with_body_names
from prsc.errors import PrscError
from prsc.files import atomic_path

from prsc.runner import lerobot_format as lerobot
from prsc.runner import robomimic_format as robomimic
from prsc.runner.episode_encoding import ASSET_REFERENCE, MODELS, RecordedEpisode

FORMATS = ("lerobot", "robomimic")
KEEP = ("all", "success")
STATE_FILE = "prsc-dataset.json"
LOCK_FILE = ".prsc-dataset-lock"
SCRATCH = ".prsc-scratch"  # files being written, outside the folders a reader globs


def require_libraries() -> None:
    """PrscError unless pyarrow, PyAV and h5py import (the [datasets] extra)."""
    missing = []
    for name in ("pyarrow", "av", "h5py"):
        try:
            __import__(name)
        except ImportError:
            missing.append(name)
    if missing:
        raise PrscError(f"recording a dataset needs {', '.join(missing)}: pip install 'prsc[datasets]'")


def _put(root: Path, path: Path, data: bytes | str | None = None, writer=None) -> None:
    """Write `path` whole (bytes, or `writer(temporary path)`) through a temporary in the scratch folder,
    outside the folders a reader globs, renamed into place (prsc.files.atomic_path)."""
    scratch = root / SCRATCH
    scratch.mkdir(exist_ok=True)
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path, folder=scratch) as temporary:
        if writer is not None:
            writer(temporary)
        else:
            temporary.write_bytes(data.encode() if isinstance(data, str) else data)


class _Deferred:
    """Ctrl-C and SIGTERM wait while a commit writes (main thread only; elsewhere nothing changes)."""

    SIGNALS = {signal.SIGINT, signal.SIGTERM}

    def __enter__(self):
        self.blocked = hasattr(signal, "pthread_sigmask")
        if self.blocked:
            signal.pthread_sigmask(signal.SIG_BLOCK, self.SIGNALS)
        return self

    def __exit__(self, *exc):
        if self.blocked:
            signal.pthread_sigmask(signal.SIG_UNBLOCK, self.SIGNALS)


class DemoDataset:
    """The dataset folder `root` of one recording (its `key`: spec, seed, format, fps...)."""

    def __init__(self, root: Path, key: dict, keep: str = "all", env_args: dict | None = None):
        if key.get("format") not in FORMATS:
            raise PrscError(f"--format must be one of {', '.join(FORMATS)}, got {key.get('format')!r}")
        if keep not in KEEP:
            raise PrscError(f"--keep must be one of {', '.join(KEEP)}, got {keep!r}")
        require_libraries()
        self.root = Path(root)
        self.key = dict(key, keep=keep)
        self.format = key["format"]
        self.keep = keep
        self.env_args = env_args or {}
        self.processed = 0  # scenes 0 .. processed-1 of the campaign are in (or were left out by --keep)
        self.episodes: list[dict] = []  # per committed episode: what the metadata lists
        self.pending: dict[int, RecordedEpisode | None] = {}
        self._lock: int | None = None

    # ------------------------------------------------------------ opening
    def open(self) -> "DemoDataset":
        """Check the folder holds nothing but this same dataset (else PrscError, nothing touched), lock it,
        and take up where it ended."""
        stored = self._stored()
        if stored is None and self.root.exists() and any(p.name != LOCK_FILE for p in self.root.iterdir()):
            raise PrscError(f"{self.root} exists and is not a prsc dataset; choose another folder for --record")
        if stored is not None and stored.get("key") != self.key:
            theirs = stored.get("key") or {}
            differ = [k for k in sorted(set(theirs) | set(self.key)) if theirs.get(k) != self.key.get(k)]
            said = ", ".join(f"{k} {theirs.get(k)!r} (asked: {self.key.get(k)!r})" for k in differ[:4])
            raise PrscError(f"{self.root} holds a dataset of another recording: {said}; "
                            "choose another folder for --record, or remove it")
        try:
            self.root.mkdir(parents=True, exist_ok=True)
            handle = os.open(self.root / LOCK_FILE, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError as error:
            raise PrscError(f"cannot write the dataset folder {self.root}: {os.strerror(error.errno)}") from None
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            os.close(handle)
            raise PrscError(f"{self.root} is being recorded by another prsc run; wait for it or choose another folder") from None
        self._lock = handle
        with _Deferred():
            if stored is None:
                self._save_state()  # from now on the folder says what it is
            else:
                self.processed = int(stored["processed"])
                self.episodes = list(stored["episodes"])
                if self.format == "lerobot":
                    self._read_stats()
                self._repair()
        return self

    def _stored(self) -> dict | None:
        try:
            stored = json.loads((self.root / STATE_FILE).read_text(encoding="utf-8"))
        except FileNotFoundError:
            return None
        except (OSError, ValueError) as error:
            raise PrscError(f"{self.root / STATE_FILE} is unreadable ({error}); remove the folder or choose another") from None
        return stored if isinstance(stored, dict) else None

    def close(self) -> None:
        """Unlock the folder."""
        if self._lock is not None:
            shutil.rmtree(self.root / SCRATCH, ignore_errors=True)
            os.close(self._lock)  # the file stays: unlinking it would let a run that opened it lock a ghost
            self._lock = None

    # ------------------------------------------------------------ adding episodes
    def add(self, episode: RecordedEpisode | None, scene_index: int) -> None:
        """An episode that finished (None: to be left out); committed once every earlier scene is in."""
        self.pending[scene_index] = episode
        while self.processed in self.pending:
            ready = self.pending.pop(self.processed)
            with _Deferred():
                if ready is not None and (self.keep == "all" or ready.success):
                    self._commit(ready)
                self.processed += 1
                self._save_state()
            if ready is not None:
                ready.drop_payload()  # an executor may hold the object until the campaign ends

    def _save_state(self) -> None:
        # the episodes' statistics are in meta/episodes (read back on opening), not rewritten here
        episodes = [{k: v for k, v in e.items() if k != "stats"} for e in self.episodes]
        _put(self.root, self.root / STATE_FILE, json.dumps({"key": self.key, "processed": self.processed,
                                                          "episodes": episodes}, indent=1) + "\n")

    def _commit(self, episode: RecordedEpisode) -> None:
        number = len(self.episodes)
        if self.episodes and [self.episodes[0][k] for k in ("names", "state_size", "cameras")] != \
                [episode.names, episode.state_size, episode.cameras]:
            raise PrscError(f"scene {episode.scene_index} records other features than the dataset's first episode "
                            f"(robots, objects or cameras differ): {self.root} holds one layout")
        self._store_model(episode)
        prefixes = {name.split("/")[0] for name in episode.names["state"]}
        robot_type = "+".join(Path(str(o.get("model"))).stem for o in with_body_names(episode.scene)["objects"]
                              if o["body"] in prefixes) or "none"
        entry = {"scene_index": episode.scene_index, "frames": len(episode), "task": episode.task, "robot_type": robot_type,
                 "model": episode.model_name, "names": episode.names, "state_size": episode.state_size,
                 "cameras": episode.cameras, "success": episode.success,
                 "extras": {"prsc/scene_index": episode.scene_index, "prsc/seed": episode.seed,
                            "prsc/spec_sha256": str(self.key.get("spec_sha256", "")), "prsc/model_file": episode.model_name,
                            "prsc/outcome": str(episode.result.get("outcome", "")),
                            "prsc/result": json.dumps(episode.result), "prsc/scene": json.dumps(episode.scene)}}
        if self.format == "lerobot":
            entry["stats"] = self._commit_lerobot(number, episode)
        else:
            self._commit_robomimic(number, episode)
        self.episodes.append(entry)
        self._write_meta()

    def _store_model(self, episode: RecordedEpisode) -> None:
        """models/<sha>.xml (with the asset files it names, once) or models/<sha>.mjb."""
        path = self.root / episode.model_name
        if path.exists():
            return
        path.parent.mkdir(parents=True, exist_ok=True)
        if episode.model_binary is not None:
            _put(self.root, path, episode.model_binary)
            return
        source_assets = Path(episode.model_source).resolve().parent.parent / "assets"
        for rel in ASSET_REFERENCE.findall(Path(episode.model_source).read_text(encoding="utf-8")):
            target = self.root / MODELS / "assets" / rel
            if not target.exists():
                _put(self.root, target, writer=lambda temporary, rel=rel: shutil.copyfile(source_assets / rel, temporary))
        _put(self.root, path, episode.model_text)

    def _commit_lerobot(self, number: int, episode: RecordedEpisode) -> dict:
        """Write the episode's videos and data file; its statistics per feature."""
        import pyarrow.parquet as pq

        files = lerobot.chunk_file(number)
        for camera, mp4 in episode.videos.items():
            _put(self.root, self.root / lerobot.VIDEO_PATH.format(video_key=lerobot.IMAGE_PREFIX + camera, **files), mp4)
        columns = self._frame_columns(number, episode)
        features = self._features(episode)
        table = lerobot.data_table(columns, features)
        _put(self.root, self.root / lerobot.DATA_PATH.format(**files),
             writer=lambda temporary: pq.write_table(table, temporary, compression="snappy"))
        stats = {}
        for key, feature in features.items():
            if feature["dtype"] == "video":
                stats[key] = episode.image_stats[key[len(lerobot.IMAGE_PREFIX):]]
            else:
                stats[key] = lerobot.feature_stats(np.asarray(columns[key]).reshape(len(episode), -1))
        return {k: {s: np.asarray(v).tolist() for s, v in d.items()} for k, d in stats.items()}

    def _frame_columns(self, number: int, episode: RecordedEpisode) -> dict[str, np.ndarray]:
        frames = len(episode)
        start = sum(e["frames"] for e in self.episodes[:number])
        tasks = self._tasks(extra=episode.task)
        return {**episode.columns, "timestamp": (np.arange(frames) / self.key["fps"]).astype(np.float32),
                "frame_index": np.arange(frames, dtype=np.int64), "episode_index": np.full(frames, number, np.int64),
                "index": np.arange(start, start + frames, dtype=np.int64),
                "task_index": np.full(frames, tasks.index(episode.task), np.int64)}

    def _tasks(self, extra: str | None = None) -> list[str]:
        tasks: list[str] = []
        for task in [e["task"] for e in self.episodes] + ([extra] if extra else []):
            if task not in tasks:
                tasks.append(task)
        return tasks

    def _features(self, episode: RecordedEpisode | dict) -> dict:
        get = episode.get if isinstance(episode, dict) else lambda k: getattr(episode, k)
        from prsc.runner.demo_frames import Camera

        names, cameras = get("names"), [Camera(c["name"], -1, c["width"], c["height"]) for c in get("cameras")]
        return lerobot.features(names["state"], names["action"], names["object"], get("state_size"), cameras)

    def _commit_robomimic(self, number: int, episode: RecordedEpisode) -> None:
        _put(self.root, self.root / robomimic.DEMO_FILE.format(episode=number), episode.hdf5)

    # ------------------------------------------------------------ metadata
    def _write_meta(self) -> None:
        if self.format == "robomimic":
            demos = [(robomimic.DEMO_FILE.format(episode=k), e["frames"], e["success"]) for k, e in enumerate(self.episodes)]
            _put(self.root, self.root / robomimic.INDEX_FILE,
                 writer=lambda temporary: robomimic.write_index(temporary, demos, self.env_args))
            return
        self._write_lerobot_meta()

    def _write_lerobot_meta(self) -> None:
        import pyarrow as pa
        import pyarrow.parquet as pq

        if not self.episodes:
            return
        features = self._features(self.episodes[0])
        tasks = self._tasks()
        rows, per_episode = [], []
        start = 0
        for number, entry in enumerate(self.episodes):
            stats = entry["stats"]
            per_episode.append(stats)
            row = {"episode_index": number, "tasks": [entry["task"]], "length": entry["frames"]}
            files = lerobot.chunk_file(number)
            row.update({"data/chunk_index": files["chunk_index"], "data/file_index": files["file_index"],
                        "dataset_from_index": start, "dataset_to_index": start + entry["frames"]})
            for camera in entry["cameras"]:
                key = lerobot.IMAGE_PREFIX + camera["name"]
                row.update({f"videos/{key}/chunk_index": files["chunk_index"], f"videos/{key}/file_index": files["file_index"],
                            f"videos/{key}/from_timestamp": 0.0, f"videos/{key}/to_timestamp": entry["frames"] / self.key["fps"]})
            for feature, values in stats.items():
                for name, value in values.items():
                    row[f"stats/{feature}/{name}"] = np.asarray(value).tolist()
            row.update({"meta/episodes/chunk_index": number // lerobot.CHUNKS_SIZE, "meta/episodes/file_index": 0})
            row.update(entry["extras"])
            rows.append(row)
            start += entry["frames"]
        for chunk in range(0, len(rows), lerobot.CHUNKS_SIZE):
            table = pa.Table.from_pylist(rows[chunk:chunk + lerobot.CHUNKS_SIZE])
            _put(self.root, self.root / lerobot.EPISODES_PATH.format(chunk_index=chunk // lerobot.CHUNKS_SIZE, file_index=0),
                 writer=lambda temporary, table=table: pq.write_table(table, temporary, compression="snappy"))
        _put(self.root, self.root / "meta/tasks.parquet", writer=lambda t: pq.write_table(lerobot.tasks_table(tasks), t))
        _put(self.root, self.root / "meta/stats.json", json.dumps(lerobot.aggregate_stats(per_episode), indent=4) + "\n")
        for camera in self.episodes[0]["cameras"]:
            key = lerobot.IMAGE_PREFIX + camera["name"]
            features[key]["info"] = lerobot.video_info(self.root / lerobot.VIDEO_PATH.format(video_key=key, **lerobot.chunk_file(0)))
        info = lerobot.info_json(features, self.key["fps"], len(self.episodes), start, len(tasks),
                                 self.episodes[0].get("robot_type", "none"))
        _put(self.root, self.root / "meta/info.json", json.dumps(info, indent=4) + "\n")

    def _read_stats(self) -> None:
        """Each committed episode's statistics, from its meta/episodes row."""
        import pyarrow.parquet as pq

        rows: list[dict] = []
        for path in sorted((self.root / "meta/episodes").glob("*/*.parquet")):
            rows += pq.read_table(path).to_pylist()
        if len(rows) < len(self.episodes):
            raise PrscError(f"{self.root}/meta/episodes lists {len(rows)} episodes, {STATE_FILE} {len(self.episodes)}; "
                            "the dataset is damaged: record into another folder")
        for entry, row in zip(self.episodes, rows):
            stats: dict[str, dict] = {}
            for column, value in row.items():
                if column.startswith("stats/"):
                    feature, _, name = column[len("stats/"):].rpartition("/")
                    stats.setdefault(feature, {})[name] = value
            entry["stats"] = stats

    # ------------------------------------------------------------ after a hard kill
    def _repair(self) -> None:
        """Remove what a kill left beyond the last finished commit; rewrite the metadata of the rest."""
        count = len(self.episodes)
        shutil.rmtree(self.root / SCRATCH, ignore_errors=True)
        if self.format == "lerobot":
            for folder in ("data", "videos"):
                for path in sorted((self.root / folder).rglob("*")) if (self.root / folder).exists() else []:
                    match = re.search(r"chunk-(\d+)/file-(\d+)\.(parquet|mp4)$", path.as_posix())
                    if path.is_file() and match and int(match[1]) * lerobot.CHUNKS_SIZE + int(match[2]) >= count:
                        path.unlink()
        else:
            for path in sorted((self.root / "demos").glob("demo_*.hdf5*")) if (self.root / "demos").exists() else []:
                match = re.fullmatch(r"demo_(\d+)\.hdf5", path.name)
                if match and int(match[1]) >= count:
                    path.unlink()
        if count:
            self._write_meta()
        else:  # killed in the first commit: no metadata may list an episode
            for rel in ("meta/info.json", "meta/stats.json", "meta/tasks.parquet", robomimic.INDEX_FILE):
                (self.root / rel).unlink(missing_ok=True)
            shutil.rmtree(self.root / "meta/episodes", ignore_errors=True)
