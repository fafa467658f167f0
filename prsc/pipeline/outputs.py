"""Paths commands write to: checked before any work is done, and OSError as a user-facing error."""

from __future__ import annotations

import errno
import os
from pathlib import Path

from prsc.errors import PrscError


def write_error(error: OSError, path: Path | str | None = None) -> PrscError:
    """`cannot write PATH: reason` for an OSError met while writing output (or writing the build
    folder's caches on the way: then that folder is named)."""
    from prsc.user_assets.asset_files import build_folder_error

    in_build = build_folder_error(error)
    if in_build is not None:
        return in_build
    where = path or error.filename or "output"
    reason = os.strerror(error.errno) if error.errno else str(error)
    if error.errno == errno.ENOSPC:
        reason = "no space left on device"
    return PrscError(f"cannot write {where}: {reason}")


def output_file(path: str) -> Path:
    """The file a command will write at `path`, or a PrscError saying why it cannot be there.

    Checked up front so that a typo in -o fails at once, not after minutes of sampling.
    """
    if not path:
        raise PrscError("the output path is empty")
    target = Path(path)
    if target.is_dir():
        raise PrscError(f"cannot write {path}: it is a folder")
    parent = target.absolute().parent
    if parent.exists() and not parent.is_dir():
        raise PrscError(f"cannot write {path}: {target.parent} is not a folder")
    if not parent.exists():
        raise PrscError(f"cannot write {path}: folder {target.parent} does not exist")
    return target
