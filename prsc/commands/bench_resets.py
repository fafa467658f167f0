"""`prsc bench --resets FILE... [-n 200]`: resets per CPU-second, a new scene written into one
shared MuJoCo model (`scenario.apply`) against a model compiled per scene
(`prsc.mujoco_model`), side by side in one process on one core (docs/learning.md); with several
files, each in turn in the same run, then one table of them all.

Rows: drawing the scene alone, through `scenario.drawer` as `SceneEnv.reset` does (its first
draw RESET_DRAW_AHEAD scenes, each later one twice the last up to RESET_DRAW_AHEAD_MAX, over
as many whole batches as hold enough scenes that most come from full ones, the ramp included;
then on, three full batches)
and one at a time through
`scenario.scene`; `apply` alone and a compile alone (scenes drawn beforehand); draw + apply (an
RL reset) and draw + compile (the path without `apply`), from those rates; and a 4-environment
`gymnasium.vector.SyncVectorEnv` of `prsc.SceneEnv` when the [gym] extra is installed (timed
from its seeded reset over whole batches of draws), with
a `SceneEnv.step` (no rendering) against the same `mujoco.mj_step` calls on its model, timed
in alternating rounds. CPU time of this process, so other load on the machine does not count.
"""

from __future__ import annotations

import os
import time
from typing import Any, Callable

VECTOR_ENVS = 4
DRAWN = "draw a scene (as a reset)"
STEADY = "draw a scene (full batches)"


def _rate(count: int, work: Callable[[int], Any]) -> float:
    """Calls per CPU-second of `work(k)` for k in range(count)."""
    start = time.process_time()
    for k in range(count):
        work(k)
    return count / max(time.process_time() - start, 1e-9)


def bench_resets(spec: str, n: int, include_dirs: list[str], seed: int = 0) -> dict[str, float]:
    """Resets per CPU-second of each way (the keys of the printed table)."""
    import mujoco

    from prsc.scenario import RESET_DRAW_AHEAD, RESET_DRAW_AHEAD_MAX, load, mujoco_model

    scenario = load(spec, include_dirs)
    model = scenario.model(seed, 0)
    data = mujoco.MjData(model)
    scenes = list(scenario.scenes(seed, n, start=1))
    scenario.apply(scenes[-1], model, data)  # warm-up: imports and caches are set-up, not per-reset cost
    compiled = max(1, n // 10)  # compiling is ~100x slower: fewer of them measure it as well
    # A reset draws through `scenario.drawer` as SceneEnv.reset does, from a seeded reset on: the
    # ramp of small draws is in the rate, and enough scenes follow it that full batches dominate.
    # One scene at a time through `scenario.scene` is kept as a row to compare against.
    draw = scenario.drawer(seed + 1, RESET_DRAW_AHEAD, RESET_DRAW_AHEAD_MAX)
    # As many resets as the ramp's batches hold whole: every scene drawn is used (1,024 resets would
    # pay for 1,216 scenes, the last batch of 256 cut to 64), as in the SyncVectorEnv row.
    ramped = _ramp_total(max(n, 4 * RESET_DRAW_AHEAD_MAX), RESET_DRAW_AHEAD, RESET_DRAW_AHEAD_MAX)
    drawn = _rate(ramped, lambda k: draw(k))
    # Then the same loop on, every draw a full batch: what a long training run's resets cost.
    drawn_steady = _rate(3 * RESET_DRAW_AHEAD_MAX, lambda k: draw(ramped + k))
    drawn_singly = _rate(max(1, n // 4), lambda k: scenario.scene(seed, n + 1 + k))
    applied = _rate(n, lambda k: scenario.apply(scenes[k], model, data))
    compiled_rate = _rate(compiled, lambda k: mujoco_model(scenes[k]))
    rates = {
        DRAWN: drawn,
        STEADY: drawn_steady,
        "draw a scene (one at a time)": drawn_singly,
        "apply (scene drawn)": applied,
        "compile (scene drawn)": compiled_rate,
        # Drawing then writing: the two costs add up, as in a reset.
        "draw + apply": 1 / (1 / drawn + 1 / applied),
        "draw + apply (full batches)": 1 / (1 / drawn_steady + 1 / applied),
        "draw + compile": 1 / (1 / drawn + 1 / compiled_rate),
    }
    try:
        import gymnasium
    except ImportError:
        return rates
    from prsc.scene_env import SceneEnv

    envs = gymnasium.vector.SyncVectorEnv([lambda: SceneEnv(spec, include_dirs=include_dirs)] * VECTOR_ENVS)
    # From the seeded reset on, as many resets as each environment's draws hold (its ramp of
    # batches): every scene drawn is used, so the rate carries the draws' whole cost.
    per_env = _ramp_total(max(1, n // VECTOR_ENVS), RESET_DRAW_AHEAD, RESET_DRAW_AHEAD_MAX)
    rates[f"SyncVectorEnv x{VECTOR_ENVS} reset"] = VECTOR_ENVS * _rate(
        per_env, lambda k: envs.reset(seed=seed) if k == 0 else envs.reset())
    envs.close()
    rates.update(bench_steps(SceneEnv(spec, include_dirs=include_dirs), seed, steps=10 * n))
    return rates


def _ramp_total(count: int, first: int, largest: int) -> int:
    """The fewest scenes, at least `count`, that a drawer's batches (`first`, then each twice the
    last up to `largest`) hold whole."""
    total, batch = 0, first
    while total < count:
        total, batch = total + batch, min(2 * batch, largest)
    return total


def bench_steps(env, seed: int, steps: int, rounds: int = 10) -> dict[str, float]:
    """Steps per CPU-second of `env.step` (no rendering) and of the same `mj_step(nstep=frame_skip)`
    calls on its model and data from the same state, in alternating rounds so that load on the
    machine falls on both; the ratio is the median of the rounds' ratios (one busy round does not
    decide it)."""
    import statistics

    import mujoco
    import numpy as np

    env.reset(seed=seed)
    action = np.zeros(env.action_space.shape, dtype=env.action_space.dtype)
    model, data, skip = env.model, env.data, env.frame_skip
    per_round = max(1, steps // rounds)
    rates: dict[str, list[float]] = {"env": [], "mujoco": []}
    for _ in range(rounds):
        env.reset()
        rates["env"].append(_rate(per_round, lambda k: env.step(action)))
        env.reset()
        data.ctrl[:] = np.clip(action, env.action_space.low, env.action_space.high)
        rates["mujoco"].append(_rate(per_round, lambda k: mujoco.mj_step(model, data, nstep=skip)))
    ratio = statistics.median(m / e for e, m in zip(rates["env"], rates["mujoco"]))
    return {"SceneEnv.step": statistics.median(rates["env"]), f"mj_step(nstep={skip})": statistics.median(rates["mujoco"]),
            "step cost ratio": ratio}


SUMMARY = (DRAWN, "apply (scene drawn)", "compile (scene drawn)", "draw + apply", "draw + compile")


def print_resets(specs: list[str], n: int, include_dirs: list[str]) -> None:
    """Run the benchmark on each spec in turn, print its table, then one row per spec."""
    from prsc.scenario import RESET_DRAW_AHEAD, RESET_DRAW_AHEAD_MAX

    summary = {}
    for spec in specs:
        rates = summary[spec] = bench_resets(spec, n, include_dirs)
        print(f"prsc reset benchmark: {spec}, {n} scenes, one core, load average {os.getloadavg()[0]:.2f}")
        print(f"  apply is {rates['apply (scene drawn)'] / rates['compile (scene drawn)']:,.0f}x a compile per scene; "
              f"a reset (draw + apply) {rates['draw + apply'] / rates['draw + compile']:,.1f}x draw + compile, "
              f"{rates['draw + apply'] / rates['compile (scene drawn)']:,.1f}x a compile alone "
              f"({rates['draw + apply (full batches)'] / rates['compile (scene drawn)']:,.1f}x once every draw is a full batch)")
        print(f"  a reset draws {RESET_DRAW_AHEAD} scenes at a time, doubling to {RESET_DRAW_AHEAD_MAX}")
        ratio = rates.pop("step cost ratio", None)
        if ratio is not None:
            print(f"  a SceneEnv step costs {ratio:.3f}x the same mj_step calls (median of 10 rounds)")
        for name, rate in rates.items():
            print(f"  {name:<28} {rate:>9,.0f} per CPU-second")
    if len(specs) > 1:
        print(f"all specs, per CPU-second: {' | '.join(SUMMARY)} | draw + apply / draw + compile")
        for spec, rates in summary.items():
            cells = " | ".join(f"{rates[name]:,.0f}" for name in SUMMARY)
            print(f"  {spec}: {cells} | {rates['draw + apply'] / rates['draw + compile']:,.1f}x")
