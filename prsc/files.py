"""Atomic file output, the one implementation every stage uses: a reader never sees a
half-written file or bundle folder, and a killed writer's temporaries can be told apart
from a live writer's and removed.

A temporary is named `.<final name>.prsc-<8 random characters>.tmp` (a folder's previous
version, while it is being replaced, `.<name>.prsc-<random>.old`) and holds an exclusive
`flock` while it is written: the lock dies with its process, so a temporary that can be
locked belongs to a writer that no longer runs.
"""

from __future__ import annotations

import contextlib
import fcntl
import os
import re
import shutil
import tempfile
import time
from pathlib import Path
from typing import IO, Iterator, Mapping

# mkstemp / mkdtemp names: `.<name>.prsc-`, 8 characters from [a-z0-9_], suffix (and a file
# type for atomic_path).
_TEMPORARY = re.compile(r"^\.(?P<name>.+)\.prsc-[a-z0-9_]{8}\.(tmp|old)(\.[A-Za-z0-9]+)?$")
# A temporary younger than this is left alone: its writer may not hold its lock yet.
STALE_SECONDS = 1.0


def write_bytes(handle: int, data: bytes) -> None:
    """Write all of `data` to an open file descriptor (the one place bytes hit the disk)."""
    view = memoryview(data)
    while view:
        written = os.write(handle, view)
        view = view[written:]


def _lock(handle: int) -> None:
    fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)


@contextlib.contextmanager
def building(path: Path) -> Iterator[None]:
    """Hold `<path>.lock` exclusively while the block builds what `path` will hold: another process
    building the same file waits, then finds it built (the lock dies with its process)."""
    handle = os.open(f"{path}.lock", os.O_RDWR | os.O_CREAT, 0o644)
    try:
        fcntl.flock(handle, fcntl.LOCK_EX)
        yield
    finally:
        os.close(handle)


def atomic_write(path: Path | str, data: bytes | str) -> None:
    """Write a file through a locked temporary sibling and a rename; on error nothing is left behind."""
    if isinstance(data, str):
        data = data.encode("utf-8")
    path = Path(path)
    handle, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.prsc-", suffix=".tmp")
    try:
        try:
            _lock(handle)
            write_bytes(handle, data)
            os.fchmod(handle, 0o644)  # mkstemp makes it private; outputs are for others to read
            os.replace(tmp, path)
        finally:
            os.close(handle)
    except BaseException:
        _remove_quietly(tmp)
        raise


@contextlib.contextmanager
def atomic_path(path: Path | str, folder: Path | str | None = None) -> Iterator[Path]:
    """A temporary path (with `path`'s file type) that a library writes and that then replaces `path`;
    made in `folder` (on the same file system) instead of beside `path` when given."""
    path = Path(path)
    where = path.absolute().parent if folder is None else Path(folder)
    handle, tmp = tempfile.mkstemp(dir=where, prefix=f".{path.name}.prsc-", suffix=f".tmp{path.suffix}")
    try:
        _lock(handle)
        yield Path(tmp)
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        _remove_quietly(tmp)
        raise
    finally:
        os.close(handle)


@contextlib.contextmanager
def atomic_text(path: Path | str) -> Iterator[IO[str]]:
    """A text handle whose content replaces `path` only when the block completes."""
    with atomic_path(path) as tmp, open(tmp, "w", encoding="utf-8") as out:
        yield out


def atomic_write_tree(folder: Path | str, files: Mapping[str, bytes | str]) -> None:
    """Write a bundle folder (relative name -> content) into a temporary folder, then rename it.

    The temporary must hold exactly `files` before the rename, so a bundle is in place
    whole or not at all. An existing folder of the same name is replaced as a whole.
    """
    folder = Path(folder)
    tmp = Path(tempfile.mkdtemp(dir=folder.parent, prefix=f".{folder.name}.prsc-", suffix=".tmp"))
    lock = os.open(tmp, os.O_RDONLY | os.O_DIRECTORY)
    try:
        _lock(lock)
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
        written = {p.relative_to(tmp).as_posix() for p in tmp.rglob("*") if p.is_file()}
        if written != {Path(name).as_posix() for name in files}:
            raise OSError(f"bundle {folder.name}: its temporary folder changed while it was written")
        os.chmod(tmp, 0o755)
        if folder.exists():
            # A stale bundle from an earlier run with other inputs: swap it out, then drop it.
            old = Path(tempfile.mkdtemp(dir=folder.parent, prefix=f".{folder.name}.prsc-", suffix=".old"))
            os.replace(folder, old / "bundle")
            os.replace(tmp, folder)
            shutil.rmtree(old, ignore_errors=True)
        else:
            os.replace(tmp, folder)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    finally:
        os.close(lock)


def atomic_copy(source: Path | str, target: Path | str) -> None:
    """Copy a file atomically (skipped when the target already exists with the same size); a
    source that cannot be read is `cannot read SOURCE` (a PrscError)."""
    source, target = Path(source), Path(target)
    try:
        size = source.stat().st_size
        data = None if target.is_file() and target.stat().st_size == size else source.read_bytes()
    except OSError as error:  # the source is an input: named as one, never as the output
        from prsc.errors import read_error

        raise read_error(error, source) from None
    if data is None:
        return
    target.parent.mkdir(parents=True, exist_ok=True)
    atomic_write(target, data)


def is_temporary_name(name: str, of: str | None = None) -> bool:
    """Whether `name` is one of this module's temporary names (of the output named `of`)."""
    found = _TEMPORARY.match(name)
    return bool(found) and (of is None or found.group("name") == of)


def remove_stale_temporaries(folder: Path | str, recursive: bool = False, of: str | None = None,
                             min_age: float = STALE_SECONDS) -> int:
    """Remove the temporaries of writers that no longer run in `folder`; returns how many.

    Only names of this module's pattern (for the output named `of`, when given) whose
    lock can be taken (no live writer holds it) and that are older than `min_age` seconds
    are removed: nothing else is touched. A caller that has seen every writer end may
    pass min_age 0."""
    removed = 0
    now = time.time()
    walk = os.walk(folder) if recursive else [next(os.walk(folder), (str(folder), [], []))]
    for parent, dirs, names in walk:
        for name in [*dirs, *names]:
            if not is_temporary_name(name, of):
                continue
            path = Path(parent) / name
            if name in dirs:
                dirs.remove(name)  # never walk into a temporary
            try:
                if now - path.lstat().st_mtime < min_age or path.is_symlink():
                    continue
                handle = os.open(path, os.O_RDONLY | (os.O_DIRECTORY if path.is_dir() else 0))
            except OSError:
                continue
            try:
                _lock(handle)
            except OSError:
                os.close(handle)
                continue  # a live writer holds it
            try:
                if path.is_dir():
                    shutil.rmtree(path, ignore_errors=True)
                else:
                    path.unlink()
                removed += 1
            except OSError:
                pass
            finally:
                os.close(handle)
    return removed


def _remove_quietly(path: str | Path) -> None:
    try:
        os.unlink(path)
    except OSError:
        pass
