"""Random actions in prsc.SceneEnv: each reset is a new Table-Cube scene written into one
MuJoCo model, no recompiling (docs/learning.md). Then the same with 4 environments in a
gymnasium SyncVectorEnv. Prints the measured resets per second.

    python examples/random_policy.py [--spec specs/table_cube.prs] [--episodes 20]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import gymnasium

import prsc

SPEC = Path(__file__).resolve().parents[1] / "specs" / "table_cube.prs"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--spec", default=str(SPEC))
    parser.add_argument("--episodes", type=int, default=20)
    parser.add_argument("--steps", type=int, default=20, help="steps per episode")
    args = parser.parse_args()

    env = prsc.SceneEnv(args.spec, frame_skip=10)
    env.reset(seed=0)
    resets = 0.0
    for episode in range(args.episodes):
        start = time.perf_counter()
        observation, info = env.reset()
        resets += time.perf_counter() - start
        for _ in range(args.steps):
            observation, reward, terminated, truncated, info = env.step(env.action_space.sample())
            if terminated or truncated:
                break
    env.close()
    print(f"one env: {args.episodes / resets:,.0f} resets per second ({args.episodes} scenes of {Path(args.spec).name})")

    envs = gymnasium.vector.SyncVectorEnv([lambda: prsc.SceneEnv(args.spec, frame_skip=10)] * 4)
    envs.reset(seed=[0, 1, 2, 3])
    start = time.perf_counter()
    for _ in range(args.episodes):
        envs.reset()
    elapsed = time.perf_counter() - start
    for _ in range(args.steps):
        envs.step(envs.action_space.sample())
    envs.close()
    print(f"4 envs (SyncVectorEnv): {4 * args.episodes / elapsed:,.0f} resets per second")


if __name__ == "__main__":
    main()
