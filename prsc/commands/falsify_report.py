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


CONFIDENCE = 0.95


@dataclass(frozen=True)
class Estimate:
    """An importance-weighted failure probability, its two-sided interval and one-sided upper bound at CONFIDENCE."""

    value: float  # mean(weight * failed): unbiased under the spec's sequential law
    low: float
    high: float
    upper: float  # one-sided: the failure probability is at most this (0 of 60: 0.0487)
    episodes: int
    effective: float  # Kish effective sample size of the weights
    spec_draws: int  # scenes drawn from the spec's own law (all of them in a uniform campaign)
    failures: float  # the binomial counts the interval is exact or effective for: failures ...
    trials: float  # ... in trials
    basis: str  # how the interval was computed, in words


def clopper_pearson(failures: float, trials: float, confidence: float = CONFIDENCE) -> tuple[float, float, float]:
    """(low, high, one-sided upper) of the exact binomial interval, also for effective (non-integer) counts."""
    from scipy.stats import beta

    if not trials > 0:
        return 0.0, 1.0, 1.0
    alpha = 1.0 - confidence
    k = min(max(failures, 0.0), trials)
    low = 0.0 if k <= 0 else float(beta.ppf(alpha / 2, k, trials - k + 1))
    high = 1.0 if k >= trials else float(beta.ppf(1 - alpha / 2, k + 1, trials - k))
    upper = 1.0 if k >= trials else float(beta.ppf(1 - alpha, k + 1, trials - k))
    return low, high, upper


def failure_estimate(failed: Sequence[bool], weights: Sequence[float], spec_draw: Sequence[bool],
                     confidence: float = CONFIDENCE) -> Estimate:
    """mean(weight * failed) and its interval (docs/falsify.md, "Intervals").

    The interval is Clopper-Pearson on binomial counts: with no failure (or no success) at all,
    the exact one on the m scenes drawn from the spec's law (0 of m, or m of m: their count is
    binomial in the target probability whatever the proposal did with the others); with every
    scene drawn from the spec's law, the exact one on (failures, episodes); otherwise on Korn
    and Graubard's effective counts, n* = p (1 - p) / var(estimate) trials with n* p failures,
    n* never more than m."""
    f = np.asarray(failed, dtype=float)
    w = np.asarray(weights, dtype=float)
    n, k, m = len(f), int(f.sum()), int(np.sum(spec_draw))
    value = float(np.mean(w * f)) if n else 0.0
    if k == 0 or k == n:
        failures, trials = float(m if k else 0), float(m)
        basis = (f"exact (Clopper-Pearson): {'no failure' if k == 0 else 'no success'} in the {m} scenes drawn "
                 "from the spec's law" + (f"; rule of three: {3 / m:.4f}" if k == 0 and m else ""))
    elif m == n and np.all(w == 1.0):
        failures, trials = float(k), float(n)
        basis = f"exact (Clopper-Pearson): {k} failures in {n} scenes of the spec's law"
    else:
        p = min(max(value, 0.0), 1.0)
        variance = float(np.var(w * f, ddof=1)) / n
        trials = min(float(m), p * (1 - p) / variance) if variance > 0 and 0 < p < 1 else float(m)
        failures = trials * p
        basis = (f"Clopper-Pearson on effective counts (Korn-Graubard): {failures:.1f} failures in {trials:.1f} "
                 f"(never more than the {m} scenes drawn from the spec's law)")
    low, high, upper = clopper_pearson(failures, trials, confidence)
    ess = float(w.sum() ** 2 / (w ** 2).sum()) if n and (w ** 2).sum() > 0 else 0.0
    return Estimate(value, low, high, upper, n, ess, m, failures, trials, basis)


def weighted_estimate(records: Sequence[dict], judged: Sequence[Any]) -> Estimate:
    """The campaign's estimate: its records (weight, spec_draw) judged against the property (Verdicts)."""
    return failure_estimate([v.failed for v in judged], [float(r["weight"]) for r in records],
                            [bool(r["spec_draw"]) for r in records])


def feature_vector(record: dict, sites: Sequence[str]) -> np.ndarray:
    """The episode's normalised coordinates over `sites` (NaN where a site did not draw)."""
    parts = []
    for site in sites:
        parts.extend(record.get("features", {}).get(site, [float("nan")]))
    return np.array(parts, dtype=float)


def failure_clusters(records: Sequence[dict], judged: Sequence[Any], radius: float = CLUSTER_RADIUS) -> list[dict]:
    """Distinct failures: leader clustering, a failure within `radius` of a leader on every coordinate joins it."""
    failures = [(r, v.label) for r, v in zip(records, judged) if v.failed]
    sites = sorted({s for r, _ in failures for s in r.get("features", {})})
    leaders: list[tuple[np.ndarray, dict]] = []
    for record, label in failures:
        x = feature_vector(record, sites)
        for centre, cluster in leaders:
            if len(x) == len(centre) and np.all(np.nan_to_num(np.abs(x - centre), nan=0.0) <= radius):
                cluster["episodes"].append(record["index"])
                cluster["outcomes"][label] = cluster["outcomes"].get(label, 0) + 1
                break
        else:
            leaders.append((x, {"leader": record["index"], "episodes": [record["index"]], "outcomes": {label: 1},
                                "features": record.get("features", {})}))
    return [cluster for _, cluster in leaders]


def summary_lines(records: Sequence[dict], judged: Sequence[Any], law: str) -> list[tuple[str, str]]:
    """(label, value) rows of the falsify summary."""
    est = weighted_estimate(records, judged)
    failed = sum(v.failed for v in judged)
    inexact = sum(1 for r in records if r.get("collision_rejections"))
    rows = [("episodes", str(len(records))), ("failed episodes (raw)", f"{failed} ({100 * failed / max(len(records), 1):.0f} per 100)"),
            (f"failure probability under the spec's {law} law (weighted)",
             f"{est.value:.4f}  {100 * CONFIDENCE:.0f}% CI [{est.low:.4f}, {est.high:.4f}]"),
            (f"{100 * CONFIDENCE:.0f}% upper bound (one-sided)", f"{est.upper:.4f}"),
            ("interval", est.basis),
            ("effective sample size of the weights", f"{est.effective:.0f}")]
    known = [(v.robustness, r["index"]) for r, v in zip(records, judged) if v.robustness is not None]
    if known:
        lowest, index = min(known)
        rows.append(("lowest robustness (episode)", f"{lowest:.4g} ({index})"))
    if inexact:
        rows.append(("scenes whose weights ignore collision rejections", str(inexact)))
    return rows


def write_report(records: Sequence[dict], judged: Sequence[Any], proposal: Any, masses: dict, out: Path, title: str,
                 declared: Sequence[str]):
    """Write clusters.json, summary.txt and falsify.png; return the summary as a rich Table."""
    from collections import Counter

    from rich.table import Table

    from prsc.runner.report import outcome_counts
    from prsc.files import atomic_write

    clusters = failure_clusters(records, judged)
    atomic_write(out / "clusters.json", json.dumps({"radius": CLUSTER_RADIUS, "clusters": clusters}, indent=1) + "\n")
    table = Table(title=title)
    table.add_column("")
    table.add_column("value", justify="right")
    for outcome, count, percent in outcome_counts(records, declared):
        table.add_row(f"outcome {outcome}", f"{count} ({percent:.0f}%)")
    if any(v.from_task for v in judged):
        table.add_section()
        for label, count in sorted(Counter(v.label for v in judged).items()):
            table.add_row(f"task {label}", f"{count} ({100 * count / max(len(records), 1):.0f}%)")
    table.add_section()
    rows = summary_lines(records, judged, proposal.law)
    rows.append(("distinct failure clusters", str(len(clusters))))
    for k, cluster in enumerate(sorted(clusters, key=lambda c: -len(c["episodes"]))[:SHOWN]):
        labels = ", ".join(f"{o} {n}" for o, n in sorted(cluster["outcomes"].items()))
        rows.append((f"  cluster {k} (episode {cluster['leader']})", f"{len(cluster['episodes'])}: {labels}"))
    if len(clusters) > SHOWN:
        rows.append((f"  ... {len(clusters) - SHOWN} more", "clusters.json"))
    for label, value in rows:
        table.add_row(label, value)
    atomic_write(out / "summary.txt", "\n".join(f"{label}: {value}" for label, value in rows) + "\n")
    plot_sites(records, judged, proposal, masses, out / "falsify.png", title)
    return table


def plot_sites(records: Sequence[dict], judged: Sequence[Any], proposal: Any, masses: dict, path: Path,
               title: str) -> None:
    """Per site, the learnt proposal's density relative to the spec's law and where episodes failed."""
    from prsc.runner.report import _pyplot, _save

    plt = _pyplot()
    sites = sorted(masses)
    fig, axes = plt.subplots(1, max(len(sites), 1), figsize=(4 * max(len(sites), 1), 3.8), squeeze=False)
    for ax, site in zip(axes[0], sites):
        mass = np.asarray(masses[site], dtype=float)
        points = [(r["features"][site], v.failed) for r, v in zip(records, judged) if site in r.get("features", {})]
        dims = len(points[0][0]) if points else 1
        ratio = proposal.site_density(site, mass, dims)
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
