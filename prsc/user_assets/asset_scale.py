"""`scale` on an asset from a file (docs/assets.md, "Size"; LANGUAGE §7): the whole tree made
`scale` times larger about its root, written once as a copy of the file in the build folder
(`$PRSC_BUILD_DIR/scaled/<stem>-<hash>-x<scale>/<stem>.<suffix>`, keyed by the content of
every file it reads, the scale and SCALE_VERSION, with copies of its meshes beside it:
prsc/user_assets/asset_cache.py). The IR names the copy as the object's model, so every later stage,
every backend and `reachable by` read one file, as they do for an unscaled asset.

What scales, by s: every position (joint, link, geom, site and inertial origins), every
geometry size and mesh scale, a prismatic joint's limits and a slide joint's range and its
keyframe values; masses by s^3 (a solid of the same density) and moments of inertia by s^5.
Revolute limits, actuator gains, tendons and equality constraints stay as the file has them.

Foundation module: imported by the IR, it imports mujoco only inside functions.
"""

from __future__ import annotations

import hashlib
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Sequence

from prsc.user_assets.asset_cache import bundle_mjcf, bundle_urdf, entry_usable, inputs_digest, write_entry
from prsc.user_assets.asset_files import build_root, file_spec, urdf_with_absolute_paths
from prsc.user_assets.urdf_source import parse_urdf

SCALE_VERSION = "2"  # 2: a folder per copy, its meshes copied in


def _times(text: str | None, factor: float) -> str:
    """A whitespace-separated list of numbers, each times `factor`."""
    return " ".join(repr(float(v) * factor) for v in (text or "").split())


def _massless_links(path: Path) -> set[str]:
    """The links a URDF declares with mass 0 (pybullet's fixed base: its table and tray)."""
    names = set()
    for link in parse_urdf(path).iter("link"):
        mass = link.find("inertial/mass")
        try:
            if mass is not None and float(mass.get("value", "nan")) == 0.0:
                names.add(link.get("name", ""))
        except ValueError:
            continue
    return names


def _scaled_urdf(text: str, s: float, massless: set[str]) -> ET.Element:
    """A URDF (its text) with every length times s, masses times s^3 and inertias times s^5; the
    `massless` links keep the mass 0 they declare (the copy says what the file says)."""
    root = ET.fromstring(text)
    for origin in root.iter("origin"):
        if origin.get("xyz") is not None:
            origin.set("xyz", _times(origin.get("xyz"), s))
    for mesh in root.iter("mesh"):
        mesh.set("scale", _times(mesh.get("scale", "1 1 1"), s))
    for shape, keys in (("box", ("size",)), ("cylinder", ("radius", "length")), ("sphere", ("radius",)),
                        ("capsule", ("radius", "length"))):
        for element in root.iter(shape):
            for key in keys:
                if element.get(key) is not None:
                    element.set(key, _times(element.get(key), s))
    for inertial in root.iter("inertial"):
        for mass in inertial.iter("mass"):
            mass.set("value", _times(mass.get("value"), s**3))
        for inertia in inertial.iter("inertia"):
            for key, value in list(inertia.attrib.items()):
                inertia.set(key, _times(value, s**5))
    for link in root.iter("link"):
        if link.get("name") in massless:
            link.find("inertial/mass").set("value", "0")
    for joint in root.iter("joint"):
        if joint.get("type") == "prismatic":
            for limit in joint.iter("limit"):
                for key in ("lower", "upper"):
                    if limit.get(key) is not None:
                        limit.set(key, _times(limit.get(key), s))
    return root


def _scaled_mjcf(path: Path, s: float, folders: Sequence[str]) -> ET.Element:
    """An MJCF (asset paths absolute) with every length times s, masses s^3, inertias s^5."""
    import mujoco
    import numpy as np

    spec = file_spec(path, folders)  # the copy keeps the file's own axes; reading it turns it
    slides = {j.name for j in spec.joints if j.type == mujoco.mjtJoint.mjJNT_SLIDE}
    model = spec.compile()  # the keyframes' qpos addresses, before anything moves
    lengths = np.ones(model.nq)
    for j in range(model.njnt):
        adr = model.jnt_qposadr[j]
        if model.joint(j).name in slides:
            lengths[adr] = s
        elif model.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE:
            lengths[adr:adr + 3] = s
    for body in spec.bodies[1:]:
        body.pos = np.asarray(body.pos) * s
        body.ipos = np.asarray(body.ipos) * s
        body.mass = body.mass * s**3
        body.inertia = np.asarray(body.inertia) * s**5
        body.fullinertia = np.asarray(body.fullinertia) * s**5
    for geom in spec.geoms:
        geom.pos = np.asarray(geom.pos) * s
        if geom.type != mujoco.mjtGeom.mjGEOM_MESH:
            geom.size = np.asarray(geom.size) * s
        geom.fromto = np.asarray(geom.fromto) * s
        geom.mass = geom.mass * s**3  # density and mass < 0 mean unset; density stays
    for mesh in spec.meshes:
        mesh.scale = np.asarray(mesh.scale) * s
    for site in spec.sites:
        site.pos, site.size, site.fromto = (np.asarray(v) * s for v in (site.pos, site.size, site.fromto))
    for joint in spec.joints:
        joint.pos = np.asarray(joint.pos) * s
        if joint.name in slides:
            joint.range = np.asarray(joint.range) * s
    for item in (*spec.frames, *spec.cameras, *spec.lights):
        item.pos = np.asarray(item.pos) * s
    for key in spec.keys:
        if len(key.qpos):
            key.qpos = np.asarray(key.qpos) * lengths
    spec.compile()
    # to_xml writes <size nkey> from the keyframes; attaching the copy into a scene (which has
    # no keys yet) then reports a conflict. The keyframes say it themselves: drop it.
    root = ET.fromstring(spec.to_xml())
    for size in root.findall("size"):
        size.attrib.pop("nkey", None)
        if not size.attrib and not len(size):
            root.remove(size)
    return root


def scaled_asset_file(path: Path, scale: float, folders: Sequence[str] = ()) -> Path:
    """The asset file `path` made `scale` times larger (a copy in the build folder, written once); `path` at scale 1."""
    if scale == 1.0:
        return path
    digest = hashlib.sha256(f"{inputs_digest(path, folders)} {SCALE_VERSION} {scale!r}".encode())
    target = build_root() / "scaled" / f"{path.stem}-{digest.hexdigest()[:10]}-x{scale:g}" / path.name
    if not entry_usable(target):
        if path.suffix.lower() == ".urdf":
            root = _scaled_urdf(urdf_with_absolute_paths(path, folders), scale, _massless_links(path))
            write_entry(target, bundle_urdf(root, target.parent))
        else:
            write_entry(target, bundle_mjcf(_scaled_mjcf(path, scale, folders), target.parent), header="")
    return target
