"""Atomic file output: a reader never sees a half-written file or bundle folder."""

from __future__ import annotations

import os
import shutil
import tempfile
from pathlib import Path
from typing import Mapping


def write_bytes(handle: int, data: bytes) -> None:
    """Write all of `data` to an open file descriptor (the one place bytes hit the disk)."""
    view = memoryview(data)
    while view:
        written = os.write(handle, view)
        view = view[written:]


def atomic_write(path: Path, data: bytes | str) -> None:
    """Write a file through a temporary sibling and a rename; on error nothing is left behind."""
    if isinstance(data, str):
        data = data.encode("utf-8")
    path = Path(path)
    handle, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        try:
            write_bytes(handle, data)
        finally:
            os.close(handle)
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        _remove_quietly(tmp)
        raise


def atomic_write_tree(folder: Path, files: Mapping[str, bytes | str]) -> None:
    """Write a bundle folder (relative name -> content) into a temporary folder, then rename it.

    An existing folder of the same name is replaced as a whole.
    """
    folder = Path(folder)
    tmp = Path(tempfile.mkdtemp(dir=folder.parent, prefix=f".{folder.name}.", suffix=".tmp"))
    try:
        for name, data in files.items():
            target = tmp / name
            target.parent.mkdir(parents=True, exist_ok=True)
            if isinstance(data, str):
                data = data.encode("utf-8")
            handle = os.open(target, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
            try:
                write_bytes(handle, data)
            finally:
                os.close(handle)
        os.chmod(tmp, 0o755)
        if folder.exists():
            # A stale bundle from an earlier run with other inputs: swap it out, then drop it.
            old = Path(tempfile.mkdtemp(dir=folder.parent, prefix=f".{folder.name}.", suffix=".old"))
            os.replace(folder, old / "bundle")
            os.replace(tmp, folder)
            shutil.rmtree(old, ignore_errors=True)
        else:
            os.replace(tmp, folder)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def atomic_copy(source: Path, target: Path) -> None:
    """Copy a file atomically (skipped when the target already exists with the same size)."""
    source, target = Path(source), Path(target)
    if target.is_file() and target.stat().st_size == source.stat().st_size:
        return
    target.parent.mkdir(parents=True, exist_ok=True)
    atomic_write(target, source.read_bytes())


def _remove_quietly(path: str | Path) -> None:
    try:
        os.unlink(path)
    except OSError:
        pass
