"""`prsc bench --backends SPEC`: files written per second per format (`make bench`).

Each run is `prsc compile` end to end (sampling, rendering, atomic writes, manifest) into a
fresh temporary folder; the asset store (robot meshes) is warmed first so runs measure
steady-state throughput. Prints one line per format and job count.
"""

from __future__ import annotations

import os
import shutil
import tempfile
import time
from pathlib import Path

from prsc.pipeline.executors import cpu_seconds


def _count_files(folder: Path) -> int:
    return sum(1 for p in folder.rglob("*") if p.is_file())


def bench(spec: str, n: int, jobs: list[int], targets: list[str], include_dirs: list[str] = ()) -> list[dict]:
    """Time `prsc compile` of `n` scenes per target and job count."""
    from prsc.backends import TARGETS
    from prsc.commands.compile import compile_scenes

    rows = []
    with tempfile.TemporaryDirectory(prefix="prsc-bench-") as tmp:
        warm = Path(tmp) / "warm"
        # Fill the build cache (robot conversions) and check the spec compiles.
        root = compile_scenes(spec, list(TARGETS), 1, 0, str(warm), include_dirs=list(include_dirs))
        for target in targets:
            for j in jobs:
                out = Path(tmp) / f"{target}-{j}"
                # Start from a warm store so the run times scenes, not the one-off mesh copy.
                shutil.copytree(root / "assets", out / root.name / "assets")
                cpu_before = cpu_seconds()
                start = time.perf_counter()
                compile_scenes(spec, [target], n, 0, str(out), jobs=j, include_dirs=list(include_dirs))
                seconds = time.perf_counter() - start
                cpu = cpu_seconds() - cpu_before
                files = _count_files(out / root.name / target)
                rows.append({"target": target, "jobs": j, "scenes": n, "files": files, "seconds": seconds, "cpu": cpu})
                shutil.rmtree(out)
    return rows


def print_backends(spec: str, n: int, jobs: list[int], targets: list[str], include_dirs: list[str] = ()) -> None:
    """Run the backends benchmark on one spec and print a table."""
    os.environ.setdefault("MUJOCO_GL", "egl")
    print(f"prsc backends benchmark: {n} scenes of {spec}, {os.cpu_count()} CPUs")
    print(f"load average {os.getloadavg()[0]:.2f} (other processes slow the wall-clock rates; the CPU-time rate is")
    print("scenes per CPU second over all processes of the run: on an idle machine, scenes/s ~ jobs x that)")
    print(f"{'target':<6} {'jobs':>4} {'seconds':>8} {'scenes/s':>9} {'files':>7} {'files/s':>9} {'scenes/cpu-s':>13}")
    for row in bench(spec, n, jobs, targets, include_dirs):
        print(f"{row['target']:<6} {row['jobs']:>4} {row['seconds']:>8.2f} {row['scenes'] / row['seconds']:>9.1f}"
              f" {row['files']:>7} {row['files'] / row['seconds']:>9.1f} {row['scenes'] / row['cpu']:>13.1f}", flush=True)
