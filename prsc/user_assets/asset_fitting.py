"""The model library's arms (docs/assets.md, "The library's arm"): a URDF or MJCF file, found
in an installed Python package, plus what the library adds to it, stated as data in
`prsc/library/<name>.json`: tool sites, position servos, finger pads, a home pose, and which
links are its fingers.

A `model` that names such a data file (`model: "NAME"` where prsc/library/NAME.json is one)
is read by the same path as a user's file (asset_files.asset_spec, describe_asset): the
file's own model, then the fitting added, then the turn that makes the file's +x its
object's ahead. Nothing about a particular arm lives in code.
"""

from __future__ import annotations

import hashlib
import importlib.util
import json
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

from prsc.errors import PrscError

LIBRARY = Path(__file__).resolve().parents[1] / "library"
"""The model library's folder: its .prs files and its arms' data files."""
HOME_KEY = "home"
"""The keyframe a fitting's home pose becomes (describe_asset reads a file's `home`)."""


@dataclass(frozen=True)
class FittedSite:
    """A site the library adds to a body of the file (a tool frame)."""

    name: str
    body: str
    pos: tuple[float, float, float]


@dataclass(frozen=True)
class FittedServo:
    """A position servo the library adds on one joint (ctrl: the joint's target, within `ctrl`)."""

    name: str
    joint: str
    kp: float
    kv: float
    force: float  # N or N m, either way
    ctrl: tuple[float, float]


@dataclass(frozen=True)
class FittedGrip:
    """Contact parameters the library gives a body's colliding geoms (a finger pad's)."""

    body: str
    friction: tuple[float, float, float]
    condim: int
    priority: int


@dataclass(frozen=True)
class Fitting:
    """What the library adds to a file's model, applied before the turn (in the file's axes)."""

    sites: tuple[FittedSite, ...] = ()
    servos: tuple[FittedServo, ...] = ()
    grips: tuple[FittedGrip, ...] = ()
    home: tuple[tuple[str, float], ...] = ()  # joint -> value; joints not named start at 0 within their limits
    fingers: tuple[str, ...] = ()  # the finger links (`holds`): the object's `fingers` property

    @property
    def digest(self) -> str:
        """A hash of the fitting: part of the key of everything built from the fitted file."""
        return hashlib.sha256(repr(self).encode()).hexdigest()

    def apply(self, spec) -> None:
        """Add the sites, servos, grips and home pose to a file's MjSpec, in place."""
        import mujoco

        for site in self.sites:
            _body(spec, site.body).add_site(name=site.name, pos=list(site.pos), size=[0.005, 0, 0], group=4)
        for grip in self.grips:
            for geom in _body(spec, grip.body).geoms:
                if geom.contype or geom.conaffinity:
                    geom.friction, geom.condim, geom.priority = list(grip.friction), grip.condim, grip.priority
        for servo in self.servos:
            if spec.joint(servo.joint) is None:
                raise PrscError(f"the library's servo {servo.name!r} names no joint {servo.joint!r} of the file")
            actuator = spec.add_actuator(name=servo.name, target=servo.joint, trntype=mujoco.mjtTrn.mjTRN_JOINT)
            actuator.set_to_position(kp=servo.kp, kv=servo.kv)
            actuator.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
            actuator.forcerange = [-servo.force, servo.force]
            actuator.ctrllimited = mujoco.mjtLimited.mjLIMITED_TRUE
            actuator.ctrlrange = list(servo.ctrl)
        if self.home:
            model = spec.compile()
            qpos = model.qpos0.copy()
            for j in range(model.njnt):  # unnamed joints: 0 clipped into their limits, as a file without a home
                low, high = model.jnt_range[j] if model.jnt_limited[j] else (-float("inf"), float("inf"))
                qpos[model.jnt_qposadr[j]] = min(max(0.0, low), high)
            for name, value in self.home:
                qpos[model.jnt_qposadr[model.joint(name).id]] = value
            spec.add_key(name=HOME_KEY, qpos=list(qpos))


def _body(spec, name: str):
    body = spec.body(name)
    if body is None:
        raise PrscError(f"the library's fitting names no body {name!r} of the file")
    return body


@dataclass(frozen=True)
class LibraryArm:
    """A model library arm: the file it is read from and what the library adds to it."""

    name: str
    file: Path
    fitting: Fitting


def library_arm(model: object) -> LibraryArm | None:
    """The library arm a `model` value names (prsc/library/<model>.json), or None."""
    if not isinstance(model, str) or not model.isidentifier():
        return None
    path = LIBRARY / f"{model.lower()}.json"
    return _read(str(path)) if path.is_file() else None


def library_arm_names() -> frozenset[str]:
    """The names of the library's arms (a class of that name uses it without saying so)."""
    return frozenset(path.stem for path in LIBRARY.glob("*.json"))


def library_files() -> frozenset[Path]:
    """The files the library's arms are read from (resolved)."""
    return frozenset(_read(str(path)).file.resolve() for path in LIBRARY.glob("*.json"))


@lru_cache(maxsize=8)
def _read(path: str) -> LibraryArm:
    data = json.loads(Path(path).read_text(encoding="utf-8"))
    package, relative = data["file"]["package"], data["file"]["path"]
    found = importlib.util.find_spec(package)
    if found is None or not found.submodule_search_locations:
        raise PrscError(f"the library's {Path(path).stem} is read from the package {package}, which is not installed")
    fitting = Fitting(
        sites=tuple(FittedSite(s["name"], s["body"], tuple(s["pos"])) for s in data.get("sites", ())),
        servos=tuple(FittedServo(s["name"], s["joint"], s["kp"], s["kv"], s["force"], tuple(s["ctrl"]))
                     for s in data.get("servos", ())),
        grips=tuple(FittedGrip(g["body"], tuple(g["friction"]), g["condim"], g["priority"]) for g in data.get("grips", ())),
        home=tuple((name, float(value)) for name, value in data.get("home", {}).items()),
        fingers=tuple(data.get("fingers", ())),
    )
    return LibraryArm(Path(path).stem, Path(found.submodule_search_locations[0]) / relative, fitting)  # type: ignore[arg-type]
