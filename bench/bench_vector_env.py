"""Steps per second of `gymnasium.vector.AsyncVectorEnv` over `prsc.SceneEnv` for N = 1, 2, 4, 8
environments (docs/learning.md, "Vector environments"): wall-clock time, since the work runs in N
worker processes. Random actions, no rendering, a reset every `--episode` steps.

    .venv/bin/python bench/bench_vector_env.py specs/table_cube.prs --steps 400
"""

from __future__ import annotations

import argparse
import os
import time

import gymnasium
import numpy as np


def vector_rate(spec: str, count: int, steps: int, episode: int) -> float:
    """Environment steps per wall-clock second of an AsyncVectorEnv of `count` SceneEnvs."""
    from prsc.scene_env import SceneEnv

    envs = gymnasium.vector.AsyncVectorEnv([lambda: SceneEnv(spec, max_episode_steps=episode)] * count)
    envs.reset(seed=list(range(count)))
    envs.action_space.seed(0)
    actions = [envs.action_space.sample() for _ in range(16)]
    for k in range(10):  # warm-up: the workers' first steps
        envs.step(actions[k % 16])
    start = time.perf_counter()
    for k in range(steps):
        envs.step(actions[k % 16])  # autoreset starts the next scene after `episode` steps
    rate = count * steps / (time.perf_counter() - start)
    envs.close()
    return rate


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("spec")
    parser.add_argument("--steps", type=int, default=400, help="vector steps per N")
    parser.add_argument("--episode", type=int, default=100, help="max_episode_steps")
    parser.add_argument("--counts", default="1,2,4,8")
    args = parser.parse_args()
    print(f"AsyncVectorEnv over SceneEnv({args.spec}), {os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f}")
    print("| N | env steps/s (wall) | per env |")
    print("|---|---|---|")
    for count in (int(c) for c in args.counts.split(",")):
        rate = vector_rate(args.spec, count, args.steps, args.episode)
        print(f"| {count} | {rate:,.0f} | {rate / count:,.0f} |", flush=True)


if __name__ == "__main__":
    np.seterr(all="ignore")
    main()
