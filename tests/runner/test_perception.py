"""The ceiling camera finds the cube from colour and depth, within millimetres when in view."""

from __future__ import annotations

import numpy as np

from prsc.backends.names import with_body_names
from prsc.runner.handover import HandoverEpisode
from prsc.runner.harness import fresh_data, load_model
from prsc.runner.perception import colour_mask, deproject, intrinsics_for, locate_cube


def _settled(scene, mjcf):
    model = load_model(mjcf)
    episode = HandoverEpisode(with_body_names(scene), model, fresh_data(model))  # as the harness passes it
    episode.sim.wait(0.3)
    return episode


def test_cube_located_within_a_few_millimetres(table_cube, compile_scene):
    episode = _settled(table_cube, compile_scene(table_cube))
    try:
        estimate = episode.perceive("test")
        assert np.linalg.norm(estimate - episode.cube_position()) < 0.008
    finally:
        episode.camera.close()


def test_deproject_inverts_the_pinhole_projection():
    class FakeModel:
        cam_fovy = np.array([60.0])

    intr = intrinsics_for(FakeModel(), 0, 320, 240)
    cam_pos = np.array([0.1, -0.2, 2.0])
    cam_mat = np.eye(3)  # looking down the world -z, image up = world +y
    point = np.array([0.35, 0.1, 0.8])
    depth = cam_pos[2] - point[2]
    u = intr.cx + (point[0] - cam_pos[0]) / depth * intr.focal - 0.5
    v = intr.cy - (point[1] - cam_pos[1]) / depth * intr.focal - 0.5
    back = deproject(np.array([u]), np.array([v]), np.array([depth]), intr, cam_pos, cam_mat)[0]
    assert np.allclose(back, point, atol=1e-9)


def test_colour_mask_matches_hue_not_brightness():
    image = np.array([[[200, 20, 20], [90, 10, 10], [150, 100, 60], [200, 200, 200]]], dtype=np.uint8)
    assert colour_mask(image, [1, 0, 0, 1]).tolist() == [[True, True, False, False]]


def test_nothing_found_without_the_colour():
    rgb = np.full((24, 32, 3), 128, dtype=np.uint8)
    depth = np.ones((24, 32))

    class FakeModel:
        cam_fovy = np.array([60.0])

    intr = intrinsics_for(FakeModel(), 0, 32, 24)
    assert locate_cube(rgb, depth, intr, np.zeros(3), np.eye(3), [0, 0, 1, 1], 0.02) is None
