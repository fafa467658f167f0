"""Load an MJCF scene in MuJoCo, simulate it, and print where every body ended up.

`python -m prsc.runner.settle_report FILE.xml [--seconds S]`: the check a user runs on a
compiled scene (and `make demo` shows): the file loads from any working directory, each
free body's displacement after S simulated seconds tells whether it rests where the
sampler put it.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import mujoco
import numpy as np
from rich.console import Console
from rich.table import Table


def settle(path: Path, seconds: float) -> tuple[mujoco.MjModel, np.ndarray, np.ndarray]:
    """Body positions of the MJCF at `path` before and after `seconds` of simulation."""
    from prsc.runner.harness import fresh_data, load_model

    model = load_model(path)  # as an episode loads it: at the `home` keyframe, arms at rest
    data = fresh_data(model)
    before = data.xpos.copy()
    for _ in range(int(round(seconds / model.opt.timestep))):
        mujoco.mj_step(model, data)
    return model, before, data.xpos.copy()


def main(argv: list[str] | None = None) -> int:
    """Print a table of the top-level bodies of an MJCF scene and how far each moved."""
    parser = argparse.ArgumentParser(prog="python -m prsc.runner.settle_report", description=__doc__)
    parser.add_argument("mjcf", type=Path)
    parser.add_argument("--seconds", type=float, default=1.0, help="simulated time (default 1 s)")
    args = parser.parse_args(argv)
    model, before, after = settle(args.mjcf, args.seconds)
    console = Console()
    console.print(f"{args.mjcf}: loaded in MuJoCo, {model.nbody - 1} bodies, {model.njnt} joints, "
                  f"{model.nu} actuators, {model.ncam} cameras; {args.seconds:g} s simulated")
    table = Table()
    for column in ("body", "free", "position (m)", "moved (mm)"):
        table.add_column(column, justify="right" if column == "moved (mm)" else "left")
    for body in range(1, model.nbody):
        if model.body_parentid[body] != 0:
            continue  # robot links and object parts: the top-level body speaks for them
        free = any(model.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE
                   for j in range(model.body_jntadr[body], model.body_jntadr[body] + model.body_jntnum[body]))
        moved = 1000.0 * float(np.linalg.norm(after[body] - before[body]))
        position = ", ".join(f"{v:+.3f}" for v in before[body])
        table.add_row(model.body(body).name, "yes" if free else "fixed", position, f"{moved:.1f}")
    console.print(table)
    return 0


if __name__ == "__main__":
    sys.exit(main())
