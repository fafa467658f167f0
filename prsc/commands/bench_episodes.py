"""Benchmark of episodes: CPU seconds per episode and where they go (`make bench`).

    prsc bench --episodes FILE [-n 21] [--controller TARGET]

Compiles n scenes, runs the first episode to warm the worker (GL context, render context,
IK models, MuJoCo's mesh cache), then the other n-1 in this process, as one worker of
`prsc run` runs them. Reports CPU seconds per episode (process time, all threads: the
GL rasteriser's too), episodes per CPU-second, and the CPU spent loading MJCF files,
stepping (`mj_step`) and rendering. A spec with a task (docs/tasks.md) runs each measured
scene's episode twice more, with and without the task monitor, back to back and without those
timers (which one first alternates from scene to scene), and reports the monitor's cost as the
median over scenes of the ratio of the two runs' CPU, with its quartiles: a ratio of one
scene's two runs, taken side by side, is what survives the load of a shared machine
(docs/tasks.md, Cost).
"""

from __future__ import annotations

import os
import statistics
import tempfile
import time
from collections import Counter
from contextlib import contextmanager

from prsc.errors import PrscError


@contextmanager
def _timed(module, name: str, totals: Counter, key: str):
    """Add the process CPU time spent in `module.name` to totals[key] while inside."""
    original = getattr(module, name)

    def wrapper(*args, **kwargs):
        start = time.process_time()
        try:
            return original(*args, **kwargs)
        finally:
            totals[key] += time.process_time() - start

    setattr(module, name, wrapper)
    try:
        yield
    finally:
        setattr(module, name, original)


def bench(spec: str, n: int, controller: str, include_dirs: list[str]) -> dict:
    """Run n episodes (the first as warm-up); CPU totals of the others."""
    from prsc.runner.gl import choose_gl_backend

    gl_backend = choose_gl_backend()
    import mujoco

    import dataclasses

    from prsc.runner import harness, rendering, task_monitor
    from prsc.runner.controller import parse_target
    from prsc.runner.episode_records import DEFAULT_MAX_SIM_SECONDS
    from prsc.runner.worker import WorkerConfig
    from prsc.pipeline.campaign import episode_tasks, run_episodes
    from prsc.commands.compile import compile_scenes
    from prsc.pipeline.executors import make_executor

    # One worker in this process (a local executor of one job runs inline), as `prsc run`'s workers run them.
    executor, config = make_executor("local", 1), WorkerConfig(gl_backend)
    with tempfile.TemporaryDirectory(prefix="prsc-run-bench-") as tmp:
        root = compile_scenes(spec, ["json", "mjcf"], n, 0, tmp, include_dirs=include_dirs)
        tasks, _ = episode_tasks(root, None, 0, parse_target(controller), DEFAULT_MAX_SIM_SECONDS)
        run_episodes(executor, config, tasks[:1], lambda record: None)
        records: list[dict] = []
        ratios: list[float] = []  # per scene: CPU monitored / CPU without the task
        totals: Counter = Counter()
        with_task = bool(tasks and tasks[0].scene.get("task"))
        for k, task in enumerate(tasks[1:]):
            with _timed(harness, "load_model", totals, "load"), _timed(mujoco, "mj_step", totals, "step"), \
                    _timed(rendering.OffscreenRenderer, "rgb", totals, "render"), \
                    _timed(rendering.OffscreenRenderer, "depth", totals, "render"), \
                    _timed(rendering, "_render_context", totals, "render"), \
                    _timed(task_monitor.TaskMonitor, "evaluate_logged", totals, "monitor"), \
                    _timed(task_monitor.TaskMonitor, "update", totals, "monitor"):
                cpu, wall = time.process_time(), time.perf_counter()
                run_episodes(executor, config, [task], records.append)
                totals["cpu"] += time.process_time() - cpu
                totals["wall"] += time.perf_counter() - wall
            if with_task:
                # The task's cost: the scene's episode again with and without it, uninstrumented (a timer
                # around every mj_step would cost the monitored side more), back to back (both see the
                # same load), the first of the two alternating from scene to scene.
                sides = [("with", task), ("without", dataclasses.replace(task, monitor_task=False))]
                first_without = k % 2 == 1
                cpu = {side: _cpu(run_episodes, executor, config, [each])
                       for side, each in (sides[::-1] if first_without else sides)}
                totals["cpu_with_task"] += cpu["with"]
                totals["cpu_without_task"] += cpu["without"]
                ratios.append(cpu["with"] / max(cpu["without"], 1e-9))
    totals["episodes"] = len(records)
    totals["sim"] = sum(r["sim_seconds"] for r in records)
    return {"totals": totals, "outcomes": Counter(r["outcome"] for r in records), "with_task": with_task,
            "ratios": ratios,
            "task_outcomes": Counter(r["task"]["outcome"] for r in records if r.get("task"))}


def _cpu(run, *args) -> float:
    """The process CPU seconds of run(*args, a record callback that drops the record)."""
    start = time.process_time()
    run(*args, lambda record: None)
    return time.process_time() - start


def overhead(ratios: list[float]) -> tuple[float, float, float]:
    """The median and quartiles of per-scene CPU ratios (monitored / without), as % overheads."""
    if len(ratios) < 2:
        return (100 * (ratios[0] - 1),) * 3 if ratios else (float("nan"),) * 3
    low, median, high = statistics.quantiles(ratios, n=4)
    return 100 * (median - 1), 100 * (low - 1), 100 * (high - 1)


def print_episodes(spec: str, n: int, controller: str, include_dirs: list[str]) -> None:
    """Run the benchmark on one spec and print the numbers."""
    if n < 2:
        raise PrscError("-n must be >= 2 with --episodes (one warm-up episode, then the measured ones)")
    found = bench(spec, n, controller, include_dirs)
    t, episodes = found["totals"], found["totals"]["episodes"]
    print(f"prsc episode benchmark: {episodes} episodes of {spec} after one warm-up, one worker, "
          f"load average {os.getloadavg()[0]:.2f}")
    print(f"  {t['cpu'] / episodes:.3f} CPU s per episode = {episodes / t['cpu']:.2f} episodes per CPU-second "
          f"({t['wall'] / episodes:.3f} s wall each, {t['sim'] / episodes:.1f} simulated s each)")
    other = t["cpu"] - t["load"] - t["step"] - t["render"]
    print(f"  per episode: load {t['load'] / episodes:.3f}, mj_step {t['step'] / episodes:.3f} "
          f"({t['sim'] / max(t['step'], 1e-9) / 0.002:,.0f} steps per CPU-second at a 2 ms step), "
          f"render {t['render'] / episodes:.3f}, controller and the rest {other / episodes:.3f} CPU s")
    print("  outcomes: " + ", ".join(f"{o} {c}" for o, c in found["outcomes"].most_common()))
    if found["with_task"]:
        with_task, without = t["cpu_with_task"], t["cpu_without_task"]
        median, low, high = overhead(found["ratios"])
        total = 100 * (with_task - without) / max(without, 1e-9)
        print(f"  the task: each scene's episode again with and without it, back to back: "
              f"{with_task / episodes:.3f} vs {without / episodes:.3f} CPU s per episode ({total:+.1f}% "
              f"in total); per scene, median {median:+.1f}% (quartiles {low:+.1f}% to {high:+.1f}%, "
              f"n={len(found['ratios'])}); the monitor's evaluation {t['monitor'] / episodes:.3f} CPU s per episode")
        print("  task outcomes: " + ", ".join(f"{o} {c}" for o, c in found["task_outcomes"].most_common()))
