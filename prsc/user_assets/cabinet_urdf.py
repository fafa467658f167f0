"""The model library's procedural cabinet (docs/assets.md, "A cabinet from the library"): a
URDF written from its width, length, height and drawer count, so a spec without files of
its own can put things in drawers.

Its object's axes: the back at -y, the drawers open along +y (ahead). The file is written
in the ROS convention, front at +x, as every file is read (its +x turned to its object's
+y, docs/assets.md, "Forward"): the boxes below are laid out in the object's axes and
written in the file's (`_file_axes`). Links `carcass` and `drawer0`
(lowest) to `drawer{n-1}`; joints `drawer0_slide`, ... (prismatic along the file's +x, 0
to 0.8 of the depth). Each drawer is a floor walled on four sides (its front panel is the fourth),
so `in cab.links["drawer1"]` places on that floor. The file is written once per set of
numbers into the build folder and then read as any user URDF is.

Foundation module: the IR writes the file when it meets `model "cabinet"`.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from pathlib import Path

from prsc.user_assets.asset_files import build_root
from prsc.errors import PrscError
from prsc.files import atomic_write

LIBRARY_NAME = "cabinet"
PANEL = 0.018  # m: carcass panels and drawer fronts
DRAWER_PANEL = 0.008  # m: drawer floors and walls
GAP = 0.004  # m: between a drawer and the carcass around it
WALL_FRACTION = 0.6  # a drawer's walls rise to this fraction of its bay
OPENING = 0.8  # a drawer slides out up to this fraction of the depth
DENSITY = 600.0  # kg/m^3: wood
MAX_DRAWERS = 8
COLOR = "0.62 0.45 0.3 1"
VERSION = "2"  # 2: written front at +x (ROS). Bump when the file written for the same numbers changes


@dataclass(frozen=True)
class _Box:
    name: str
    centre: tuple[float, float, float]
    size: tuple[float, float, float]


def _check(width: float, length: float, height: float, drawers: int) -> None:
    if not (isinstance(drawers, int) and 1 <= drawers <= MAX_DRAWERS):
        raise PrscError(f"a cabinet has 1 to {MAX_DRAWERS} drawers, not {drawers!r}")
    if min(width, length) < 0.1 or height < 0.06 * drawers + 2 * PANEL:
        raise PrscError(f"a cabinet of {width:g} x {length:g} x {height:g} m is too small for {drawers} drawers "
                        f"(at least 0.1 m wide and deep, {0.06 * drawers + 2 * PANEL:.3f} m tall)")


def _carcass(width: float, length: float, height: float, drawers: int, bay: float) -> list[_Box]:
    w, l, h, t = width, length, height, PANEL
    boxes = [_Box("bottom", (0, 0, t / 2), (w, l, t)), _Box("top", (0, 0, h - t / 2), (w, l, t)),
             _Box("left", (-w / 2 + t / 2, 0, h / 2), (t, l, h - 2 * t)),
             _Box("right", (w / 2 - t / 2, 0, h / 2), (t, l, h - 2 * t)),
             _Box("back", (0, -l / 2 + t / 2, h / 2), (w - 2 * t, t, h - 2 * t))]
    for k in range(1, drawers):  # dividers between the bays
        z = t + k * (bay + t) - t / 2
        boxes.append(_Box(f"divider{k}", (0, t / 2, z), (w - 2 * t, l - t, t)))
    return boxes


def _drawer(width: float, length: float, bay: float) -> list[_Box]:
    """A drawer in its own frame: origin at the middle of its floor's bottom, front at +y."""
    inner_w = width - 2 * PANEL - 2 * GAP
    depth = length - PANEL - GAP  # from the back panel to the carcass front
    wall = WALL_FRACTION * bay
    d, front = DRAWER_PANEL, PANEL
    body = depth - front  # floor and side walls, behind the front panel
    y0 = -depth / 2
    return [_Box("floor", (0, y0 + body / 2, d / 2), (inner_w, body, d)),
            _Box("left", (-inner_w / 2 + d / 2, y0 + body / 2, d + wall / 2), (d, body, wall)),
            _Box("right", (inner_w / 2 - d / 2, y0 + body / 2, d + wall / 2), (d, body, wall)),
            _Box("back", (0, y0 + d / 2, d + wall / 2), (inner_w - 2 * d, d, wall)),
            _Box("front", (0, depth / 2 - front / 2, (bay - GAP) / 2), (width - 2 * PANEL, front, bay - GAP))]


def _file_axes(box: _Box) -> _Box:
    """A box laid out in the object's axes (ahead +y) in the file's (ahead +x): (x, y) -> (y, -x)."""
    (x, y, z), (sx, sy, sz) = box.centre, box.size
    return _Box(box.name, (y, -x if x else 0.0, z), (sy, sx, sz))


def _link(name: str, boxes: list[_Box]) -> str:
    """A URDF link of boxes (in the object's axes), each both seen and colliding, with the
    inertia of their union's box, written in the file's axes."""
    boxes = [_file_axes(box) for box in boxes]
    volume = sum(b.size[0] * b.size[1] * b.size[2] for b in boxes)
    mass = DENSITY * volume
    low = [min(b.centre[i] - b.size[i] / 2 for b in boxes) for i in range(3)]
    high = [max(b.centre[i] + b.size[i] / 2 for b in boxes) for i in range(3)]
    centre = [(a + b) / 2 for a, b in zip(low, high)]
    x, y, z = (b - a for a, b in zip(low, high))
    inertia = (mass * (y * y + z * z) / 12, mass * (x * x + z * z) / 12, mass * (x * x + y * y) / 12)
    parts = [f'  <link name="{name}">',
             f'    <inertial><origin xyz="{centre[0]!r} {centre[1]!r} {centre[2]!r}"/><mass value="{mass!r}"/>'
             f'<inertia ixx="{inertia[0]!r}" ixy="0" ixz="0" iyy="{inertia[1]!r}" iyz="0" izz="{inertia[2]!r}"/></inertial>']
    for box in boxes:
        origin = f'<origin xyz="{box.centre[0]!r} {box.centre[1]!r} {box.centre[2]!r}"/>'
        geometry = f'<geometry><box size="{box.size[0]!r} {box.size[1]!r} {box.size[2]!r}"/></geometry>'
        parts.append(f'    <visual name="{name}_{box.name}">{origin}{geometry}<material name="wood"/></visual>')
        parts.append(f'    <collision name="{name}_{box.name}_collision">{origin}{geometry}</collision>')
    parts.append("  </link>")
    return "\n".join(parts)


def cabinet_text(width: float, length: float, height: float, drawers: int) -> str:
    """The URDF of a cabinet of this box with `drawers` drawers stacked in equal bays."""
    _check(width, length, height, drawers)
    bay = (height - 2 * PANEL - (drawers - 1) * PANEL) / drawers
    lines = ['<?xml version="1.0"?>',
             f"<!-- prsc's procedural cabinet: {width!r} x {length!r} x {height!r} m, {drawers} drawers -->",
             '<robot name="cabinet">', f'  <material name="wood"><color rgba="{COLOR}"/></material>',
             _link("carcass", _carcass(width, length, height, drawers, bay))]
    depth = length - PANEL - GAP
    for k in range(drawers):
        lines.append(_link(f"drawer{k}", _drawer(width, length, bay)))
        y = -length / 2 + PANEL + GAP + depth / 2  # from the back panel (and a gap) to the carcass front
        z = PANEL + k * (bay + PANEL)
        lines.append(f'  <joint name="drawer{k}_slide" type="prismatic"><parent link="carcass"/>'
                     f'<child link="drawer{k}"/><origin xyz="{y!r} 0 {z!r}"/><axis xyz="1 0 0"/>'
                     f'<limit lower="0" upper="{OPENING * depth!r}" effort="100" velocity="1"/></joint>')
    lines.append("</robot>")
    return "\n".join(lines) + "\n"


def cabinet_urdf(width: float, length: float, height: float, drawers: int) -> Path:
    """The cabinet's URDF file in the build folder (written once per set of numbers)."""
    text = cabinet_text(width, length, height, drawers)
    digest = hashlib.sha256((VERSION + text).encode()).hexdigest()[:12]
    target = build_root() / "assets" / "cabinets" / f"cabinet-{digest}.urdf"
    try:
        usable = target.read_text(encoding="utf-8") == text
    except (OSError, UnicodeDecodeError):
        usable = False
    if not usable:  # missing, or not what these numbers write: written again, not trusted
        target.parent.mkdir(parents=True, exist_ok=True)
        atomic_write(target, text)
    return target
