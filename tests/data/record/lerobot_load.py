"""Load a dataset prsc recorded with lerobot's own `LeRobotDataset`, offline, and report what it
reads as JSON (run by a Python that has lerobot: `make lerobot-check`, tests/runner/test_datasets.py).

    python lerobot_load.py DIR --item I [--frame OUT.npy]

prints {"episodes", "frames", "fps", "features": {key: [dtype, shape]}, "lengths", "item": {...}}
and, with --frame, saves the item's first camera image as uint8 (H, W, 3) in OUT.npy.

lerobot 0.4 imports torchvision at module level; torch 2.13's CPU wheels have no torchvision on
PyPI (its CUDA build fails to import next to a CPU torch). Reading a video dataset through
torchcodec uses none of it, so when `import torchvision` fails a stand-in with the names lerobot
imports is put in its place (it raises if lerobot ever calls it).
"""

from __future__ import annotations

import argparse
import importlib.machinery
import json
import os
import sys
import tempfile
import types

os.environ.setdefault("HF_HUB_OFFLINE", "1")
os.environ.setdefault("HF_DATASETS_OFFLINE", "1")
os.environ.setdefault("HF_HUB_DISABLE_TELEMETRY", "1")
os.environ.setdefault("HF_DATASETS_CACHE", tempfile.mkdtemp(prefix="prsc-lerobot-cache-"))


def _torchvision_stand_in() -> None:
    try:
        import torchvision  # noqa: F401
        return
    except Exception:  # missing, or a CUDA build beside a CPU torch
        for name in [m for m in sys.modules if m.split(".")[0] == "torchvision"]:
            del sys.modules[name]

    def unavailable(*args, **kwargs):
        raise RuntimeError("torchvision is not installed: lerobot_load.py's stand-in cannot do this")

    root, transforms, io = (types.ModuleType(n) for n in ("torchvision", "torchvision.transforms", "torchvision.io"))
    transforms.ToTensor = unavailable
    root.transforms, root.io, root.set_video_backend, root.__version__ = transforms, io, unavailable, "0+prsc-stand-in"
    for module in (root, transforms, io):
        module.__spec__ = importlib.machinery.ModuleSpec(module.__name__, None)
        sys.modules[module.__name__] = module


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("root")
    parser.add_argument("--item", type=int, default=0)
    parser.add_argument("--frame", default=None)
    args = parser.parse_args()
    _torchvision_stand_in()
    import numpy as np
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    dataset = LeRobotDataset("local/prsc", root=args.root)
    meta = dataset.meta
    item = dataset[args.item]
    report = {
        "episodes": dataset.num_episodes, "frames": dataset.num_frames, "length": len(dataset), "fps": dataset.fps,
        "features": {k: [f["dtype"], list(f["shape"])] for k, f in dataset.features.items()},
        "lengths": [int(meta.episodes[e]["length"]) for e in range(meta.total_episodes)],
        "tasks": list(meta.tasks.index),
        "item": {"episode_index": int(item["episode_index"]), "frame_index": int(item["frame_index"]),
                 "index": int(item["index"]), "task": item["task"], "state": item["observation.state"].tolist(),
                 "done": bool(item["next.done"])},
    }
    if args.frame and meta.video_keys:
        image = item[meta.video_keys[0]]  # (3, H, W) float in [0, 1]
        np.save(args.frame, np.round(image.permute(1, 2, 0).numpy() * 255).astype(np.uint8))
    print(json.dumps(report))


if __name__ == "__main__":
    main()
