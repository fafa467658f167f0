"""Results of a campaign: results.jsonl records, the terminal summary table and the plots.

A record is one results.jsonl object (a dict). Outcomes are listed in the order the
controller declares them, then any others (`error`, `timeout`, labels it did not declare)
in the order they first appear."""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from prsc.geometry.rotations import quat_to_matrix

OUTCOME_COLOURS = {
    "success": "#2ca02c",
    "perception_fault": "#1f77b4",
    "no_path": "#ff7f0e",
    "poor_grip": "#d62728",
    "other": "#7f7f7f",
    "error": "#000000",
    "timeout": "#bcbd22",
}


def outcome_order(records: Sequence[dict], declared: Sequence[str] = ()) -> list[str]:
    """Declared outcomes first, then the others in order of first appearance."""
    return list(dict.fromkeys([*declared, *(r["outcome"] for r in records)]))


def outcome_counts(records: Sequence[dict], declared: Sequence[str] = ()) -> list[tuple[str, int, float]]:
    """(outcome, count, percent) for every declared or seen outcome."""
    counts = Counter(r["outcome"] for r in records)
    total = max(1, len(records))
    return [(o, counts.get(o, 0), 100.0 * counts.get(o, 0) / total) for o in outcome_order(records, declared)]


def outcome_colour(outcome: str, order: Sequence[str]) -> str:
    """A fixed colour for the handover's labels and `error`/`timeout`, else one from a palette."""
    if outcome in OUTCOME_COLOURS:
        return OUTCOME_COLOURS[outcome]
    palette = ("#9467bd", "#8c564b", "#e377c2", "#17becf", "#bcbd22", "#aec7e8", "#ffbb78", "#98df8a")
    others = [o for o in order if o not in OUTCOME_COLOURS]
    return palette[others.index(outcome) % len(palette)]


def summary_table(records: Sequence[dict], title: str, declared: Sequence[str] = ()):
    """A rich Table of outcome, count and percent."""
    from rich.table import Table

    table = Table(title=title)
    table.add_column("outcome")
    table.add_column("count", justify="right")
    table.add_column("percent", justify="right")
    for outcome, count, percent in outcome_counts(records, declared):
        table.add_row(outcome, str(count), f"{percent:.0f}%")
    table.add_section()
    table.add_row("total", str(len(records)), "100%")
    return table


TASK_OUTCOMES = ("success", "timeout", "incomplete")
"""The task outcomes besides `fail:LABEL` (docs/tasks.md), in the order tables list them."""


def task_outcome_order(records: Sequence[dict]) -> list[str]:
    """success, each fail:LABEL seen, timeout, incomplete, then anything else seen (an `error`)."""
    seen = [r["task"]["outcome"] for r in records if r.get("task")]
    fails = sorted({o for o in seen if o.startswith("fail:")})
    return list(dict.fromkeys(["success", *fails, "timeout", "incomplete", *seen]))


def task_table(records: Sequence[dict], title: str, declared: Sequence[str] = ()):
    """A rich Table of the task's outcome against the controller's (episodes with a task), with `trivial`."""
    from rich.table import Table

    tasked = [r for r in records if r.get("task")]
    columns = task_outcome_order(tasked)
    table = Table(title=f"{title}: task outcome (columns) by the controller's outcome (rows)")
    table.add_column("controller \\ task")
    for column in columns:
        table.add_column(column, justify="right")
    table.add_column("trivial", justify="right")
    for outcome in outcome_order(tasked, declared):
        row = [r for r in tasked if r["outcome"] == outcome]
        if not row and outcome not in declared:
            continue
        counts = Counter(r["task"]["outcome"] for r in row)
        table.add_row(outcome, *(str(counts.get(c, 0)) for c in columns),
                      str(sum(bool(r["task"].get("trivial")) for r in row)))
    table.add_section()
    counts = Counter(r["task"]["outcome"] for r in tasked)
    table.add_row("total", *(str(counts.get(c, 0)) for c in columns), str(sum(bool(r["task"].get("trivial")) for r in tasked)))
    return table


def plot_task_outcomes(records: Sequence[dict], path: Path, title: str, declared: Sequence[str] = ()) -> Path:
    """Stacked bars: episodes per controller outcome, split by the task's outcome."""
    plt = _pyplot()
    tasked = [r for r in records if r.get("task")]
    rows = outcome_order(tasked, declared)
    columns = task_outcome_order(tasked)
    fig, ax = plt.subplots(figsize=(6.4, 3.6))
    bottom = np.zeros(len(rows))
    palette = {"success": "#2ca02c", "timeout": "#7f7f7f", "incomplete": "#bcbd22"}
    others = ("#d62728", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#17becf")
    for k, column in enumerate(columns):
        heights = np.array([sum(1 for r in tasked if r["outcome"] == row and r["task"]["outcome"] == column)
                            for row in rows], dtype=float)
        if not heights.any():
            continue
        ax.bar(rows, heights, bottom=bottom, label=f"task: {column}", color=palette.get(column, others[k % len(others)]))
        bottom += heights
    ax.set_ylabel("episodes")
    ax.set_xlabel("controller's outcome")
    ax.set_title(title + " (task outcome stacked)", fontsize=10)
    ax.legend(fontsize=7)
    fig.tight_layout()
    _save(fig, path)
    plt.close(fig)
    return path


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


def plot_outcomes(records: Sequence[dict], path: Path, title: str, declared: Sequence[str] = ()) -> Path:
    """Bar chart of outcome counts."""
    plt = _pyplot()
    rows = outcome_counts(records, declared)
    order = [o for o, _, _ in rows]
    fig, ax = plt.subplots(figsize=(6.4, 3.6))
    bars = ax.bar(order, [c for _, c, _ in rows], color=[outcome_colour(o, order) for o in order])
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


def plot_cube_map(records: Sequence[dict], source_trays: Sequence[dict], path: Path, title: str) -> Path:
    """Top-down maps of the cube's initial position coloured by outcome: world and tray frames.

    Records without `cube_initial` (an `error` or `timeout`) are left out."""
    plt = _pyplot()
    fig, (world, local) = plt.subplots(1, 2, figsize=(10, 4.6))
    trays = {int(r["index"]): t for r, t in zip(records, source_trays)}
    order = outcome_order(records)
    for outcome in order:
        chosen = [r for r in records if r["outcome"] == outcome and r.get("cube_initial")]
        if not chosen:
            continue
        colour = outcome_colour(outcome, order)
        xy = np.array([r["cube_initial"][:2] for r in chosen])
        world.scatter(xy[:, 0], xy[:, 1], s=18, color=colour, label=outcome)
        rel = []
        for r in chosen:
            tray = trays[int(r["index"])]
            rot = quat_to_matrix(tray["quaternion"])
            rel.append((rot.T @ (np.asarray(r["cube_initial"]) - np.asarray(tray["position"], float)))[:2])
        rel = np.array(rel)
        local.scatter(rel[:, 0], rel[:, 1], s=18, color=colour, label=outcome)
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
