"""Splicing cached, pre-serialised XML into a document (robot models reused across scenes).

Serialising a robot's hundred elements for every scene costs more than the rest of the
scene: backends serialise it once per process and drop the text in where a placeholder
element stands.
"""

from __future__ import annotations

import copy
import xml.etree.ElementTree as ET

SPLICE = "prsc_splice"


def element_text(element: ET.Element) -> str:
    """An element as indented XML text (two spaces), no trailing newline."""
    element = copy.deepcopy(element)
    element.tail = None
    ET.indent(element, space="  ")
    return ET.tostring(element, encoding="unicode").strip()


def placeholder(parent: ET.Element, pieces: list[str], text: str) -> None:
    """Append a placeholder for `text` under `parent` (recorded in `pieces`)."""
    ET.SubElement(parent, SPLICE, id=str(len(pieces)))
    pieces.append(text)


def serialise(root: ET.Element, pieces: list[str]) -> str:
    """Indent and serialise `root`, replacing each placeholder line by its piece, re-indented."""
    ET.indent(root, space="  ")
    out = []
    for line in ET.tostring(root, encoding="unicode").split("\n"):
        stripped = line.lstrip()
        if stripped.startswith(f"<{SPLICE} "):
            indent = line[: len(line) - len(stripped)]
            piece = pieces[int(stripped.split('"')[1])]
            out.append("\n".join(indent + l for l in piece.split("\n")))
        else:
            out.append(line)
    return "\n".join(out)
