"""Rejection statistics by cause (the paper's Table II, plus require and dead ends)."""

from __future__ import annotations

from dataclasses import dataclass, field

from prsc.constraints.polytope_ir import CAUSES, DEAD_END


@dataclass
class RejectionStats:
    """Counts of rejected draws by cause, over one or more scenes."""

    counts: dict[str, int] = field(default_factory=dict)
    scenes: int = 0

    def add(self, cause: str, n: int = 1) -> None:
        """Count n rejections of one cause."""
        self.counts[cause] = self.counts.get(cause, 0) + n

    def merge(self, other: RejectionStats) -> None:
        """Add another set of counts (and its scenes) to this one."""
        for cause, n in other.counts.items():
            self.add(cause, n)
        self.scenes += other.scenes

    @property
    def total(self) -> int:
        """All rejections (dead ends included)."""
        return sum(self.counts.values())

    def by_cause(self) -> dict[str, int]:
        """Counts for every cause (zeros included), dead ends last."""
        out = {cause: self.counts.get(cause, 0) for cause in CAUSES}
        out[DEAD_END] = self.counts.get(DEAD_END, 0)
        for cause, n in self.counts.items():
            out.setdefault(cause, n)
        return out

    def summary(self) -> str:
        """One line: 'collision 3, containment 1' (or 'no rejections')."""
        parts = [f"{cause} {n}" for cause, n in self.by_cause().items() if n]
        return ", ".join(parts) if parts else "no rejections"
