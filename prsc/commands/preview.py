"""`prsc preview`: a contact sheet of sampled scenes, rendered offscreen with MuJoCo.

    prsc preview FILE -n 16 -o sheet.png [--seed S] [-I DIR]

Each scene is compiled to MJCF in a temporary folder and rendered from the same oblique
viewpoint framing the scene's objects, so the sheet shows the spread of the distribution
at a glance. FILE is a .prs spec or scene JSON (.json / .jsonl).
"""

from __future__ import annotations

import argparse
import math
import os
import tempfile
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from prsc.commands.outputs import output_file, write_error
from prsc.errors import PrscError

TILE = (320, 240)  # width, height of one scene's image


def add_parser(subparsers: Any) -> None:
    """Register `prsc preview`."""
    parser = subparsers.add_parser("preview", help="render a contact sheet of sampled scenes", description=__doc__,
                                   formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("file", metavar="FILE", help="a .prs spec, or scene JSON (.json / .jsonl)")
    parser.add_argument("-n", "--scenes", type=int, default=16, help="number of scenes (default 16)")
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    parser.add_argument("-o", "--output", default="sheet.png", help="output image (default sheet.png)")
    parser.add_argument("--include", "-I", action="append", default=[], metavar="DIR", help="also search DIR for imports")


def _scenes(file: str, n: int, seed: int, include_dirs: Sequence[str] = ()) -> list[dict]:
    """The first n scenes of a spec (sampled) or of scene JSON (read)."""
    from prsc.commands.scene_sources import read_scene_file, spec_sampler

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


def render_scene(scene: dict, folder: Path, size: tuple[int, int] = TILE) -> np.ndarray:
    """An RGB image (height, width, 3) of one scene from an oblique overview camera."""
    import mujoco

    from prsc.backends.mjcf import render
    from prsc.backends.scene import parse_scene
    from prsc.backends.store import AssetStore

    path = folder / "mjcf" / f"{scene.get('index', 0)}.xml"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(render(parse_scene(scene), path, AssetStore(folder / "assets")))
    model = mujoco.MjModel.from_xml_path(str(path))
    data = mujoco.MjData(model)
    if model.nkey:
        mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
    mujoco.mj_forward(model, data)
    centre, radius = _framing(scene)
    camera = mujoco.MjvCamera()
    camera.type = mujoco.mjtCamera.mjCAMERA_FREE
    camera.lookat[:] = centre
    # The objects' bounding sphere nearly fills MuJoCo's default 45 degree field of view.
    camera.distance = 0.8 * radius / math.sin(math.radians(45) / 2)
    camera.azimuth = -60.0  # from the front right, looking back along +y
    camera.elevation = -30.0
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


def preview(file: str, n: int, seed: int, output: str, include_dirs: Sequence[str] = ()) -> Path:
    """Render `n` scenes of `file` into a contact sheet PNG at `output`."""
    if n < 1:
        raise PrscError(f"-n must be >= 1, got {n}")
    if Path(output).suffix.lower() != ".png":
        raise PrscError(f"the contact sheet is a PNG: {output} should end in .png")
    out = output_file(output)
    os.environ.setdefault("MUJOCO_GL", "egl")
    scenes = _scenes(file, n, seed, include_dirs)
    with tempfile.TemporaryDirectory(prefix="prsc-preview-") as tmp:
        images = [render_scene(scene, Path(tmp)) for scene in scenes]
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
    preview(args.file, args.scenes, args.seed, args.output, args.include)
    return 0
