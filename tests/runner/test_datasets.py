"""`prsc run --record`: LeRobot v3 and robomimic datasets of a campaign, checked against the
formats' documented fields, the same with --jobs 2 and after a kill and a resume, replayed
to the recorded poses and frames, and bad input refused with nothing recorded touched."""

from __future__ import annotations

import hashlib
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

pa = pytest.importorskip("pyarrow")
pq = pytest.importorskip("pyarrow.parquet")
h5py = pytest.importorskip("h5py")
av = pytest.importorskip("av")

from prsc.cli import main  # noqa: E402

DATA = Path(__file__).resolve().parents[1] / "data" / "record"
SPEC = str(DATA / "panda_camera.prs")
WAVE = f"{DATA / 'wave.py'}:wave"
EPISODES = 3
FPS = 10
FRAMES = 6  # 0.6 simulated s at 10 fps: frames at 0.0 .. 0.5 s

# LeRobot v3.0's documented fields (lerobot/datasets/utils.py, docs "LeRobotDataset v3.0")
INFO_KEYS = {"codebase_version", "robot_type", "total_episodes", "total_frames", "total_tasks", "chunks_size",
             "data_files_size_in_mb", "video_files_size_in_mb", "fps", "splits", "data_path", "video_path", "features"}
DEFAULT_FEATURES = {"timestamp": "float32", "frame_index": "int64", "episode_index": "int64", "index": "int64",
                    "task_index": "int64"}
EPISODE_COLUMNS = {"episode_index", "tasks", "length", "data/chunk_index", "data/file_index", "dataset_from_index",
                   "dataset_to_index", "meta/episodes/chunk_index", "meta/episodes/file_index"}
VIDEO_COLUMNS = {"chunk_index", "file_index", "from_timestamp", "to_timestamp"}
STATS = {"min", "max", "mean", "std", "count", "q01", "q10", "q50", "q90", "q99"}
VIDEO_INFO = {"video.height", "video.width", "video.codec", "video.pix_fmt", "video.is_depth_map", "video.fps",
              "video.channels", "has_audio"}


@pytest.fixture(scope="module")
def out(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("record")


def record(out: Path, name: str, *extra: str, run: str = "run") -> tuple[int, Path]:
    folder = out / name
    code = main(["run", SPEC, "--controller", WAVE, "-n", str(EPISODES), "-o", str(out / run), "--record", str(folder),
                 "--fps", str(FPS), *extra])
    return code, folder


@pytest.fixture(scope="module")
def lerobot_dataset(out) -> Path:
    code, folder = record(out, "lerobot", "--lossless")
    assert code == 0
    return folder


def check_lerobot_layout(root: Path, episodes: int) -> dict:
    """The v3 layout: info.json's fields and features, every episode's data and video file, the
    episodes' metadata, tasks and stats; returns info.json."""
    info = json.loads((root / "meta/info.json").read_text())
    assert set(info) == INFO_KEYS and info["codebase_version"] == "v3.0"
    assert info["total_episodes"] == episodes and info["splits"] == {"train": f"0:{episodes}"}
    assert info["data_path"] == "data/chunk-{chunk_index:03d}/file-{file_index:03d}.parquet"
    assert info["video_path"] == "videos/{video_key}/chunk-{chunk_index:03d}/file-{file_index:03d}.mp4"
    features = info["features"]
    for key, dtype in DEFAULT_FEATURES.items():
        assert features[key] == {"dtype": dtype, "shape": [1], "names": None}
    for key in ("observation.state", "action", "next.reward", "next.done", "next.success"):
        assert set(features[key]) == {"dtype", "shape", "names"}
    camera = features["observation.images.camera"]
    assert camera["dtype"] == "video" and camera["shape"] == [64, 64, 3] and set(camera["info"]) == VIDEO_INFO
    assert len(features["observation.state"]["names"]) == features["observation.state"]["shape"][0]
    assert any(n.endswith("gripper_opening") for n in features["observation.state"]["names"])

    rows = pq.read_table(root / "meta/episodes/chunk-000/file-000.parquet").to_pylist()
    assert [r["episode_index"] for r in rows] == list(range(episodes))
    frames = 0
    for row in rows:
        assert EPISODE_COLUMNS <= set(row)
        assert {f"videos/observation.images.camera/{c}" for c in VIDEO_COLUMNS} <= set(row)
        assert {f"stats/{k}/{s}" for k in features for s in STATS} <= set(row)
        assert row["dataset_from_index"] == frames and row["dataset_to_index"] == frames + row["length"]
        data = pq.read_table(root / info["data_path"].format(chunk_index=row["data/chunk_index"],
                                                             file_index=row["data/file_index"]))
        assert data.column_names == [k for k, f in features.items() if f["dtype"] != "video"]
        assert data.schema.field("observation.state").type == pa.list_(pa.float32(), features["observation.state"]["shape"][0])
        assert data.column("index").to_pylist() == list(range(frames, frames + row["length"]))
        assert data.column("episode_index").to_pylist() == [row["episode_index"]] * row["length"]
        assert np.allclose(data.column("timestamp").to_numpy(), np.arange(row["length"]) / info["fps"])
        assert data.column("next.done").to_pylist() == [False] * (row["length"] - 1) + [True]  # no task: the last frame
        assert data.column("next.reward").to_pylist() == [0.0] * row["length"]
        video = root / info["video_path"].format(video_key="observation.images.camera",
                                                 chunk_index=row["videos/observation.images.camera/chunk_index"],
                                                 file_index=row["videos/observation.images.camera/file_index"])
        with av.open(str(video)) as container:
            assert sum(1 for _ in container.decode(video=0)) == row["length"]
        assert row["videos/observation.images.camera/to_timestamp"] == pytest.approx(row["length"] / info["fps"])
        frames += row["length"]
    assert info["total_frames"] == frames
    tasks = pq.read_table(root / "meta/tasks.parquet")
    assert tasks.column("task_index").to_pylist() == [0] and tasks.column("__index_level_0__").to_pylist() == ["panda_camera"]
    stats = json.loads((root / "meta/stats.json").read_text())
    assert set(stats) == set(features) and all(set(s) == STATS for s in stats.values())
    assert stats["index"]["count"] == [frames] and stats["index"]["max"] == [frames - 1]
    assert np.array(stats["observation.images.camera"]["mean"]).shape == (3, 1, 1)
    return info


def test_lerobot_dataset_has_the_v3_layout_and_replays_exactly(lerobot_dataset):
    info = check_lerobot_layout(lerobot_dataset, EPISODES)
    assert info["total_frames"] == EPISODES * FRAMES and info["fps"] == FPS
    rows = pq.read_table(lerobot_dataset / "meta/episodes/chunk-000/file-000.parquet").to_pylist()
    model = lerobot_dataset / rows[0]["prsc/model_file"]
    assert model.is_file() and json.loads(rows[2]["prsc/scene"])["index"] == 2
    assert [r["prsc/outcome"] for r in rows] == ["success", "fail", "success"]
    from prsc.runner.demo_replay import replay

    for episode in range(EPISODES):
        report = replay(lerobot_dataset, episode)
        assert report.frames == FRAMES
        assert report.position_error <= 1e-9
        assert report.image_error == {"camera": 0.0}  # lossless video: the same frames
        assert report.replayed["camera"].std() > 1.0  # a picture, not a blank


def _files(root: Path, pattern: str) -> dict[str, bytes]:
    return {p.relative_to(root).as_posix(): p.read_bytes() for p in sorted(root.glob(pattern))}


def test_two_jobs_write_the_same_dataset(out, lerobot_dataset):
    code, two = record(out, "lerobot_jobs2", "--lossless", "--jobs", "2")
    assert code == 0
    for pattern in ("data/*/*.parquet", "meta/episodes/*/*.parquet", "meta/*.json", "meta/tasks.parquet"):
        assert _files(two, pattern) == _files(lerobot_dataset, pattern)


def test_a_killed_recording_is_a_dataset_and_resumes_to_the_uninterrupted_one(out, lerobot_dataset):
    folder = out / "killed"
    command = [sys.executable, "-m", "prsc.cli", "run", SPEC, "--controller", WAVE, "-n", str(EPISODES),
               "-o", str(out / "run"), "--record", str(folder), "--fps", str(FPS), "--lossless"]  # scenes compiled
    process = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                               env=dict(os.environ, MUJOCO_GL=os.environ.get("MUJOCO_GL", "egl")))
    deadline = time.monotonic() + 240
    state = folder / "prsc-dataset.json"
    while time.monotonic() < deadline and process.poll() is None:
        try:
            if json.loads(state.read_text())["processed"] >= 1:
                break
        except (OSError, ValueError, KeyError):
            pass
        time.sleep(0.05)
    process.send_signal(signal.SIGINT)
    assert process.wait(timeout=120) in (0, 130)
    done = json.loads(state.read_text())["processed"]
    assert 1 <= done <= EPISODES
    check_lerobot_layout(folder, done)  # a finished dataset of the episodes before the kill
    if _lerobot_python() is not None:  # and lerobot reads it so
        loaded = subprocess.run([_lerobot_python(), str(DATA / "lerobot_load.py"), str(folder)],
                                capture_output=True, text=True, timeout=600)
        assert loaded.returncode == 0, loaded.stderr[-2000:]
        assert json.loads(loaded.stdout.strip().splitlines()[-1])["episodes"] == done
    assert subprocess.run(command, capture_output=True).returncode == 0  # the same command resumes
    check_lerobot_layout(folder, EPISODES)
    for pattern in ("data/*/*.parquet", "meta/episodes/*/*.parquet", "meta/*.json", "videos/*/*/*.mp4"):
        assert _files(folder, pattern) == _files(lerobot_dataset, pattern)


def test_robomimic_keeps_the_successes_with_robomimic_keys(out):
    code, folder = record(out, "robomimic", "--format", "robomimic", "--keep", "success")
    assert code == 0
    with h5py.File(folder / "demo.hdf5", "r", swmr=True, libver="latest") as f:  # as robomimic opens it
        assert sorted(f["data"]) == ["demo_0", "demo_1"]  # scenes 0 and 2: scene 1 failed
        assert f["data"].attrs["total"] == 2 * FRAMES
        assert [n.decode() for n in f["mask/successful"][()]] == ["demo_0", "demo_1"]
        env_args = json.loads(f["data"].attrs["env_args"])
        assert env_args["type"] == 2 and env_args["env_kwargs"] == {"spec": SPEC, "frame_skip": 50}
        for name in ("demo_0", "demo_1"):
            demo = f["data"][name]
            assert demo.attrs["num_samples"] == FRAMES and demo.attrs["model_file"].startswith("<mujoco")
            assert demo["actions"].shape == (FRAMES, len(json.loads(demo.attrs["action_names"])))
            assert demo["states"].shape[0] == FRAMES and demo["rewards"].shape == demo["dones"].shape == (FRAMES,)
            assert demo["obs/camera_image"].shape == (FRAMES, 64, 64, 3) and demo["obs/camera_image"].dtype == np.uint8
            assert demo["obs/state"].shape == (FRAMES, len(json.loads(demo.attrs["state_names"])))
            assert demo["obs/object"].shape == (FRAMES, 7)
            assert set(demo["next_obs"]) == set(demo["obs"])
            assert np.array_equal(demo["next_obs/camera_image"][:-1], demo["obs/camera_image"][1:])
        assert json.loads(f["data/demo_1"].attrs["prsc_scene"])["index"] == 2
    from prsc.runner.demo_replay import replay

    report = replay(folder, 1)
    assert report.position_error <= 1e-9 and report.image_error == {"camera": 0.0}


def _snapshot(root: Path) -> dict[str, str]:
    return {p.relative_to(root).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(root.rglob("*")) if p.is_file()}


def test_bad_input_is_refused_and_nothing_recorded_is_touched(out, lerobot_dataset, tmp_path, capsys):
    before = _snapshot(lerobot_dataset)
    for extra, message, run in ((["--seed", "1"], "another recording: seed", "run_seed1"),
                                (["--format", "robomimic"], "another recording: format", "run")):
        code, _ = record(out, "lerobot", "--lossless", *extra, run=run)
        assert code == 2 and message in capsys.readouterr().err
    assert _snapshot(lerobot_dataset) == before
    code, _ = record(out, "too_fast", "--fps", "1000")
    assert code == 2 and "above the control rate" in capsys.readouterr().err
    no_camera = tmp_path / "no_camera.prs"
    no_camera.write_text("\n".join(line for line in Path(SPEC).read_text().splitlines() if not line.startswith("camera")))
    code = main(["run", str(no_camera), "--controller", WAVE, "-n", "1", "-o", str(tmp_path / "run"),
                 "--record", str(tmp_path / "ds")])
    assert code == 2 and "no camera object" in capsys.readouterr().err
    assert not (tmp_path / "ds").exists()


def test_record_episodes_wraps_a_scene_env_of_a_users_policy(tmp_path):
    gymnasium = pytest.importorskip("gymnasium")
    import prsc

    folder = tmp_path / "gym"
    env = prsc.RecordEpisodes(prsc.SceneEnv(SPEC, render_mode="rgb_array", frame_skip=50), folder, lossless=True)
    for episode in range(2):
        env.reset(seed=0) if episode == 0 else env.reset()
        for _ in range(4):
            env.step(env.unwrapped.data.ctrl + 0.05)
    joint1 = env.unwrapped.model.actuator("arm/panda_joint1").id  # a wide range (the gripper's is 0-0.04 m)
    env.close()
    info = check_lerobot_layout(folder, 2)
    assert info["fps"] == 10 and info["total_frames"] == 8  # 50 steps of 2 ms a frame
    from prsc.runner.demo_replay import replay

    report = replay(folder, 1)
    assert report.position_error <= 1e-9 and report.image_error == {"camera": 0.0}
    data = pq.read_table(folder / "data/chunk-000/file-001.parquet")
    actions = np.array(data.column("action").to_pylist())
    assert np.all(np.diff(actions[:, joint1]) > 0.04)  # each step's action, as sent
    from gymnasium.utils.env_checker import check_env

    checked = prsc.RecordEpisodes(prsc.SceneEnv(SPEC, frame_skip=50), tmp_path / "checked", images=False)
    check_env(checked, skip_render_check=True)
    checked.close()
    assert isinstance(checked, gymnasium.Wrapper) and (tmp_path / "checked" / "meta/info.json").is_file()


def _lerobot_python() -> str | None:
    """A Python with lerobot: $PRSC_LEROBOT_PYTHON (make lerobot-check sets it), else this one when it has lerobot."""
    import importlib.util

    given = os.environ.get("PRSC_LEROBOT_PYTHON")
    if given:
        return given
    return sys.executable if importlib.util.find_spec("lerobot") is not None else None


@pytest.mark.skipif(_lerobot_python() is None, reason="lerobot is not installed (make lerobot-check installs it)")
def test_lerobot_loads_the_dataset_and_decodes_a_fresh_render(lerobot_dataset, tmp_path):
    item = FRAMES + 3  # episode 1, frame 3
    frame = tmp_path / "frame.npy"
    done = subprocess.run([_lerobot_python(), str(DATA / "lerobot_load.py"), str(lerobot_dataset), "--item", str(item),
                           "--frame", str(frame)], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    report = json.loads(done.stdout.strip().splitlines()[-1])
    assert report["episodes"] == EPISODES and report["frames"] == report["length"] == EPISODES * FRAMES
    assert report["lengths"] == [FRAMES] * EPISODES and report["tasks"] == ["panda_camera"]
    info = json.loads((lerobot_dataset / "meta/info.json").read_text())
    assert report["features"] == {k: [f["dtype"], f["shape"]] for k, f in info["features"].items()}
    assert report["item"]["episode_index"] == 1 and report["item"]["frame_index"] == 3 and report["item"]["index"] == item
    from prsc.runner.demo_replay import replay

    fresh = replay(lerobot_dataset, 1).replayed["camera"][3]  # the stored state, rendered again
    assert np.array_equal(np.load(frame), fresh)


@pytest.mark.parametrize("name", ["lerobot", "robomimic"])
def test_a_hard_kill_inside_a_commit_is_repaired_on_opening(out, lerobot_dataset, name):
    """SIGKILL after an episode's files and metadata were written but before prsc-dataset.json
    counted it (the commit's last write): opening the folder drops that episode, and what is left
    reads as a dataset of the episodes before it."""
    import shutil

    from prsc.runner.demo_dataset import DemoDataset

    source = lerobot_dataset if name == "lerobot" else out / "robomimic"
    if not source.exists():
        record(out, "robomimic", "--format", "robomimic", "--keep", "success")
    folder = out / f"hard_kill_{name}"
    shutil.copytree(source, folder)
    state = json.loads((folder / "prsc-dataset.json").read_text())
    kept = len(state["episodes"]) - 1
    state["episodes"], state["processed"] = state["episodes"][:kept], state["processed"] - 1
    (folder / "prsc-dataset.json").write_text(json.dumps(state))
    (folder / ".prsc-scratch").mkdir(exist_ok=True)
    (folder / ".prsc-scratch" / "1-file-003.parquet").write_bytes(b"cut short")
    key = {k: v for k, v in state["key"].items() if k != "keep"}
    dataset = DemoDataset(folder, key, state["key"]["keep"]).open()
    assert not (folder / ".prsc-scratch" / "1-file-003.parquet").exists()
    dataset.close()
    assert not (folder / ".prsc-scratch").exists()
    if name == "lerobot":
        check_lerobot_layout(folder, kept)
        assert not (folder / f"data/chunk-000/file-{kept:03d}.parquet").exists()
    else:
        with h5py.File(folder / "demo.hdf5", "r") as f:
            assert sorted(f["data"]) == [f"demo_{k}" for k in range(kept)]
            assert f["data"].attrs["total"] == kept * FRAMES
        assert sorted(p.name for p in (folder / "demos").iterdir()) == [f"demo_{k}.hdf5" for k in range(kept)]
