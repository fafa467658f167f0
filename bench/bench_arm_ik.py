"""Benchmark of the arm IK (prsc/user_assets/arm_ik.py) against another revision's, side by side
in one run, on pybullet's held-out arms (docs/assets.md, "The IK").

Run: .venv/bin/python bench/bench_arm_ik.py [--against REV] [-n 150] [--hard 200] [--arms xarm,kuka,franka]

REV's arm_ik.py is read with `git show` and run beside this tree's on the same arm models
(asset_spec of each URDF) and the same targets, the two taking turns target by target:
  easy: the tool's position at random joint values within the limits whose tool points down
        (drawn with it pointing within 0.35 rad of down, then turned exactly down by scipy's
        least squares on the tool's axis alone, every link above the base): reachable by construction;
  hard: points drawn in a cylinder about the root (radius 5 cm to the arm's span, 10 cm below to
        30 cm above the root): many unreachable, many near the edges of the reach.
Per set and IK: `solve_top_down` from home turned towards the target (success, median and 95th
percentile residual of the successes, ms per solve), and `reach_top_down` as `reachable by`
asks it (the point and 12 cm above it, RESTARTS more starts: success, ms per target); an
answer that puts one of the arm's links into another (this tree's `ArmFrames.self_collides`,
which REV may not check) does not count.
"""

from __future__ import annotations

import argparse
import importlib.util
import math
import subprocess
import sys
import time
from pathlib import Path

import mujoco
import numpy as np

from prsc.user_assets import arm_ik
from prsc.user_assets.asset_files import asset_spec, describe_asset

ROOT = Path(__file__).resolve().parents[1]
ARMS = {  # name: (file under pybullet_data, tool)
    "xarm": ("xarm/xarm6_robot.urdf", None),
    "kuka": ("kuka_iiwa/model.urdf", None),
    "franka": ("franka_panda/panda.urdf", "panda_grasptarget"),
}
NEAR_DOWN = 0.35  # rad: random joint values kept for the easy set when the tool points this near down


def other_ik(revision: str):
    """arm_ik.py of `revision`, loaded as its own module."""
    text = subprocess.run(["git", "show", f"{revision}:prsc/user_assets/arm_ik.py"], cwd=ROOT, check=True,
                          capture_output=True, text=True).stdout
    spec = importlib.util.spec_from_loader(f"arm_ik_{revision}", loader=None)
    module = importlib.util.module_from_spec(spec)
    sys.modules[module.__name__] = module  # before it runs: its dataclasses look their module up
    exec(compile(text, f"{revision}:prsc/user_assets/arm_ik.py", "exec"), module.__dict__)
    return module


class Arm:
    """One arm's model, its frames under each IK, home and root."""

    def __init__(self, path: str, tool: str | None, iks: dict) -> None:
        from dataclasses import replace

        asset = describe_asset(path)
        if tool is not None:
            asset = replace(asset, tcp=tool)
        self.model = asset_spec(asset.source).compile()
        self.data = mujoco.MjData(self.model)
        joints = [j.name for j in asset.joints]
        self.frames = {name: ik.ArmFrames.of(self.model, joints, str(asset.tcp)) for name, ik in iks.items()}
        self.home = np.array([j.home for j in asset.joints])
        self.data.qpos[self.frames["this"].qpos] = self.home
        mujoco.mj_kinematics(self.model, self.data)
        self.root = self.data.xpos[self.model.body(asset.root).id].copy()
        self.heading = self.frames["this"].heading(self.data, self.root)
        self.span = sum(float(np.linalg.norm(self.model.body_pos[b])) for b in range(2, self.model.nbody))

    def pose(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The tool's position and rotation at arm joint values `q`."""
        self.data.qpos[self.frames["this"].qpos] = q
        mujoco.mj_kinematics(self.model, self.data)
        return self.frames["this"].tool_pose(self.data)


def easy_targets(arm: Arm, count: int, rng: np.random.Generator) -> list[np.ndarray]:
    """Tool positions at random joint values with the tool straight down and every link above the base."""
    from scipy.optimize import least_squares

    frames = arm.frames["this"]
    lower = np.where(np.isfinite(frames.lower), frames.lower, -math.pi)
    upper = np.maximum(np.where(np.isfinite(frames.upper), frames.upper, math.pi), lower + 1e-9)  # a range held at its middle
    targets: list[np.ndarray] = []
    while len(targets) < count:
        q = rng.uniform(lower, upper)
        if arm.pose(q)[1][2, 2] > -math.cos(NEAR_DOWN):
            continue
        fit = least_squares(lambda x: arm.pose(x)[1][:, 2] - arm_ik.DOWN, q, bounds=(lower, upper), xtol=1e-12)
        position, rotation = arm.pose(fit.x)
        if rotation[2, 2] < -math.cos(1e-4) and frames.above_base(arm.data):
            targets.append(position)
    return targets


def hard_targets(arm: Arm, count: int, rng: np.random.Generator) -> list[np.ndarray]:
    """Points in a cylinder about the root, out to the arm's span."""
    radius = rng.uniform(0.05, arm.span, count)
    angle = rng.uniform(-math.pi, math.pi, count)
    height = rng.uniform(-0.1, 0.3, count)
    return [arm.root + np.array([r * math.cos(a), r * math.sin(a), h]) for r, a, h in zip(radius, angle, height)]


def measure(arm: Arm, iks: dict, targets: list[np.ndarray]) -> dict:
    """Per IK: solves reached, residuals of the reached (mm, mrad), ms per solve; reach_top_down's."""
    rows = {name: {"solved": 0, "miss": [], "tilt": [], "ms": [], "reached": 0, "reach_ms": []} for name in iks}
    for goal in targets:
        for name, ik in iks.items():
            frames, row = arm.frames[name], rows[name]
            start = ik.turned(arm.home, frames, arm.heading, math.atan2(*(goal - arm.root)[1::-1]))
            began = time.process_time()
            _, ok = ik.solve_top_down(arm.model, arm.data, frames, goal, start)
            row["ms"].append(1000 * (time.process_time() - began))
            if ok:
                position, rotation = frames.tool_pose(arm.data)
                row["solved"] += 1
                row["miss"].append(1000 * float(np.linalg.norm(position - goal)))
                row["tilt"].append(1000 * math.acos(min(1.0, -rotation[2, 2])))
            began = time.process_time()
            q, ok = ik.reach_top_down(arm.model, arm.data, frames, goal, start, start, ik.REACH_APPROACH, ik.RESTARTS)
            row["reach_ms"].append(1000 * (time.process_time() - began))
            # Judged alike: a pose with one link in another (this tree's check) does not count.
            arm.data.qpos[frames.qpos] = q
            mujoco.mj_kinematics(arm.model, arm.data)
            row["reached"] += ok and not arm.frames["this"].self_collides(arm.model, arm.data)
    return rows


def main() -> None:
    """Print the table."""
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--against", default="main", help="the revision whose arm_ik.py runs beside this tree's (default main)")
    parser.add_argument("-n", type=int, default=150, help="easy targets per arm (default 150)")
    parser.add_argument("--hard", type=int, default=200, help="hard targets per arm (default 200)")
    parser.add_argument("--arms", default=",".join(ARMS), help=f"comma-separated subset of {','.join(ARMS)}")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    import pybullet_data

    iks = {args.against: other_ik(args.against), "this": arm_ik}
    print("| arm | set | IK | solved from home | median / 95th residual (mm) | ms per solve "
          "| reached with restarts + approach | ms per target |")
    print("|---|---|---|---|---|---|---|---|")
    for name in args.arms.split(","):
        file, tool = ARMS[name]
        arm = Arm(str(Path(pybullet_data.getDataPath()) / file), tool, iks)
        rng = np.random.default_rng(args.seed)
        for label, targets in (("easy", easy_targets(arm, args.n, rng)), ("hard", hard_targets(arm, args.hard, rng))):
            for ik, row in measure(arm, iks, targets).items():
                miss = np.percentile(row["miss"], [50, 95]) if row["miss"] else (math.nan, math.nan)
                print(f"| {name} | {label} | {'mink (this tree)' if ik == 'this' else ik} | {row['solved']}/{len(targets)} "
                      f"| {miss[0]:.3f} / {miss[1]:.3f} | {np.median(row['ms']):.2f} (mean {np.mean(row['ms']):.2f}) "
                      f"| {row['reached']}/{len(targets)} | {np.mean(row['reach_ms']):.1f} |", flush=True)


if __name__ == "__main__":
    main()
