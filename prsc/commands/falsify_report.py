"""What `prsc falsify` reports: the weighted estimate, distinct failure clusters, the summary and plots."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Sequence

import numpy as np

SHOWN = 10  # clusters listed in the summary (all are in clusters.json)
CLUSTER_RADIUS = 0.1  # normalised units per coordinate: failures this close are one scene repeated


@dataclass(frozen=True)
class Estimate:
    """An importance-weighted failure probability with its 95 % normal interval."""

    value: float
    low: float
    high: float
    episodes: int
    effective: float  # Kish effective sample size of the weights


def weighted_estimate(records: Sequence[dict]) -> Estimate:
    """mean(w * failed) over every episode (unbiased: each round's proposal is fixed before it runs)."""
    w = np.array([float(r["weight"]) for r in records])
    y = w * np.array([r["outcome"] != "success" for r in records], dtype=float)
    n = len(y)
    mean = float(y.mean()) if n else 0.0
    half = 1.96 * float(y.std(ddof=1)) / math.sqrt(n) if n > 1 else float("inf")
    ess = float(w.sum() ** 2 / (w ** 2).sum()) if n and (w ** 2).sum() > 0 else 0.0
    return Estimate(mean, max(0.0, mean - half), min(1.0, mean + half), n, ess)


def feature_vector(record: dict, sites: Sequence[str]) -> np.ndarray:
    """The episode's normalised coordinates over `sites` (NaN where a site did not draw)."""
    parts = []
    for site in sites:
        parts.extend(record.get("features", {}).get(site, [float("nan")]))
    return np.array(parts, dtype=float)


def failure_clusters(records: Sequence[dict], radius: float = CLUSTER_RADIUS) -> list[dict]:
    """Distinct failures: leader clustering, a failure within `radius` of a leader on every coordinate joins it."""
    failures = [r for r in records if r["outcome"] != "success"]
    sites = sorted({s for r in failures for s in r.get("features", {})})
    leaders: list[tuple[np.ndarray, dict]] = []
    for record in failures:
        x = feature_vector(record, sites)
        for centre, cluster in leaders:
            if len(x) == len(centre) and np.all(np.nan_to_num(np.abs(x - centre), nan=0.0) <= radius):
                cluster["episodes"].append(record["index"])
                cluster["outcomes"][record["outcome"]] = cluster["outcomes"].get(record["outcome"], 0) + 1
                break
        else:
            leaders.append((x, {"leader": record["index"], "episodes": [record["index"]],
                                "outcomes": {record["outcome"]: 1},
                                "features": record.get("features", {})}))
    return [cluster for _, cluster in leaders]


def summary_lines(records: Sequence[dict], law: str) -> list[tuple[str, str]]:
    """(label, value) rows of the falsify summary."""
    est = weighted_estimate(records)
    failed = sum(r["outcome"] != "success" for r in records)
    inexact = sum(1 for r in records if r.get("collision_rejections"))
    rows = [("episodes", str(len(records))), ("failed episodes (raw)", f"{failed} ({100 * failed / max(len(records), 1):.0f} per 100)"),
            (f"failure probability under the spec's {law} law (weighted)", f"{est.value:.3f}  95% CI [{est.low:.3f}, {est.high:.3f}]"),
            ("effective sample size of the weights", f"{est.effective:.0f}")]
    if inexact:
        rows.append(("scenes whose weights ignore collision rejections", str(inexact)))
    return rows


def write_report(records: Sequence[dict], proposal: Any, masses: dict, out: Path, title: str, declared: Sequence[str]):
    """Write clusters.json, summary.txt and falsify.png; return the summary as a rich Table."""
    from rich.table import Table

    from prsc.runner.report import outcome_counts
    from prsc.files import atomic_write

    clusters = failure_clusters(records)
    atomic_write(out / "clusters.json", json.dumps({"radius": CLUSTER_RADIUS, "clusters": clusters}, indent=1) + "\n")
    table = Table(title=title)
    table.add_column("")
    table.add_column("value", justify="right")
    for outcome, count, percent in outcome_counts(records, declared):
        table.add_row(f"outcome {outcome}", f"{count} ({percent:.0f}%)")
    table.add_section()
    rows = summary_lines(records, proposal.law)
    rows.append(("distinct failure clusters", str(len(clusters))))
    for k, cluster in enumerate(sorted(clusters, key=lambda c: -len(c["episodes"]))[:SHOWN]):
        labels = ", ".join(f"{o} {n}" for o, n in sorted(cluster["outcomes"].items()))
        rows.append((f"  cluster {k} (episode {cluster['leader']})", f"{len(cluster['episodes'])}: {labels}"))
    if len(clusters) > SHOWN:
        rows.append((f"  ... {len(clusters) - SHOWN} more", "clusters.json"))
    for label, value in rows:
        table.add_row(label, value)
    atomic_write(out / "summary.txt", "\n".join(f"{label}: {value}" for label, value in rows) + "\n")
    plot_sites(records, proposal, masses, out / "falsify.png", title)
    return table


def plot_sites(records: Sequence[dict], proposal: Any, masses: dict, path: Path, title: str) -> None:
    """Per site, the learnt proposal's density relative to the spec's law and where episodes failed."""
    from prsc.runner.report import _pyplot, _save

    plt = _pyplot()
    sites = sorted(masses)
    fig, axes = plt.subplots(1, max(len(sites), 1), figsize=(4 * max(len(sites), 1), 3.8), squeeze=False)
    for ax, site in zip(axes[0], sites):
        mass = np.asarray(masses[site], dtype=float)
        ratio = proposal.site_density(site, mass)
        points = [(r["features"][site], r["outcome"] != "success") for r in records if site in r.get("features", {})]
        dims = len(points[0][0]) if points else 1
        if dims >= 2:
            k = int(round(len(mass) ** (1.0 / dims)))
            grid = ratio.reshape((k,) * dims)
            grid = grid.mean(axis=tuple(range(2, dims))) if dims > 2 else grid
            image = ax.imshow(grid.T, origin="lower", extent=(0, 1, 0, 1), cmap="Blues", vmin=0)
            fig.colorbar(image, ax=ax, label="proposal / spec density")
            for failed in (False, True):
                xy = np.array([p[:2] for p, f in points if f == failed]).reshape(-1, 2)
                ax.scatter(xy[:, 0], xy[:, 1], s=10 if failed else 4, c="red" if failed else "0.5",
                           marker="x" if failed else "o", label="failed" if failed else "succeeded")
            ax.set_xlabel("axis 1 of the region's box (normalised)")
            ax.set_ylabel("axis 2")
        else:
            ax.bar((np.arange(len(mass)) + 0.5) / len(mass), ratio, width=1 / len(mass), color="#9ecae1")
            fails = [p[0] for p, f in points if f]
            ax.hist(fails, bins=len(mass), range=(0, 1), histtype="step", color="red",
                    weights=np.full(len(fails), 1.0 / max(len(points), 1) * len(mass)), label="failed (density)")
            ax.set_xlabel("normalised value")
        ax.set_title(site, fontsize=9)
        ax.legend(fontsize=7, loc="upper right")
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    _save(fig, path)
    plt.close(fig)
