"""Which joints of a compiled asset model its own position servos hold (docs/assets.md, "In
every format"): prsc gives every other joint of an arm a servo of its own."""

from __future__ import annotations


def position_servo_joints(model) -> tuple[str, ...]:
    """The joints that a position servo of the model holds: those it drives directly, and those
    a joint equality makes follow one of them (a URDF `<mimic>`: a gripper.s second finger)."""
    import mujoco

    held = {int(model.actuator_trnid[a, 0]) for a in range(model.nu)
            if int(model.actuator_trntype[a]) == int(mujoco.mjtTrn.mjTRN_JOINT) and is_position_servo(model, a)}
    followers = {int(model.eq_obj1id[e]) for e in range(model.neq)
                 if int(model.eq_type[e]) == int(mujoco.mjtEq.mjEQ_JOINT) and int(model.eq_obj2id[e]) in held}
    return tuple(sorted(model.joint(j).name for j in held | followers))


def is_position_servo(model, actuator: int) -> bool:
    """Whether a compiled model's actuator is a position servo, which holds its joint at its
    control: gain kp > 0 and bias -kp on the position, as `<position>` writes (robosuite's
    `<motor>`s apply torques and hold nothing)."""
    import mujoco

    gain = model.actuator_gainprm[actuator, 0]
    return (int(model.actuator_biastype[actuator]) == int(mujoco.mjtBias.mjBIAS_AFFINE)
            and gain > 0 and model.actuator_biasprm[actuator, 1] == -gain)
