"""Per-scene evaluation state: the scene's random stream, memoised draws, placed objects."""

from __future__ import annotations

from typing import Any

import numpy as np

from prsc.constraints.values import ObjectValue

# Uniforms are fetched from the generator in blocks: one numpy call instead of one per
# draw. The block boundaries depend only on how many draws came before, so the stream is
# still a pure function of (seed, index).
_BLOCK = 32


class SceneContext:
    """Everything one scene's evaluation reads and writes.

    `level` is the index of the object being placed (-1 before the first): every memoised
    draw or variable is journalled with it so a backtrack to object k forgets exactly the
    values drawn while placing objects k, k+1, ...
    """

    __slots__ = ("rng", "_buffer", "draws", "variables", "objects", "journal", "level", "active_requires", "proposal", "prepared")

    def __init__(self, rng: np.random.Generator) -> None:
        self.rng = rng
        self._buffer: list[float] = []
        self.draws: dict[int, Any] = {}
        self.variables: dict[str, Any] = {}
        self.objects: dict[str, ObjectValue] = {}
        self.journal: list[tuple[int, int, Any]] = []  # (level, 0 draw / 1 variable, key)
        self.level = -1
        self.active_requires: frozenset[int] = frozenset()
        # A falsification proposal's per-scene state (prsc/sampling/proposal.py), or None: the spec's law.
        self.proposal: Any = None
        # The sampler's regions prepared in this scene, by the sampling stage's own keys
        # (prsc/sampling/prepared_regions.py): kept with the scene, so threads sharing a sampler never mix them.
        self.prepared: dict[Any, Any] = {}

    def uniform(self) -> float:
        """A uniform draw from [0, 1)."""
        buffer = self._buffer
        if not buffer:
            buffer.extend(self.rng.random(_BLOCK).tolist())
            buffer.reverse()
        return buffer.pop()

    def normal(self) -> float:
        """A standard normal draw."""
        return float(self.rng.standard_normal())

    def remember_draw(self, draw_id: int, value: Any) -> None:
        """Memoise a distribution's value for the rest of this scene (or until a backtrack)."""
        self.draws[draw_id] = value
        self.journal.append((self.level, 0, draw_id))

    def remember_variable(self, name: str, value: Any) -> None:
        """Memoise a global variable's value."""
        self.variables[name] = value
        self.journal.append((self.level, 1, name))

    def rollback(self, level: int) -> None:
        """Forget every draw and variable memoised while placing objects >= level."""
        if self.proposal is not None:
            self.proposal.rollback(level)
        journal = self.journal
        while journal and journal[-1][0] >= level:
            _, kind, key = journal.pop()
            if kind == 0:
                self.draws.pop(key, None)
            else:
                self.variables.pop(key, None)
