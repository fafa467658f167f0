"""Object names as every output format can hold them: one mapping, the same in all formats.

The scene JSON keeps the user's name; MJCF bodies, SDF and URDF models, URDF file names
and USD prims use its element name: the name itself when it is an identifier that no
format reserves, else the name with every other character replaced by `_` (a leading digit
gets a `_` before it), made unique among the scene's names with a numeric suffix.
"""

from __future__ import annotations

import functools
import re
from typing import Sequence

# MJCF's root body is `world`; the other names the backends add (ground, PhysicsScene,
# scene.json) are chosen around the objects' names by the backends themselves.
RESERVED = frozenset({"world"})
_IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")


def is_element_name(name: str) -> bool:
    """Whether every format holds `name` as it is."""
    return bool(_IDENTIFIER.match(name)) and name not in RESERVED


def element_names(names: Sequence[str]) -> tuple[str, ...]:
    """The element name of each of a scene's (distinct) object names, in order."""
    taken = {name for name in names if is_element_name(name)}
    out = []
    for name in names:
        if is_element_name(name):
            out.append(name)
            continue
        base = re.sub(r"[^A-Za-z0-9_]", "_", name)
        if not base or base[0].isdigit():
            base = "_" + base
        if base in RESERVED:
            base += "_"
        candidate, k = base, 1
        while candidate in taken:
            k += 1
            candidate = f"{base}_{k}"
        taken.add(candidate)
        out.append(candidate)
    return tuple(out)


@functools.lru_cache(maxsize=64)
def _element_names(names: tuple[str, ...]) -> tuple[str, ...]:
    """`element_names`, once per set of names (every scene of a spec has the same: a reset loop asks often)."""
    return element_names(names)


def with_body_names(scene: dict) -> dict:
    """A copy of a scene JSON whose objects carry `body`: their element name in the compiled files."""
    objects = scene.get("objects", [])
    names = _element_names(tuple(o["name"] for o in objects))
    return {**scene, "objects": [{**o, "body": body} for o, body in zip(objects, names)]}
