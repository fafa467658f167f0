"""`prsc preview`: a contact sheet of sampled scenes, rendered offscreen with MuJoCo.

    prsc preview FILE -n 16 -o sheet.png [--seed S] [-I DIR] [--view top|front|iso | --camera NAME]

Each scene is compiled to MJCF in a temporary folder and rendered from the same viewpoint,
so the sheet shows the spread of the distribution at a glance. --view picks a standard
view framing the scene's objects: iso (default: from the front right, 30 degrees down),
top (straight down, +y up in the image) or front (level, looking along +y). --camera NAME
renders what the spec's camera object NAME sees (its fovy and aspect ratio). FILE is a
.prs spec or scene JSON (.json / .jsonl).
"""

from __future__ import annotations

import argparse
import math
import os
import tempfile
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from prsc.pipeline.outputs import output_file, write_error
from prsc.errors import PrscError

TILE = (320, 240)  # width, height of one scene's image
VIEWS = {"iso": (-60.0, -30.0), "top": (90.0, -90.0), "front": (90.0, 0.0)}
"""Standard views: (azimuth, elevation) of MuJoCo's free camera in degrees; azimuth 90
looks along +y, elevation -90 looks straight down."""


def add_parser(subparsers: Any) -> None:
    """Register `prsc preview`."""
    parser = subparsers.add_parser("preview", help="render a contact sheet of sampled scenes", description=__doc__,
                                   formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("file", metavar="FILE", help="a .prs spec, or scene JSON (.json / .jsonl)")
    parser.add_argument("-n", "--scenes", type=int, default=16, help="number of scenes (default 16)")
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    parser.add_argument("-o", "--output", default="sheet.png", help="output image (default sheet.png)")
    parser.add_argument("--include", "-I", action="append", default=[], metavar="DIR", help="also search DIR for imports")
    where = parser.add_mutually_exclusive_group()
    where.add_argument("--view", choices=sorted(VIEWS), default="iso", help="standard view (default iso)")
    where.add_argument("--camera", metavar="NAME", help="render from the spec's camera object NAME")


def _scenes(file: str, n: int, seed: int, include_dirs: Sequence[str] = ()) -> list[dict]:
    """The first n scenes of a spec (sampled) or of scene JSON (read)."""
    from prsc.pipeline.scene_sources import read_scene_file, spec_sampler

    path = Path(file)
    if path.suffix in (".json", ".jsonl"):
        return read_scene_file(path)[:n]
    sample = spec_sampler(file, seed, include_dirs)
    return [sample(k) for k in range(n)]


def _framing(scene: dict) -> tuple[np.ndarray, float]:
    """Centre and radius of the region the scene's objects occupy (their box corners)."""
    from prsc.geometry.rotations import quat_to_matrix

    corners = []
    for o in scene["objects"]:
        half = np.asarray(o["dimensions"], float) / 2
        rot = quat_to_matrix(o["quaternion"])
        signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], float)
        corners.append(np.asarray(o["position"], float) + (signs * half) @ rot.T)
    if not corners:
        return np.array([0.0, 0.0, 0.5]), 1.5
    points = np.concatenate(corners)
    low, high = points.min(axis=0), points.max(axis=0)
    return (low + high) / 2, max(float(np.linalg.norm(high - low)) / 2, 0.3)


def camera_object(scene: dict, name: str) -> dict:
    """The camera object `name` of a scene, or a PrscError listing the scene's cameras."""
    from prsc.ir.scope import did_you_mean

    cameras = [o["name"] for o in scene["objects"] if o.get("camera")]
    for o in scene["objects"]:
        if o["name"] == name and o.get("camera"):
            return o
    if any(o["name"] == name for o in scene["objects"]):
        raise PrscError(f"--camera {name}: object {name!r} is not a camera (a camera object has `camera True`, "
                        "e.g. class Camera of the model library)")
    known = f"its cameras are {', '.join(cameras)}" if cameras else "it has no camera objects"
    raise PrscError(f"--camera {name}: scene {scene.get('index', 0)} has no object {name!r}; {known}"
                    f"{did_you_mean(name, cameras)}")


def render_scene(scene: dict, folder: Path, size: tuple[int, int] = TILE, view: str = "iso",
                 camera_name: str | None = None, include_dirs: Sequence[str] = ()) -> np.ndarray:
    """An RGB image (height, width, 3) of one scene from a standard view or a camera object
    (meshes and model files found as `compile -I include_dirs` finds them)."""
    import mujoco

    from prsc.backends.mjcf import render
    from prsc.runner.harness import fresh_data, load_model
    from prsc.backends.scene import parse_scene
    from prsc.backends.store import AssetStore

    path = folder / "mjcf" / f"{scene.get('index', 0)}.xml"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(render(parse_scene(scene), path, AssetStore(folder / "assets", include_dirs)))
    model = load_model(path)
    data = fresh_data(model)
    if camera_name is not None:
        # The backends name an object's camera after the object (it looks along its +y).
        camera: Any = camera_name
    else:
        centre, radius = _framing(scene)
        camera = mujoco.MjvCamera()
        camera.type = mujoco.mjtCamera.mjCAMERA_FREE
        camera.lookat[:] = centre
        # The objects' bounding sphere nearly fills MuJoCo's default 45 degree field of view.
        camera.distance = 0.8 * radius / math.sin(math.radians(45) / 2)
        camera.azimuth, camera.elevation = VIEWS[view]
    width, height = size
    model.vis.global_.offwidth = max(model.vis.global_.offwidth, width)
    model.vis.global_.offheight = max(model.vis.global_.offheight, height)
    renderer = mujoco.Renderer(model, height, width)
    try:
        renderer.update_scene(data, camera=camera)
        return renderer.render().copy()
    finally:
        renderer.close()


def contact_sheet(images: list[np.ndarray], labels: list[str], output: Path) -> None:
    """Tile images in a near-square grid with a label over each, saved as PNG."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cols = max(1, math.ceil(math.sqrt(len(images))))
    rows = max(1, math.ceil(len(images) / cols))
    height, width = images[0].shape[:2] if images else (TILE[1], TILE[0])
    figure, axes = plt.subplots(rows, cols, figsize=(cols * width / 100, rows * (height + 24) / 100), dpi=100, squeeze=False)
    for ax in axes.flat:
        ax.axis("off")
    for ax, image, label in zip(axes.flat, images, labels):
        ax.imshow(image)
        ax.set_title(label, fontsize=9)
    figure.tight_layout(pad=0.3)
    figure.savefig(output, format="png")
    plt.close(figure)


def preview(file: str, n: int, seed: int, output: str, include_dirs: Sequence[str] = (), view: str = "iso",
            camera: str | None = None) -> Path:
    """Render `n` scenes of `file` from `view` (or the camera object `camera`) into a contact sheet PNG."""
    if n < 1:
        raise PrscError(f"-n must be >= 1, got {n}")
    if Path(output).suffix.lower() != ".png":
        raise PrscError(f"the contact sheet is a PNG: {output} should end in .png")
    out = output_file(output)
    os.environ.setdefault("MUJOCO_GL", "egl")
    if view not in VIEWS:
        raise PrscError(f"unknown view {view!r} (one of {', '.join(sorted(VIEWS))})")
    scenes = _scenes(file, n, seed, include_dirs)
    sizes = [TILE] * len(scenes)
    if camera is not None:
        # Every scene is checked before any is rendered; tiles keep the camera's aspect ratio.
        resolutions = [camera_object(scene, camera)["camera"]["resolution"] for scene in scenes]
        sizes = [(TILE[0], max(1, round(TILE[0] * h / w))) for w, h in resolutions]
    with tempfile.TemporaryDirectory(prefix="prsc-preview-") as tmp:
        images = [render_scene(scene, Path(tmp), size, view, camera, include_dirs) for scene, size in zip(scenes, sizes)]
    labels = [f"scene {s.get('index', k)}" for k, s in enumerate(scenes)]
    import io

    from prsc.files import atomic_write

    buffer = io.BytesIO()
    contact_sheet(images, labels, buffer)  # type: ignore[arg-type]
    try:
        atomic_write(out, buffer.getvalue())
    except OSError as error:
        raise write_error(error, output) from None
    return out


def run(args: argparse.Namespace) -> int:
    """Entry point of `prsc preview`."""
    preview(args.file, args.scenes, args.seed, args.output, args.include, args.view, args.camera)
    return 0
