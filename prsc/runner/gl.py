"""Headless OpenGL for MuJoCo: choose the backend before mujoco is imported, one context per process.

MuJoCo reads MUJOCO_GL once, when `import mujoco` runs, so `prsc run` calls
`choose_gl_backend()` before anything imports it (with MUJOCO_GL unset MuJoCo would pick
GLFW, which needs a display). Every worker process then owns one GL context for its life;
renderers of successive episodes share it (creating a context costs about 0.4 CPU s).
"""

from __future__ import annotations

import os
import subprocess
import sys

from prsc.runner.faults import InfrastructureError

HEADLESS_BACKENDS = ("egl", "osmesa")
GL_VARIABLES = ("MUJOCO_GL", "PYOPENGL_PLATFORM")
"""What `choose_gl_backend` sets: every worker process of a campaign starts with the driver's."""

_context = None  # this process's GL context, made on first use


def _try_backend(backend: str) -> str | None:
    """None when MuJoCo can open an offscreen context with `backend` (in a fresh process), else why not."""
    code = "import mujoco; c = mujoco.GLContext(16, 16); c.make_current(); c.free()"
    env = dict(os.environ, MUJOCO_GL=backend, PYOPENGL_PLATFORM=backend)
    try:
        done = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, timeout=120)
    except (OSError, subprocess.TimeoutExpired) as error:
        return str(error)
    if done.returncode == 0:
        return None
    lines = done.stderr.decode("utf-8", "replace").strip().splitlines()
    return lines[-1] if lines else f"exit code {done.returncode}"


def choose_gl_backend() -> str:
    """Set MUJOCO_GL (and PYOPENGL_PLATFORM) for headless rendering; returns the backend.

    Keeps the user's MUJOCO_GL; else the first of egl, osmesa that opens a context. Raises
    InfrastructureError when none does, or when mujoco was already imported with another one."""
    chosen = os.environ.get("MUJOCO_GL")
    if not chosen:
        if "mujoco" in sys.modules:
            raise InfrastructureError("mujoco was imported before the GL backend was chosen; set MUJOCO_GL=egl")
        failures = {}
        for backend in HEADLESS_BACKENDS:
            failures[backend] = _try_backend(backend)
            if failures[backend] is None:
                chosen = backend
                break
        else:
            why = "; ".join(f"{b}: {reason}" for b, reason in failures.items())
            raise InfrastructureError(f"no offscreen OpenGL context can be made ({why}); "
                                      "install EGL or OSMesa, or set MUJOCO_GL")
        os.environ["MUJOCO_GL"] = chosen
    os.environ.setdefault("PYOPENGL_PLATFORM", chosen)
    return chosen


def use_gl_backend(backend: str) -> None:
    """In a worker: adopt the driver's backend before mujoco is imported here."""
    if "mujoco" not in sys.modules:
        os.environ["MUJOCO_GL"] = backend
        os.environ["PYOPENGL_PLATFORM"] = backend
    elif os.environ.get("MUJOCO_GL") != backend:
        raise InfrastructureError(f"this worker imported mujoco with MUJOCO_GL={os.environ.get('MUJOCO_GL')!r}, "
                                  f"not {backend!r}")


def gl_context():
    """This process's offscreen GL context, current; InfrastructureError when none can be made."""
    global _context
    if _context is None:
        import mujoco

        try:
            context = mujoco.GLContext(16, 16)
            context.make_current()
        except Exception as error:  # EGL, OSMesa and GLFW each raise their own kinds
            raise InfrastructureError(f"no offscreen OpenGL context with MUJOCO_GL="
                                      f"{os.environ.get('MUJOCO_GL', '')!r}: {type(error).__name__}: {error}") from None
        _context = context
    _context.make_current()
    return _context
