"""`touches` in MuJoCo: the monitor's geom distance (bounding-box broad phase, then MuJoCo's own
mj_geomDistance) equals the distance between two boxes computed independently, on random poses."""

from __future__ import annotations

import mujoco
import numpy as np
from scipy.optimize import lsq_linear
from scipy.spatial.transform import Rotation

from prsc.runner.task_monitor import MjWorld
from prsc.task.bind import task_object
from prsc.task.terms import Task, TaskStatements

HALF_A, HALF_B = np.array([0.05, 0.03, 0.02]), np.array([0.2, 0.1, 0.04])
XML = f"""<mujoco><worldbody>
<body name="a"><freejoint/><geom type="box" size="{' '.join(map(str, HALF_A))}"/></body>
<body name="b"><freejoint/><geom type="box" size="{' '.join(map(str, HALF_B))}"/>
  <geom type="box" size="0.01 0.01 0.01" pos="0.3 0 0"/></body>
</worldbody></mujoco>"""


def _box_gap(pa, ra, pb, rb) -> float:
    """Distance between two separated boxes: min |pa + Ra u - pb - Rb v| over the boxes, by bounded least squares."""
    solved = lsq_linear(np.hstack([ra, -rb]), pb - pa, bounds=(-np.r_[HALF_A, HALF_B], np.r_[HALF_A, HALF_B]),
                        method="bvls", tol=1e-15)
    return float(np.linalg.norm(np.hstack([ra, -rb]) @ solved.x - (pb - pa)))


def test_the_geom_distance_is_the_distance_between_the_boxes():
    model = mujoco.MjModel.from_xml_string(XML)
    data = mujoco.MjData(model)
    objects = [{"name": n, "dimensions": list(2 * h), "position": [0, 0, 0]} for n, h in (("a", HALF_A), ("b", HALF_B))]
    scene = {"objects": objects}
    world = MjWorld(scene, model, Task(TaskStatements(), tuple(task_object(o) for o in objects)))
    rng = np.random.default_rng(5)
    compared = touching = 0
    for _ in range(150):
        poses = [(rng.uniform(-0.25, 0.25, 3), Rotation.random(random_state=int(rng.integers(1 << 31)))) for _ in range(2)]
        for k, (p, r) in enumerate(poses):
            data.qpos[7 * k:7 * k + 3] = p
            data.qpos[7 * k + 3:7 * k + 7] = np.roll(r.as_quat(), 1)
        mujoco.mj_forward(model, data)
        found = world.distances(data)("a", "b")
        pa, ra = data.xpos[1], data.xmat[1].reshape(3, 3)
        pb, rb = data.xpos[2], data.xmat[2].reshape(3, 3)
        expected = _box_gap(pa, ra, pb, rb)
        small = mujoco.mj_geomDistance(model, data, 0, 2, 1.0, np.zeros(6))
        if expected > 1e-9:
            assert abs(min(expected, small) - found) < 1e-6
            compared += 1
            # asked only whether they are within `enough`: the answer lies between the distance and it
            for enough in (found - 0.01, found + 0.01, found + 0.5):
                bounded = world.distances(data)("a", "b", enough)
                assert bounded == found if enough < found else found - 1e-12 <= bounded <= enough
        else:
            assert found <= 1e-9  # overlapping boxes: contact, `touches` holds
            touching += 1
    assert compared > 50 and touching > 5
