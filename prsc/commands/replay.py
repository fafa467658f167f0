"""`prsc replay`: rebuild a recorded episode from its dataset and check it against the recording.

    prsc replay DIR --episode K [--frames OUT]

reads episode K of a dataset `prsc run --record` (or prsc.RecordEpisodes) wrote, LeRobot or
robomimic: the model from the stored MJCF, each frame's stored MuJoCo state set and
forward-computed. It prints how far the objects' poses are from the recorded ones and how
far each camera's re-rendered frames are from the recorded images (0 for --lossless or
robomimic; H.264's tolerance otherwise), and exits 1 when a pose differs by more than 1e-9.
--frames OUT writes the re-rendered frames as PNG files OUT/<camera>_<frame>.png.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from prsc.errors import PrscError

POSE_TOLERANCE = 1e-9  # m: a replayed state is the recorded one, bit for bit up to rounding


def add_parser(subparsers) -> None:
    """Register `prsc replay`."""
    parser = subparsers.add_parser("replay", help="replay a recorded episode of a dataset and compare it with the recording",
                                   description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("dataset", metavar="DIR", type=Path, help="a dataset folder of prsc run --record")
    parser.add_argument("--episode", type=int, required=True, metavar="K", help="the episode (0-based, dataset order)")
    parser.add_argument("--frames", type=Path, default=None, metavar="OUT", help="write the re-rendered frames as PNGs")


def run(args: argparse.Namespace) -> int:
    """Replay and report; 0 when the poses match the recording, 1 when not."""
    from prsc.runner.gl import choose_gl_backend

    if not args.dataset.is_dir():
        raise PrscError(f"{args.dataset}: no such dataset folder")
    choose_gl_backend()
    from prsc.runner.demo_replay import replay

    report = replay(args.dataset, args.episode)
    print(f"episode {report.episode} (scene {report.scene_index}): {report.frames} frames replayed from {args.dataset}")
    print(f"  object poses: largest difference from the recording {report.position_error:.3g}")
    for camera, worst in report.image_error.items():
        print(f"  camera {camera}: largest pixel difference {worst:g} of 255, mean {report.image_mean_error[camera]:.3g}")
    if args.frames is not None:
        from PIL import Image

        args.frames.mkdir(parents=True, exist_ok=True)
        for camera, frames in report.replayed.items():
            for k, frame in enumerate(frames):
                Image.fromarray(frame).save(args.frames / f"{camera}_{k:05d}.png")
        print(f"  frames written to {args.frames}")
    return 0 if report.position_error <= POSE_TOLERANCE else 1
