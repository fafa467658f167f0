"""Benchmark of `prsc run --record` (docs/datasets.md): what recording a dataset costs beyond
the campaign and the rendering it cannot avoid.

Run: .venv/bin/python bench/bench_record.py [-n 4] [--size 224] [--fps 20] [--format lerobot]

Compiles franka_pick_camera.prs with its camera at SIZE x SIZE, warms one worker (GL and
render contexts, IK models: episode 0 of each kind, not counted), then measures in this
process, as one worker of `prsc run` runs them, over episodes 1..n-1:
  A  the campaign without recording;
  B  the same frames rendered alone with mujoco.Renderer (each recorded state set, forward-computed,
     rendered);
  C  the recording campaign: frames taken from the step hook, rendered, encoded, committed.
Prints CPU seconds (process time, all threads: the GL rasteriser's too), C / (A + B), frames per
CPU-second of C, and the dataset's size per episode (its episodes' own files; models/ apart).
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time
from pathlib import Path

SPEC = Path(__file__).resolve().parents[1] / "specs" / "pybullet_arm" / "franka_pick_camera.prs"


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("-n", type=int, default=4)
    parser.add_argument("--size", type=int, default=224)
    parser.add_argument("--fps", type=int, default=20)
    parser.add_argument("--format", default="lerobot")
    args = parser.parse_args()
    from prsc.runner.gl import choose_gl_backend

    choose_gl_backend()
    import mujoco
    import pybullet_data

    from prsc.commands.compile import compile_scenes
    from prsc.pipeline.campaign import episode_tasks
    from prsc.runner.controller import parse_target
    from prsc.runner.demo_dataset import DemoDataset
    from prsc.runner.demo_replay import load_stored_model, read_episode
    from prsc.runner.episode_records import RecordSettings
    from prsc.runner.harness import run_episode
    from prsc.runner.worker import _recorded

    with tempfile.TemporaryDirectory(prefix="prsc-record-bench-") as tmp:
        spec = Path(tmp) / "franka_pick_camera.prs"
        spec.write_text(SPEC.read_text().replace("[128, 128]", f"[{args.size}, {args.size}]"))
        root = compile_scenes(str(spec), ["json", "mjcf"], args.n, 0, tmp, include_dirs=[pybullet_data.getDataPath()])
        tasks, _ = episode_tasks(root, range(args.n), 0, parse_target("prsc.runner.pick:pick"), 600.0)
        settings = RecordSettings(args.format, args.fps)
        dataset = DemoDataset(Path(tmp) / "dataset", {"format": args.format, "fps": args.fps}).open()
        run_episode(tasks[0])  # warm-up: this process's GL context, IK models, mesh caches
        _, first = _recorded(settings, tasks[0])
        dataset.add(first, 0)

        start = time.process_time()
        plain = [run_episode(task) for task in tasks[1:]]
        campaign = time.process_time() - start

        start = time.process_time()
        for task in tasks[1:]:
            result, episode = _recorded(settings, task)
            dataset.add(episode, task.index)
        recording = time.process_time() - start
        dataset.close()
        frames = sum(e["frames"] for e in dataset.episodes[1:])
        assert [r.outcome for r in plain] == [json.loads(e["extras"]["prsc/result"])["outcome"]
                                              for e in dataset.episodes[1:]], "recording changed an outcome"

        stored = [read_episode(dataset.root, k) for k in range(1, len(dataset.episodes))]
        model = load_stored_model(stored[0].model_path)
        renderer = mujoco.Renderer(model, args.size, args.size)
        renderer.render()  # warm-up
        start = time.process_time()
        for episode in stored:
            model = load_stored_model(episode.model_path)
            data = mujoco.MjData(model)
            renderer._model = model  # the same render assets for every scene of the spec
            for state in episode.states:
                mujoco.mj_setState(model, data, state, mujoco.mjtState.mjSTATE_INTEGRATION)
                mujoco.mj_forward(model, data)
                renderer.update_scene(data, camera="camera")
                renderer.render()
        rendering = time.process_time() - start
        renderer.close()

        own = [p for p in dataset.root.rglob("*") if p.is_file() and "models" not in p.parts]
        size = sum(p.stat().st_size for p in own) / len(dataset.episodes)
        models = sum(p.stat().st_size for p in (dataset.root / "models").rglob("*") if p.is_file())
        print(f"{len(tasks) - 1} episodes, {frames} frames of {args.size}x{args.size} at {args.fps} fps ({args.format})")
        print(f"A campaign without recording   {campaign:7.2f} CPU s")
        print(f"B frames alone (mujoco.Renderer) {rendering:5.2f} CPU s   {frames / rendering:6.1f} frames per CPU-second")
        print(f"C recording campaign           {recording:7.2f} CPU s   {frames / recording:6.1f} frames per CPU-second")
        print(f"C / (A + B) = {recording / (campaign + rendering):.3f}   (the issue's bound: 1.25)")
        print(f"dataset: {size / 1e6:.2f} MB per episode ({frames / (len(tasks) - 1):.0f} frames), "
              f"plus {models / 1e6:.1f} MB of models and meshes stored once")


if __name__ == "__main__":
    os.environ.setdefault("MUJOCO_GL", "egl")
    main()
