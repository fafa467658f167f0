"""Results of a batch: results.jsonl, the terminal summary table and the two plots."""

from __future__ import annotations

import json
from collections import Counter
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from prsc.backends.files import atomic_write
from prsc.backends.runner.episode import OUTCOMES, EpisodeResult
from prsc.geometry.rotations import quat_to_matrix

OUTCOME_COLOURS = {
    "success": "#2ca02c",
    "perception_fault": "#1f77b4",
    "no_path": "#ff7f0e",
    "poor_grip": "#d62728",
    "other": "#7f7f7f",
}


def write_results(results: Sequence[EpisodeResult], path: Path) -> Path:
    """Write results.jsonl (one episode per line, in index order)."""
    lines = [json.dumps(r.to_json(), separators=(", ", ": ")) for r in sorted(results, key=lambda r: r.index)]
    atomic_write(path, "\n".join(lines) + ("\n" if lines else ""))
    return path


def outcome_counts(results: Sequence[EpisodeResult]) -> list[tuple[str, int, float]]:
    """(outcome, count, percent) for every outcome, in the fixed order."""
    counts = Counter(r.outcome for r in results)
    total = max(1, len(results))
    return [(o, counts.get(o, 0), 100.0 * counts.get(o, 0) / total) for o in OUTCOMES]


def summary_table(results: Sequence[EpisodeResult], title: str):
    """A rich Table of outcome, count and percent."""
    from rich.table import Table

    table = Table(title=title)
    table.add_column("outcome")
    table.add_column("count", justify="right")
    table.add_column("percent", justify="right")
    for outcome, count, percent in outcome_counts(results):
        table.add_row(outcome, str(count), f"{percent:.0f}%")
    table.add_section()
    table.add_row("total", str(len(results)), "100%")
    return table


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _save(fig, path: Path) -> Path:
    """Save a figure atomically (temporary sibling, then rename)."""
    tmp = path.with_name(f".{path.stem}.tmp{path.suffix}")
    fig.savefig(tmp, dpi=110)
    tmp.replace(path)
    return path


def plot_outcomes(results: Sequence[EpisodeResult], path: Path, title: str) -> Path:
    """Bar chart of outcome counts."""
    plt = _pyplot()
    rows = outcome_counts(results)
    fig, ax = plt.subplots(figsize=(6.4, 3.6))
    bars = ax.bar([o for o, _, _ in rows], [c for _, c, _ in rows], color=[OUTCOME_COLOURS[o] for o, _, _ in rows])
    for bar, (_, count, percent) in zip(bars, rows):
        ax.annotate(f"{count} ({percent:.0f}%)", (bar.get_x() + bar.get_width() / 2, bar.get_height()),
                    ha="center", va="bottom", fontsize=8)
    ax.set_ylabel("episodes")
    ax.set_title(title, fontsize=10)
    ax.margins(y=0.15)
    fig.tight_layout()
    _save(fig, path)
    plt.close(fig)
    return path


def plot_cube_map(results: Sequence[EpisodeResult], source_trays: Sequence[dict], path: Path, title: str) -> Path:
    """Top-down maps of the cube's initial position coloured by outcome: world and tray frames."""
    plt = _pyplot()
    fig, (world, local) = plt.subplots(1, 2, figsize=(10, 4.6))
    trays = {int(r.index): t for r, t in zip(results, source_trays)}
    for outcome in OUTCOMES:
        chosen = [r for r in results if r.outcome == outcome]
        if not chosen:
            continue
        xy = np.array([r.cube_initial[:2] for r in chosen])
        world.scatter(xy[:, 0], xy[:, 1], s=18, color=OUTCOME_COLOURS[outcome], label=outcome)
        rel = []
        for r in chosen:
            tray = trays[int(r.index)]
            rot = quat_to_matrix(tray["quaternion"])
            rel.append((rot.T @ (np.asarray(r.cube_initial) - np.asarray(tray["position"], float)))[:2])
        rel = np.array(rel)
        local.scatter(rel[:, 0], rel[:, 1], s=18, color=OUTCOME_COLOURS[outcome], label=outcome)
    if source_trays:
        w, l = np.median([t["dimensions"][:2] for t in source_trays], axis=0)
        local.add_patch(plt.Rectangle((-w / 2, -l / 2), w, l, fill=False, lw=1.0, color="black"))
    world.set_title("cube start, world frame (top view)", fontsize=10)
    world.set_xlabel("x (m)")
    world.set_ylabel("y (m)")
    local.set_title("cube start in the source tray's frame (outline: tray)", fontsize=10)
    local.set_xlabel("tray x (m)")
    local.set_ylabel("tray y (m)")
    for ax in (world, local):
        ax.set_aspect("equal", adjustable="datalim")
        ax.grid(alpha=0.3)
    local.legend(fontsize=8, loc="center left", bbox_to_anchor=(1.02, 0.5))
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    _save(fig, path)
    plt.close(fig)
    return path
