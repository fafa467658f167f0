"""Controllers named on the command line: `package.module:name` or `path/to/file.py:name`.

A controller is a callable `name(scene, model, data) -> dict`, called once per episode with
the scene JSON and a fresh MjModel/MjData of the compiled MJCF; it steps the simulation
itself and returns at least `"outcome"` and `"reason"`. Optional attributes of the callable:
`outcomes` (the labels it may return, so a summary lists zero counts), `check(scene)`
(raise PrscError when a scene does not fit the controller; run before anything is
compiled) and `report(records, scenes, folder, title)` (extra plots of a campaign).
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.util
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from prsc.errors import PrscError

DEFAULT_CONTROLLER = "prsc.runner.handover:handover"

_loaded: dict[ControllerRef, Any] = {}


@dataclass(frozen=True)
class ControllerRef:
    """A controller target, picklable: a file's source text travels with it to remote workers."""

    target: str
    name: str
    module: str | None = None  # package.module
    path: str | None = None  # path/to/file.py, as given
    source: str | None = None  # that file's text

    @property
    def digest(self) -> str:
        """What identifies the controller's code: the hash of its file's text (a module's source file)."""
        source = self.source
        if source is None:
            found = importlib.util.find_spec(str(self.module)) if self.module else None
            origin = found.origin if found is not None else None
            try:
                source = Path(origin).read_text(encoding="utf-8") if origin else str(self.module)
            except (OSError, UnicodeDecodeError):
                source = str(self.module)
        return hashlib.sha256(source.encode("utf-8")).hexdigest()


def parse_target(target: str) -> ControllerRef:
    """Split TARGET into module or file and attribute; a file is read now (PrscError if it cannot be)."""
    where, sep, name = target.rpartition(":")
    if not sep or not where or not name.isidentifier():
        raise PrscError(f"--controller {target!r}: expected package.module:name or path/to/file.py:name")
    if where.endswith(".py"):
        path = Path(where)
        try:
            source = path.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as error:
            raise PrscError(f"--controller: cannot read {where}: {getattr(error, 'strerror', None) or error}") from None
        return ControllerRef(target, name, path=where, source=source)
    if not all(part.isidentifier() for part in where.split(".")):
        raise PrscError(f"--controller {target!r}: {where!r} is neither a module name nor a .py file")
    return ControllerRef(target, name, module=where)


def _module(ref: ControllerRef):
    if ref.module is not None:
        try:
            return importlib.import_module(ref.module)
        except ImportError as error:
            raise PrscError(f"--controller {ref.target}: cannot import {ref.module}: {error}") from None
    # A file controller runs from its text, so a worker on another machine needs no copy of the file.
    name = f"prsc_controller_{ref.digest[:16]}"
    module = importlib.util.module_from_spec(importlib.util.spec_from_loader(name, loader=None, origin=ref.path))
    module.__file__ = str(ref.path)
    sys.modules[name] = module  # dataclasses and pickling look classes up here
    try:
        exec(compile(ref.source, str(ref.path), "exec"), module.__dict__)
    except SyntaxError as error:
        del sys.modules[name]
        raise PrscError(f"--controller: {ref.path}:{error.lineno}:{error.offset}: syntax error: {error.msg}") from None
    except Exception as error:
        del sys.modules[name]
        raise PrscError(f"--controller: importing {ref.path} failed: {type(error).__name__}: {error}") from None
    return module


def load_controller(ref: ControllerRef):
    """The controller callable (imported once per process)."""
    if ref not in _loaded:
        controller = getattr(_module(ref), ref.name, None)
        if controller is None:
            raise PrscError(f"--controller {ref.target}: {ref.path or ref.module} has no {ref.name!r}")
        if not callable(controller):
            raise PrscError(f"--controller {ref.target}: {ref.name!r} is not callable")
        _loaded[ref] = controller
    return _loaded[ref]


def declared_outcomes(controller: Any) -> tuple[str, ...]:
    """The outcome labels a controller declares (`outcomes = (...)`), or none."""
    outcomes = getattr(controller, "outcomes", ())
    if isinstance(outcomes, str) or not all(isinstance(o, str) for o in outcomes):
        raise PrscError(f"the controller's `outcomes` must be a tuple of strings, got {outcomes!r}")
    return tuple(outcomes)
