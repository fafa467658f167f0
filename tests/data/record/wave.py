"""A controller for dataset tests: the arm's servos swing about home for 0.6 simulated s; even
scenes end `success`, odd ones `fail` (so `--keep success` has something to leave out)."""

import math

import mujoco


def wave(scene, model, data):
    home = data.ctrl.copy()
    while data.time < 0.6:
        data.ctrl[:] = home + 0.3 * math.sin(4.0 * data.time)
        mujoco.mj_step(model, data, nstep=5)
    outcome = "success" if scene["index"] % 2 == 0 else "fail"
    return {"outcome": outcome, "reason": ""}
