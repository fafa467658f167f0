"""Scene JSON lines of a batched spec from one text template (`prsc sample`'s fast path).

In a batched spec (batched.py) only the seed, the index and the centres of the objects that
move change between scenes: the rest of a scene's JSON text is the same. The template is
the JSON encoder's own output for one scene with holes there, filled per scene with
`%`-formatting; floats print as `repr`, as the encoder prints them, so each line is the
text `json.dumps` gives for the scene's dict (tests/sampling/test_batched.py).
"""

from __future__ import annotations

import json
from typing import Any, Sequence

import numpy as np

_HOLE = "\x00prsc-hole-{}\x00"


class SceneText:
    """A spec's scene JSON line with holes for the seed, the index and the moving centres."""

    def __init__(self, example: dict[str, Any], moving: Sequence[int], encode: Any) -> None:
        scene = dict(example, seed=_HOLE.format("seed"), index=_HOLE.format("index"))
        scene["objects"] = [dict(o, position=_HOLE.format("position")) if k in moving else o
                            for k, o in enumerate(example["objects"])]
        text = encode(scene).replace("%", "%%")
        for name, field in (("seed", "%d"), ("index", "%d"), ("position", "[%r,%r,%r]")):
            text = text.replace(encode(_HOLE.format(name)), field)
        self.template = text + "\n"
        self.moving = tuple(moving)

    def lines(self, seed: int, indices: Sequence[int], centres: Sequence[np.ndarray]) -> list[str]:
        """The lines of scenes `indices` whose moving objects' centres are `centres` (one (n, 3) array each)."""
        template = self.template
        rows = np.hstack([centres[k] for k in self.moving]).tolist() if self.moving else [[]] * len(indices)
        return [template % (seed, int(index), *row) for index, row in zip(indices, rows)]


def scene_encoder() -> Any:
    """The encoder of scene JSON lines: compact, and no NaN or infinity."""
    return json.JSONEncoder(separators=(",", ":"), allow_nan=False).encode
