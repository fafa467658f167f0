"""Domain randomisation with prsc.SceneEnv: every reset draws a new scene of
specs/domain_randomisation/table_cube_dr.prs, whose cube shows one of three images, whose spot
light moves, turns and changes colour, and whose ceiling camera jitters; the observation is that
camera's image (docs/learning.md, "Domain randomisation"). Nothing is recompiled: the images
were loaded into the model once, and each reset writes the scene's numbers into it.

Writes a contact sheet of each episode's first image and prints the resets per CPU-second.

    python examples/domain_randomisation.py [--episodes 8] [--out domain_randomisation.png]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

import prsc

SPEC = Path(__file__).resolve().parents[1] / "specs" / "domain_randomisation" / "table_cube_dr.prs"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--spec", default=str(SPEC))
    parser.add_argument("--episodes", type=int, default=8)
    parser.add_argument("--steps", type=int, default=10, help="random actions per episode (max_episode_steps)")
    parser.add_argument("--out", default="domain_randomisation.png", help="the contact sheet (PNG)")
    args = parser.parse_args()

    env = prsc.SceneEnv(args.spec, observation={"camera": "rgb"}, max_episode_steps=args.steps)
    env.action_space.seed(0)
    firsts, cpu = [], 0.0
    for episode in range(args.episodes):
        start = time.process_time()
        observation, info = env.reset(seed=0) if episode == 0 else env.reset()
        if episode:  # the first reset also makes the renderer and its GL context
            cpu += time.process_time() - start
        firsts.append(observation["camera"]["rgb"])
        cube = next(o for o in info["scene"]["objects"] if o["name"] == "c1")
        print(f"scene {info['scene']['index']}: cube shows {cube['properties']['texture']}")
        truncated = False
        while not truncated:
            observation, reward, terminated, truncated, info = env.step(env.action_space.sample())
    env.close()

    from PIL import Image

    sheet = np.concatenate(firsts, axis=1)
    Image.fromarray(sheet).save(args.out)
    distinct = len({frame.tobytes() for frame in firsts})
    print(f"{distinct} distinct first images of {args.episodes} episodes, written to {args.out}")
    if args.episodes > 1:
        print(f"{(args.episodes - 1) / cpu:,.0f} resets per CPU-second, each with its camera image")


if __name__ == "__main__":
    main()
