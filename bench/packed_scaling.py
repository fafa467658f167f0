"""How the cost of packed bins grows (issue 38; docs/sampling.md, "Gibbs rounds"): a bin of
washers and bolts (specs/bin_ten_parts.prs) at 5, 10, 20 and 40 parts with the bin grown to
keep the density, and 10 parts at three densities. Per case: the path the default law takes,
scenes per CPU-second under the joint and the sequential law (`prsc bench`'s measurement, each
in a fresh process, with its peak resident memory), and the mixing: the largest |correlation|
of a coordinate with its start after 1 sweep and after the default sweeps, against the same
statistic between two independent starts (the noise floor), over 256 scenes.

Run: .venv/bin/python bench/packed_scaling.py [--seconds 5]   (prints a markdown table,
writes docs/img/packed_scaling.png)
"""

from __future__ import annotations

import argparse
import math
import tempfile
from pathlib import Path

import numpy as np

from prsc.commands.bench import measure_isolated
from prsc.sampling import compile_sampler
from prsc.sampling.group_gibbs import GroupGibbs

REPO = Path(__file__).resolve().parents[1]
CLASSES = (REPO / "specs" / "bin_ten_parts.prs").read_text().split("table = ")[0]
BIN = (0.36, 0.28)  # the ten-part bin's outer size
CASES = [  # (label, parts, bin area over the ten-part bin's per part)
    ("5 parts", 5, 1.0), ("10 parts", 10, 1.0), ("20 parts", 20, 1.0), ("40 parts", 40, 1.0),
    ("10 parts, loose", 10, 1.5), ("10 parts, dense", 10, 0.85),
]
MIXING_SCENES = 256


def spec_text(parts: int, area: float) -> str:
    """The bin of `parts` parts (washers first), its area `area` times the ten-part bin's per part."""
    scale = math.sqrt(area * parts / 10)
    width, length = BIN[0] * scale, BIN[1] * scale
    lines = [CLASSES, f"table = Table on Vector3D(0, 0, 0), with width {width + 0.6:.3f}, with length {length + 0.5:.3f}, "
             "with height 0.75",
             f"bin_1 = Bin completely on table, with width {width:.4f}, with length {length:.4f}, with height 0.12"]
    lines += [f"washer_{i} = Washer completely in bin_1" for i in range((parts + 1) // 2)]
    lines += [f"bolt_{i} = Bolt completely in bin_1" for i in range(parts // 2)]
    return "\n".join(lines) + "\n"


def _coordinates(result) -> np.ndarray:
    at = {o.name: o for o in result.objects}
    base = at["bin_1"].position
    return np.concatenate([np.r_[(o.position - base)[:2], o.dims[0] if o.name.startswith("washer") else o.dims[2]]
                           for o in result.objects if o.name.startswith(("washer", "bolt"))])


def _largest(a: np.ndarray, b: np.ndarray) -> float:
    return float(max(abs(np.corrcoef(a[:, j], b[:, j])[0, 1]) for j in range(a.shape[1])))


def mixing(path: str) -> dict[str, float]:
    """Start correlation after 1 sweep and after the default sweeps, and the floor (two independent starts)."""
    sampler = compile_sampler(path)
    group = sampler._group
    if group is None:  # candidate rounds: exact draws, no chain
        return {}

    def rows(sweeps: int, seed: int) -> np.ndarray:
        chain = GroupGibbs(group.objects, group.cprog, group.runtimes, sweeps)
        return np.array([_coordinates(r) for r in chain.draw(seed, range(MIXING_SCENES))])

    start = rows(0, 1)
    return {"one": _largest(start, rows(1, 1)), "default": _largest(start, rows(group.sweeps, 1)),
            "floor": _largest(start, rows(0, 2)), "sweeps": group.sweeps}


def main() -> None:
    """Measure every case, print the table, write the plot."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--seconds", type=float, default=5.0)
    args = parser.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for label, parts, area in CASES:
            path = Path(tmp) / f"bin_{parts}_{area}.prs"
            path.write_text(spec_text(parts, area))
            sampler = compile_sampler(path)
            interior = (sampler.runtimes[1].dims[0] - 0.018) * (sampler.runtimes[1].dims[1] - 0.018)
            rates = {law: measure_isolated(str(path), [], "exact", 20000, args.seconds, 0, 100, law)
                     for law in ("joint", "sequential")}
            row = {"case": label, "parts": parts, "path": sampler.plan.path, "floor_m2": interior,
                   "joint": rates["joint"]["scenes_per_s"], "sequential": rates["sequential"]["scenes_per_s"],
                   "joint_mb": rates["joint"]["peak_memory_mb"], "sequential_mb": rates["sequential"]["peak_memory_mb"],
                   **mixing(str(path))}
            rows.append(row)
            print(row, flush=True)
    print("\n| case | bin floor (m^2) | path | joint scenes/s | sequential scenes/s | joint / sequential "
          "| start corr. after 1 sweep / default sweeps / floor | peak MB joint / sequential |")
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        mix = "exact draws" if "one" not in r else f"{r['one']:.2f} / {r['default']:.2f} ({r['sweeps']}) / {r['floor']:.2f}"
        print(f"| {r['case']} | {r['floor_m2']:.3f} | {r['path']} | {r['joint']:,.0f} | {r['sequential']:,.0f} | "
              f"{r['joint'] / r['sequential']:.1f} | {mix} | {r['joint_mb']:.0f} / {r['sequential_mb']:.0f} |")
    _plot(rows)


def _plot(rows: list[dict]) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (left, right) = plt.subplots(1, 2, figsize=(10, 4))
    growth = [r for r in rows if "," not in r["case"]]
    parts = [r["parts"] for r in growth]
    for law, style in (("joint", "o-"), ("sequential", "s--")):
        left.plot(parts, [r[law] for r in growth], style, label=f"{law} law")
    left.set_xscale("log", base=2)
    left.set_yscale("log")
    left.set_xticks(parts, [str(p) for p in parts])
    left.set_xlabel("parts (bin grown to keep the density)")
    left.set_ylabel("scenes per CPU-second")
    left.legend()
    left.grid(alpha=0.3)
    ten = sorted((r for r in rows if r["parts"] == 10), key=lambda r: -r["floor_m2"])
    density = [10 / r["floor_m2"] for r in ten]
    for law, style in (("joint", "o-"), ("sequential", "s--")):
        right.plot(density, [r[law] for r in ten], style, label=f"{law} law")
    for r, x in zip(ten, density):
        if r["path"] != "Gibbs rounds":
            right.annotate(r["path"], (x, r["joint"]), textcoords="offset points", xytext=(8, -12), fontsize=8)
    right.set_yscale("log")
    right.set_xlabel("10 parts: parts per m^2 of bin floor")
    right.legend()
    right.grid(alpha=0.3)
    fig.suptitle("Packed bins of washers and bolts (random sizes and yaws)")
    fig.tight_layout()
    out = REPO / "docs" / "img" / "packed_scaling.png"
    fig.savefig(out, dpi=110)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
