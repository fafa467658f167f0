"""MuJoCo simulation options: the one place they are set, for scene files and robot models alike.

Every MJCF prsc writes carries these options, and robot fragments carry the same ones so
that attaching a robot to a scene does not conflict; the runner loads a file as written.
"""

from __future__ import annotations

from typing import Any

TIMESTEP = 0.002  # s: the handover controller is tuned for 500 Hz physics
IMPRATIO = 10.0  # frictional-to-normal impedance ratio: grasps do not slip under elliptic cones


def set_simulation_options(option: Any) -> None:
    """Set prsc's options on an MjSpec's `option` (integrator, friction cone, timestep)."""
    import mujoco

    option.timestep = TIMESTEP
    option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    option.impratio = IMPRATIO
