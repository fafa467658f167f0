"""The output folder of `prsc compile`: its lock, its manifest and the journal of finished files.

One run at a time writes a folder (an exclusive lock; a second run is refused). Each file
is recorded in `manifest.jsonl` the moment it is in place, and `manifest.json` (the whole
list) is rewritten every few seconds and at the end, when it absorbs `manifest.jsonl`:
after a kill the two together list every finished file. prsc deletes only files its
manifest lists.
"""

from __future__ import annotations

import errno
import fcntl
import json
import os
import shutil
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Iterable

from prsc.pipeline.outputs import write_error
from prsc.errors import PrscError
from prsc.task.terms import TASK_SUFFIX

MANIFEST = "manifest.json"
DEFAULT_WIDTH = 5  # digits of a scene file name (more when -n needs them)


JOURNAL = "manifest.jsonl"  # one line per file put in place since manifest.json was written


LOCK = ".prsc-lock"


MANIFEST_FORMAT = "prsc-manifest"


CHECKPOINT_SECONDS = 2.0  # manifest.json is rewritten at most this often during a run


def record_files(root: Path, index: int, files: dict[str, str]) -> None:
    """Append a scene's finished files (a target's file and its task file) to the journal: a single
    O_APPEND write, so lines never interleave and the two are listed together or not at all."""
    line = json.dumps({"index": index, "files": files}, separators=(",", ":")) + "\n"
    data = line.encode()
    handle = os.open(root / JOURNAL, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
    try:
        if os.write(handle, data) != len(data):  # a full disk (or file-size limit) cut the line
            try:
                os.write(handle, b"\n")  # end the cut line, so the next one starts clean; readers skip it
            except OSError:
                pass
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(root / JOURNAL))
    finally:
        os.close(handle)


def task_key(target: str) -> str:
    """The manifest key of a file target's task file ("mjcf.task")."""
    return f"{target}.task"


def output_root(output: Path, path: Path) -> Path:
    """`output/<stem>`: the stem must name a folder inside `output`, never `output` itself or its parent."""
    stem = path.stem
    if stem in ("", ".", "..") or "/" in stem or "\\" in stem or not stem.isprintable():
        raise PrscError(f"cannot name an output folder after {path} (its name without the suffix is {stem!r}); "
                        "rename the file")
    return output / stem


def prepare_root(root: Path, targets: Iterable[str], assets: str | None = None) -> list[Path]:
    """Create `root/<target>/` and the assets folder (default `root/assets`) with clear errors for a
    broken or unwritable path; returns the folders this call created, outermost first (a failed
    run removes them again)."""
    created: list[Path] = []
    try:
        for folder in [root, Path(assets) if assets else root / "assets"] + [root / t for t in targets]:
            if folder.exists() and not folder.is_dir():
                raise PrscError(f"output path {folder} exists and is not a folder")
            missing = [p for p in (*reversed(folder.absolute().parents), folder.absolute()) if not p.exists()]
            folder.mkdir(parents=True, exist_ok=True)
            created.extend(missing)
        if not os.access(root, os.W_OK):
            raise PrscError(f"cannot write to output folder {root}: permission denied")
    except OSError as error:
        raise PrscError(f"cannot create output folder {error.filename or root}: {os.strerror(error.errno) if error.errno else error}") from None
    return created


LOCK_MARK = b"prsc output-folder lock\n"  # what prsc writes in a lock file it creates: its proof of authorship


@dataclass(frozen=True)
class FolderLock:
    """An exclusive lock on an output folder; `release` removes the lock file when prsc wrote it."""

    handle: int
    path: Path
    ours: bool

    def release(self) -> None:
        """Unlink the lock file (only prsc's own) while still holding it, then close it."""
        try:
            if self.ours:
                self.path.unlink(missing_ok=True)
        except OSError:
            pass  # a folder that refuses the unlink keeps an empty lock file: harmless, and the run's own error matters
        finally:
            os.close(self.handle)


def lock_folder(root: Path) -> FolderLock:
    """An exclusive lock on the output folder for this run (released when the process and its workers end).

    A run that holds the lock removes its file when it ends, so a second run may have opened
    the old file just before: after locking, the lock must still be the file at the path."""
    path = root / LOCK
    while True:
        try:
            try:
                handle, created = os.open(path, os.O_RDWR | os.O_CREAT | os.O_EXCL, 0o644), True
            except FileExistsError:
                handle, created = os.open(path, os.O_RDWR), False
        except FileNotFoundError:
            continue  # removed between the two opens by the run that held it: try again
        except OSError as error:
            raise write_error(error, path) from None
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            os.close(handle)
            raise PrscError(f"output folder {root} is being written by another prsc run; "
                            "wait for it to finish or choose another output folder") from None
        try:
            current = os.stat(path).st_ino
        except FileNotFoundError:
            current = None
        if current != os.fstat(handle).st_ino:
            os.close(handle)  # the run before us removed this file after we opened it
            continue
        # Ours: created just now, or left by a prsc run that was killed (it holds the mark).
        # An empty lock file of an older prsc cannot be told from a user's file: it stays.
        ours = created or os.read(handle, len(LOCK_MARK) + 1) == LOCK_MARK
        if created:
            os.write(handle, LOCK_MARK)
        return FolderLock(handle, path, ours)


def _entry_files(root: Path, entry: Any, where: str) -> tuple[int, dict[str, str]]:
    """(index, target -> relative path) of one manifest entry, each path exactly a name this
    prsc gives (`<target>/<zero-padded index><suffix>`): anything else is not prsc's."""
    from prsc.backends import TARGETS

    def bad(why: str) -> PrscError:
        return PrscError(f"{root / MANIFEST} is not a prsc manifest ({where}: {why}); prsc will not write into this "
                         "folder: remove the manifest or choose another output folder")

    if not isinstance(entry, dict):
        raise bad(f"expected an object, got {json.dumps(entry)[:60]}")
    index, files = entry.get("index"), entry.get("files")
    if isinstance(index, bool) or not isinstance(index, int) or index < 0:
        raise bad(f"index {index!r} is not a scene number")
    if not isinstance(files, dict):
        raise bad(f"scene {index}: files is not an object")
    for key, rel in files.items():
        target, _, part = str(key).partition(".")
        if target not in TARGETS or part not in ("", "task") or (part and TARGETS[target].task_inside) \
                or not isinstance(rel, str):
            raise bad(f"scene {index}: {key!r}: {rel!r} is not an output of prsc")
        suffix = TASK_SUFFIX if part else TARGETS[target].suffix
        folder, _, name = rel.partition("/")
        digits = name[: len(name) - len(suffix)] if suffix else name
        if folder != target or not name.endswith(suffix) or not digits.isdigit() or not digits.isascii() \
                or int(digits) != index or len(digits) < DEFAULT_WIDTH:
            raise bad(f"scene {index}: {key!r}: {rel!r} is not an output of prsc")
    return index, dict(files)


def load_manifest(root: Path) -> tuple[dict | None, dict[int, dict[str, str]]]:
    """The folder's manifest header and its entries (manifest.json and then the journal), validated."""
    path = root / MANIFEST
    if not path.exists():
        return None, {}
    try:
        manifest = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError, UnicodeDecodeError, RecursionError) as error:
        raise PrscError(f"{path} is unreadable ({str(error)[:200]}); remove it or choose another output folder") from None
    if not isinstance(manifest, dict) or manifest.get("format", MANIFEST_FORMAT) != MANIFEST_FORMAT \
            or not isinstance(manifest.get("scenes"), list):
        raise PrscError(f"{path} is not a prsc manifest; remove it or choose another output folder")
    entries: dict[int, dict[str, str]] = {}
    for k, entry in enumerate(manifest["scenes"]):
        index, files = _entry_files(root, entry, f"scenes[{k}]")
        entries.setdefault(index, {}).update(files)
    _absorb_journal(root, entries)
    return manifest, entries


def _absorb_journal(root: Path, entries: dict[int, dict[str, str]]) -> None:
    """Add the files the journal records to `entries` (validated as manifest entries)."""
    try:
        journal = (root / JOURNAL).read_bytes()
    except FileNotFoundError:
        return
    except OSError as error:
        raise PrscError(f"cannot read {root / JOURNAL}: {os.strerror(error.errno) if error.errno else error}") from None
    lines = journal.split(b"\n")
    for number, line in enumerate(lines[:-1], start=1):  # a last line without "\n" was cut by a kill
        try:
            entry = json.loads(line)
        except ValueError:
            continue  # cut by a full disk (its file was removed): listing less never deletes more
        index, files = _entry_files(root, entry, f"{JOURNAL} line {number}")
        entries.setdefault(index, {}).update(files)


def remove_listed(root: Path, entries: dict[int, dict[str, str]]) -> None:
    """Delete the files a validated manifest lists (outputs of other sources), and nothing else."""
    try:
        for files in entries.values():
            for rel in files.values():
                path = root / rel
                if path.parent.is_symlink():  # prsc made <target>/ a folder: this one leads elsewhere
                    raise PrscError(f"{path.parent} is a symbolic link, not the folder prsc made; "
                                    "remove it or choose another output folder")
                if path.is_dir() and not path.is_symlink():
                    shutil.rmtree(path)
                elif path.exists() or path.is_symlink():
                    path.unlink()
        (root / JOURNAL).unlink(missing_ok=True)
    except OSError as error:
        raise PrscError(f"cannot remove the earlier scenes in {root}: "
                        f"{error.filename}: {os.strerror(error.errno) if error.errno else error}") from None


def write_manifest(root: Path, manifest: dict) -> None:
    from prsc.files import atomic_write

    try:
        atomic_write(root / MANIFEST, json.dumps(manifest, indent=1) + "\n")
    except OSError as error:
        raise write_error(error, root / MANIFEST) from None


def close_manifest(root: Path, entries: dict[int, dict[str, str]], manifest_now: Callable[[], dict]) -> None:
    """Write manifest.json with every journalled file (the workers have stopped), then drop the journal."""
    _absorb_journal(root, entries)
    write_manifest(root, manifest_now())
    (root / JOURNAL).unlink(missing_ok=True)  # manifest.json now holds every line of it


def compiled_scenes(root: Path, indices: Iterable[int] | None = None) -> list[tuple[int, Path, Path]]:
    """(index, scene JSON, MJCF) of the scenes an output folder's manifest lists with both files."""
    _, entries = load_manifest(root)
    wanted = None if indices is None else set(indices)
    return sorted((index, root / files["json"], root / files["mjcf"]) for index, files in entries.items()
                  if "json" in files and "mjcf" in files and (wanted is None or index in wanted))


@dataclass
class Listed:
    """Whether the manifest lists a scene's file for a target (picklable, for the workers)."""

    entries: dict[int, dict[str, str]]

    def __call__(self, index: int, target: str) -> bool:
        return target in self.entries.get(index, {})


@dataclass(frozen=True)
class FolderBefore:
    """What a campaign's folder held before the campaign started: put back when it fails before
    its first episode (prsc run, prsc falsify), so such a failure leaves nothing of its own."""

    folder: Path
    existed: bool
    paths: frozenset[str]  # files and folders inside, relative
    manifests: tuple[tuple[str, bytes], ...]  # the manifests a compile rewrites, as they were


def folder_before(folder: Path) -> FolderBefore:
    """The folder's paths (and its manifests' bytes) now."""
    folder = Path(folder)
    if not folder.is_dir():
        return FolderBefore(folder, False, frozenset(), ())
    paths = frozenset(str(p.relative_to(folder)) for p in folder.rglob("*"))
    manifests = tuple((rel, (folder / rel).read_bytes()) for rel in sorted(paths)
                      if Path(rel).name == MANIFEST and (folder / rel).is_file())
    return FolderBefore(folder, True, paths, manifests)


def restore_folder(before: FolderBefore) -> None:
    """Remove every path the campaign added to its folder (the folder itself, if it made it) and
    put back the manifests it rewrote. Best effort: a path that cannot go stays."""
    from prsc.files import atomic_write

    folder = before.folder
    if not before.existed:
        shutil.rmtree(folder, ignore_errors=True)
        return
    added = sorted((p for p in folder.rglob("*") if str(p.relative_to(folder)) not in before.paths),
                   key=lambda p: len(p.parts))
    for path in added:
        if path.is_dir() and not path.is_symlink():
            shutil.rmtree(path, ignore_errors=True)
        else:
            try:
                path.unlink(missing_ok=True)
            except OSError:
                pass
    for rel, data in before.manifests:
        try:
            atomic_write(folder / rel, data)
        except OSError:
            pass
