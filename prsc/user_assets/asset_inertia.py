"""Inertias in a user's URDF that no simulator accepts (docs/assets.md): the triangle
inequality broken (the xArm's link2, balanced as MuJoCo's balanceinertia does), or a mass
or moment of zero (the random_urdfs' izz = 0, recomputed from the geometry). Each fix is
said once per file, as an AssetFixWarning that `prsc check` and `compile` print."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path


class AssetFixWarning(UserWarning):
    """prsc changed something in a user's asset file so that simulators load it (said once per file)."""


def principal_moments(link: ET.Element) -> tuple[float, list[float]] | None:
    """(mass, ascending principal moments) of a link's inertial, None when it has none or it is unreadable."""
    import numpy as np

    inertial = link.find("inertial")
    if inertial is None:
        return None
    mass, inertia = inertial.find("mass"), inertial.find("inertia")
    try:
        m = float(mass.get("value", "0")) if mass is not None else 0.0
        i = {k: float(inertia.get(k, "0")) for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")} if inertia is not None else {}
    except ValueError:
        return 0.0, [0.0, 0.0, 0.0]
    if not i:
        return m, [0.0, 0.0, 0.0]
    tensor = np.array([[i["ixx"], i["ixy"], i["ixz"]], [i["ixy"], i["iyy"], i["iyz"]], [i["ixz"], i["iyz"], i["izz"]]])
    return m, [float(v) for v in np.linalg.eigvalsh(tensor)]


def unbalanced(link: ET.Element) -> bool:
    """Whether a link's principal moments break the triangle inequality (A + B < C), as the xArm's link2."""
    found = principal_moments(link)
    return found is not None and found[1][0] > 0 and found[1][0] + found[1][1] < found[1][2] * (1 - 1e-9)


def _say_once(path: Path, message: str) -> None:
    """One AssetFixWarning per file and message; none for a library arm's file, not the user's to fix."""
    import warnings

    from prsc.user_assets.asset_fitting import library_files

    if (str(path), message) not in _warned_files and Path(path).resolve() not in library_files():
        _warned_files.add((str(path), message))
        warnings.warn(AssetFixWarning(f"{path.name}: {message}"), stacklevel=3)


def drop_invalid_inertias(root: ET.Element, path: Path) -> None:
    """Remove `<inertial>`s whose mass or inertia no simulator accepts (the random_urdfs'
    izz = 0); those links get mass and inertia from their geometry (MuJoCo's
    inertiafromgeom, density 1000 kg/m^3), and the user is told once."""
    names = [link.get("name", "?") for link in root.findall("link") if unbalanced(link)]
    if names:
        _say_once(path, f"links {', '.join(names)} have inertias that break the triangle inequality; "
                        "balanced as MuJoCo's balanceinertia does, in every format")
    dropped = []
    for link in root.findall("link"):
        found = principal_moments(link)
        if found is not None and (found[0] <= 0 or found[1][0] <= 0):
            link.remove(link.find("inertial"))
            dropped.append(link.get("name", "?"))
    if dropped:
        _say_once(path, f"links {', '.join(dropped)} have a mass or inertia no simulator accepts; "
                        "prsc computes theirs from their geometry (1000 kg/m^3)")


_warned_files: set[tuple[str, str]] = set()
