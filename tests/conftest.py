"""Suite-wide setup: every test session starts from a cold asset cache, as a fresh clone does.

Without this, assets built by an earlier run in `build/` hide bugs in building them (a USD
robot conversion once failed only on a clean checkout). The xdist workers inherit the
folder from the controlling process, so they also race to build the same assets, which
the atomic writes must survive.
"""

from __future__ import annotations

import os
import shutil
import tempfile

# A fresh shell has no MUJOCO_GL: without a default, the first camera test makes MuJoCo
# pick GLFW, which needs a display, and the xdist worker dies. The Makefile sets the same
# default; this one holds for `pytest` run alone. Set before anything imports mujoco.
os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("PYOPENGL_PLATFORM", os.environ["MUJOCO_GL"])

from hypothesis import settings  # noqa: E402

_OWNED = "PRSC_TEST_OWNS_BUILD_DIR"

# Property tests draw the same examples on every run (the suite's fixed seeds): a failure
# found once is found again, and CI does not turn red on a new draw.
settings.register_profile("prsc", derandomize=True)
settings.load_profile("prsc")


def pytest_configure(config) -> None:
    """Point PRSC_BUILD_DIR at a fresh folder unless the caller chose one."""
    if "PRSC_BUILD_DIR" not in os.environ:
        os.environ["PRSC_BUILD_DIR"] = tempfile.mkdtemp(prefix="prsc-test-build-")
        os.environ[_OWNED] = "1"


def pytest_unconfigure(config) -> None:
    """Remove the folder made above (in the controlling process only)."""
    if hasattr(config, "workerinput") or not os.environ.get(_OWNED):
        return
    shutil.rmtree(os.environ.pop("PRSC_BUILD_DIR"), ignore_errors=True)
    os.environ.pop(_OWNED, None)
