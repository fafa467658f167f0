"""What the example specs of stacks and visibility promise beyond their rows (compiled and settled in
tests/specs/test_example_specs.py): the fourth cube's distance, the camera's own image."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from prsc.cli import main
from prsc.ir import compile_program
from prsc.sampling import Sampler

SPECS = Path(__file__).resolve().parents[2] / "specs"


def test_the_fourth_cube_is_at_least_10_cm_from_every_cube_of_the_stack():
    spec = SPECS / "stack_and_cube.prs"
    sampler = Sampler(compile_program(str(spec), (str(SPECS),)), "exact")
    for index in range(200):
        boxes = {o.name: o for o in sampler.sample(0, index).objects}
        for cube in ("base", "middle", "top_cube"):
            assert np.linalg.norm(boxes["loose"].position - boxes[cube].position) >= 0.1 - 1e-9


def test_what_camera_view_declares_visible_is_whole_in_the_cameras_own_image(tmp_path):
    """Rendered by MuJoCo from the compiled camera (segmentation), each object `visible from
    camera` alone (the others moved away: the frustum says nothing of occlusion): it shows,
    and touches no border of the image (no edge of the image cuts it)."""
    import mujoco

    from prsc.ir import model as ir

    spec = SPECS / "camera_view.prs"
    assert main(["compile", str(spec), "-t", "json,mjcf", "-n", "5", "-o", str(tmp_path)]) == 0
    program = compile_program(str(spec), (str(SPECS),))
    visible = [o.name for o in program.objects if any(isinstance(s, ir.VisibleFrom) for s in o.specifiers)]
    assert len(visible) == 4
    for path in sorted((tmp_path / "camera_view" / "mjcf").iterdir()):
        model = mujoco.MjModel.from_xml_path(str(path))
        with mujoco.Renderer(model, 240, 320) as renderer:  # 640 x 480 halved: the same field of view
            renderer.enable_segmentation_rendering()
            for name in visible:
                data = mujoco.MjData(model)
                for joint in range(model.njnt):  # every other free object far below the floor
                    if model.jnt_type[joint] == mujoco.mjtJoint.mjJNT_FREE and model.jnt_bodyid[joint] != model.body(name).id:
                        data.qpos[model.jnt_qposadr[joint] + 2] = -50.0
                mujoco.mj_forward(model, data)
                renderer.update_scene(data, camera="camera")
                seg = renderer.render()
                geom = np.where(seg[..., 1] == int(mujoco.mjtObj.mjOBJ_GEOM), seg[..., 0], -1)
                mask = (geom >= 0) & (model.geom_bodyid[np.maximum(geom, 0)] == model.body(name).id)
                assert mask.sum() > 20, (path.name, name)
                assert not (mask[0].any() or mask[-1].any() or mask[:, 0].any() or mask[:, -1].any()), (path.name, name)
