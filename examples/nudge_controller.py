"""A small controller with a rare failure, for `prsc falsify` on Table-Cube (docs/falsify.md, "A rare failure").

It nudges the cube c1 diagonally toward its tray's +x +y corner (one push of NUDGE m/s, then
friction alone) and lets it slide to rest. The episode fails, `cornered`, when the cube
touches both of the tray's walls there (+x and +y) at once: only a cube that starts within
about a centimetre of both slides into the corner, a fraction of a percent of the spec's
scenes. The record's `clearance` is the closest the cube came to that (metres: the larger
of its distances to the two walls by MuJoCo's mj_geomDistance, at its least), the
robustness the task monitor computes for the same property, in a spec with a task:

    c1 touches tr_1's +x wall and c1 touches tr_1's +y wall

(a `fail "cornered" when ...` in the task language's words for the two wall geoms:
docs/tasks.md). Run it:

    prsc falsify specs/table_cube.prs --controller examples/nudge_controller.py:nudge --budget 60
"""

from __future__ import annotations

import math

import mujoco

OUTCOMES = ("success", "cornered")
NUDGE = 0.6  # m/s toward the +x +y corner at the start: about 18 mm of sliding at friction 1
SETTLE_SECONDS = 1.0  # simulated time to slide to rest
CUBE, TRAY = "c1", "tr_1"
WALLS = ("wall_right", "wall_front")  # the tray's +x and +y walls (the tray is placed unrotated)
TOUCH = 1e-4  # metres: a gap this small is contact
FAR = 0.5  # metres: mj_geomDistance's search radius (a gap beyond it reads as FAR)


def nudge(scene, model, data):
    """Push the cube toward its tray's +x +y corner; report whether it got wedged there, and how close it came."""
    body = model.body(CUBE).id
    geom = next(g for g in range(model.ngeom) if model.geom_bodyid[g] == body)
    walls = [model.geom(f"{TRAY}/{name}").id for name in WALLS]
    mujoco.mj_forward(model, data)
    dof = model.jnt_dofadr[model.joint(CUBE).id]
    data.qvel[dof:dof + 2] = NUDGE / math.sqrt(2)
    clearance = float("inf")
    end = data.time + SETTLE_SECONDS
    while data.time < end:
        mujoco.mj_step(model, data)
        gaps = [mujoco.mj_geomDistance(model, data, geom, wall, FAR, None) for wall in walls]
        clearance = min(clearance, float(max(gaps)))
    if clearance <= TOUCH:
        return {"outcome": "cornered", "reason": "the nudged cube touched both walls of its tray's +x +y corner",
                "clearance": round(clearance, 6)}
    return {"outcome": "success", "reason": f"the cube came {clearance * 1000:.1f} mm from the corner's walls",
            "clearance": round(clearance, 6)}


nudge.outcomes = OUTCOMES
