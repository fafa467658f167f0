"""`prsc preview --view top|front|iso` and `--camera NAME`: what each viewpoint shows."""

from __future__ import annotations

import json

import numpy as np

from prsc.cli import main
from tests.backends.scenes import obj, on_ground, scene

RED, BLUE = (1.0, 0.0, 0.0, 1.0), (0.0, 0.0, 1.0, 1.0)


def _two_cubes_and_a_camera() -> dict:
    """A red cube at +x, a blue cube at +y, and a camera at -y looking along +y at the blue one."""
    size = (0.1, 0.1, 0.1)
    return scene([
        obj("red", "Cube", on_ground(size, 0.5, 0.0), size, color=RED),
        obj("blue", "Cube", on_ground(size, 0.0, 0.5), size, color=BLUE),
        obj("eye", "Camera", (0.0, -0.5, 0.05), (0.05, 0.05, 0.05), static=True, model="camera",
            camera={"fovy": 30.0, "resolution": [160, 120]}),
    ])


def _centroid(image: np.ndarray, channel: int) -> np.ndarray | None:
    """Pixel centroid (column, row) of the strongly red (0) or blue (2) pixels."""
    rgb = image[..., :3].astype(float)
    others = [c for c in range(3) if c != channel]
    mask = (rgb[..., channel] > 100) & (rgb[..., others].max(axis=-1) < 60)
    if mask.sum() < 20:
        return None
    rows, cols = np.nonzero(mask)
    return np.array([cols.mean(), rows.mean()])


def test_standard_views_and_a_camera_object_see_what_they_should(tmp_path):
    from prsc.commands.preview import render_scene

    s = _two_cubes_and_a_camera()
    top = render_scene(s, tmp_path, view="top")
    red, blue = _centroid(top, 0), _centroid(top, 2)
    assert red[0] > blue[0] + 20, "top view: +x is to the right"
    assert blue[1] < red[1] - 20, "top view: +y is up"
    front = render_scene(s, tmp_path, view="front")
    red, blue = _centroid(front, 0), _centroid(front, 2)
    assert red[0] > blue[0] + 20, "front view looks along +y: +x is to the right"
    assert abs(red[1] - blue[1]) < 0.1 * front.shape[0], "front view is level: both cubes at one height"
    seen = render_scene(s, tmp_path, size=(160, 120), camera_name="eye")
    assert seen.shape[:2] == (120, 160)
    centre = _centroid(seen, 2)
    assert centre is not None and np.allclose(centre, [80, 60], atol=8), "the camera looks straight at blue"
    assert _centroid(seen, 0) is None, "red is outside the camera's 30 degree view"


def test_camera_preview_through_the_cli_and_its_errors(tmp_path, capsys):
    import matplotlib.image

    source = tmp_path / "scene.json"
    source.write_text(json.dumps(_two_cubes_and_a_camera()))
    out = tmp_path / "sheet.png"
    assert main(["preview", str(source), "-n", "1", "--camera", "eye", "-o", str(out)]) == 0
    image = matplotlib.image.imread(out)
    assert image.shape[1] >= 320
    assert main(["preview", str(source), "-n", "1", "--camera", "ey", "-o", str(tmp_path / "x.png")]) == 2
    assert capsys.readouterr().err == ("prsc: error: --camera ey: scene 0 has no object 'ey'; its cameras are eye; "
                                       "did you mean 'eye'?\n")
    assert main(["preview", str(source), "-n", "1", "--camera", "red", "-o", str(tmp_path / "x.png")]) == 2
    assert "object 'red' is not a camera" in capsys.readouterr().err
    assert not (tmp_path / "x.png").exists()
