"""Until the merge of branch `handover` only: the names the runner's handover (prsc/runner/motion.py,
ik.py, grasping.py) still reads of the library's Panda, read off the library arm itself (its data,
prsc/library/panda.json, and its model from the one asset path, prsc.assets.articulated), never
stated twice. The handover is rewritten against the generic arm interface there; delete this
module with prsc/runner/ik.py.
"""

from __future__ import annotations

from functools import lru_cache

LIBRARY_ARM = "panda"


@lru_cache(maxsize=1)
def _names() -> dict:
    from prsc.assets.articulated import robot_model
    from prsc.user_assets.asset_fitting import library_arm

    arm = library_arm(LIBRARY_ARM)
    robot = robot_model(LIBRARY_ARM)
    assert arm is not None and robot is not None
    arm_joints = tuple(j.name for j in robot.joints if j.kind == "revolute")
    gripper = arm.fitting.servos[0]
    return {
        "ARM_JOINTS": arm_joints,
        "FINGER_JOINTS": tuple(j.name for j in robot.joints if j.kind == "prismatic"),
        "ARM_ACTUATORS": arm_joints,  # prsc's servos, named after their joints (docs/assets.md)
        "GRIPPER_ACTUATOR": gripper.name,
        "GRIPPER_CLOSED": gripper.ctrl[0],
        "GRIPPER_OPEN": gripper.ctrl[1],
        "TCP_SITE": arm.fitting.sites[0].name,
        "BASE_BODY": robot.root,
        "HOME_QPOS": tuple(dict(arm.fitting.home)[name] for name in arm_joints),
    }


def __getattr__(name: str):
    names = _names()
    if name in names:
        return names[name]
    raise AttributeError(name)


def panda_mjcf_spec():
    """A fresh MjSpec of the library's Panda as a scene attaches it (prsc.assets.articulated), with
    the scene's simulation options (prsc.assets.simulation), as the runner's IK model had them."""
    from prsc.assets.articulated import robot_model
    from prsc.assets.simulation import set_simulation_options

    spec = robot_model(LIBRARY_ARM).mjcf_spec()  # type: ignore[union-attr]
    set_simulation_options(spec.option)
    return spec
