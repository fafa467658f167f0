"""`prsc compile`: sample scenes of a spec and write them in simulator formats.

    prsc compile FILE --target mjcf,urdf -n 100 --seed 0 -o out [--jobs 2]

writes under `out/<spec stem>/` one file (or bundle folder) per scene and target, named by
the zero-padded scene index (`mjcf/00007.xml`, `urdf/00007/`, ...), the shared assets
(`assets/`) they refer to by relative paths, and `manifest.json`. Every file is written to
a temporary name and renamed, so an interrupted or failed run leaves no half-written
file; a re-run with the same spec and seed skips the scenes already written. FILE may
also be scene JSON (a `.json` document or `.jsonl` lines, e.g. from `prsc sample`).
"""

from __future__ import annotations

import argparse
import errno
import hashlib
import json
import multiprocessing
import os
import shutil
import sys
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterable

from prsc.errors import PrscError

MANIFEST = "manifest.json"
MANIFEST_FORMAT = "prsc-manifest"
DEFAULT_WIDTH = 5


def add_parser(subparsers: Any) -> None:
    """Register `prsc compile`."""
    parser = subparsers.add_parser("compile", help="sample scenes and write simulator files", description=__doc__,
                                   formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("file", help="a .prs spec, or scene JSON (.json / .jsonl)")
    parser.add_argument("--target", "-t", default="json", help="comma-separated: json, mjcf, urdf, sdf, usd (default json)")
    parser.add_argument("-n", "--scenes", type=int, default=None,
                        help="number of scenes (default 1; for scene JSON input, all of them, as does 0)")
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    parser.add_argument("-o", "--output", default="out", help="output folder (default out)")
    parser.add_argument("--jobs", "-j", type=int, default=1, help="worker processes (default 1)")


# ------------------------------------------------------------------ scene sources


def _read_scene_file(path: Path) -> list[dict]:
    """Scenes of a .json (one scene or a list) or .jsonl file."""
    text = path.read_text(encoding="utf-8")
    try:
        if path.suffix == ".jsonl":
            scenes = [json.loads(line) for line in text.splitlines() if line.strip()]
        else:
            loaded = json.loads(text)
            scenes = loaded if isinstance(loaded, list) else [loaded]
    except json.JSONDecodeError as error:
        from prsc.errors import Span

        raise PrscError(f"invalid JSON: {error.msg}", Span(str(path), error.lineno, error.colno, error.lineno, error.colno + 1)) from None
    if not all(isinstance(s, dict) for s in scenes):
        raise PrscError(f"{path}: expected scene JSON objects")
    return scenes


def _spec_sampler(spec: str, seed: int) -> Callable[[int], dict]:
    """Scene k of a .prs spec as scene JSON (the sampler is imported only when needed)."""
    from prsc.sampling import compile_sampler

    sampler = compile_sampler(spec, include_dirs=())
    return lambda index: sampler.scene(seed=seed, index=index)


@dataclass
class Job:
    """What a worker needs to render scenes: the source, targets and output layout."""

    spec: str
    seed: int
    targets: tuple[str, ...]
    root: str
    width: int
    scenes: list[dict] | None = None  # given scene JSON, or None to sample the spec
    _sampler: Callable[[int], dict] | None = field(default=None, repr=False)

    def scene(self, index: int) -> dict:
        """Scene JSON of scene `index`."""
        if self.scenes is not None:
            return self.scenes[index]
        if self._sampler is None:
            self._sampler = _spec_sampler(self.spec, self.seed)
        return self._sampler(index)

    def __getstate__(self) -> dict:
        # A spawned worker compiles the spec again rather than pickling the sampler.
        state = dict(self.__dict__)
        state["_sampler"] = None
        return state

    def relative(self, target: str, index: int) -> str:
        """Path of a scene's output for one target, relative to the manifest."""
        from backends import TARGETS

        return f"{target}/{TARGETS[target].filename(index, self.width)}"


# ------------------------------------------------------------------ one scene


def _os_error(error: OSError, path: Path | str | None = None) -> PrscError:
    where = path or error.filename or "output"
    reason = os.strerror(error.errno) if error.errno else str(error)
    if error.errno == errno.ENOSPC:
        reason = "no space left on device"
    return PrscError(f"cannot write {where}: {reason}")


def render_one(job: Job, index: int) -> tuple[int, dict[str, str], list[str]]:
    """Render and write the missing outputs of one scene; returns its files and warnings."""
    from backends import TARGETS
    from backends.files import atomic_write, atomic_write_tree
    from backends.scene import parse_scene
    from backends.store import AssetStore

    root = Path(job.root)
    store = AssetStore(root / "assets")
    files: dict[str, str] = {}
    missing = []
    for target in job.targets:
        rel = job.relative(target, index)
        files[target] = rel
        if not (root / rel).exists():
            missing.append(target)
    messages: list[str] = []
    if not missing:
        return index, files, messages
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scene = parse_scene(job.scene(index))
        for target in missing:
            path = root / files[target]
            try:
                data = TARGETS[target].render()(scene, path, store)
                if TARGETS[target].bundle:
                    atomic_write_tree(path, data)
                else:
                    atomic_write(path, data)
            except OSError as error:
                raise _os_error(error, path) from None
    from backends.bodies import UnknownModelWarning

    for w in caught:  # others (e.g. MuJoCo's mesh decoder) go back to Python's filters
        if not issubclass(w.category, UnknownModelWarning):
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    messages = [str(w.message) for w in caught if issubclass(w.category, UnknownModelWarning)]
    return index, files, messages


# ------------------------------------------------------------------ workers

_worker_job: Job | None = None


def _worker_init(job: Job) -> None:
    global _worker_job
    _worker_job = job


def _worker_render(index: int) -> tuple[str, Any]:
    """Worker entry: ('ok', result) or ('error', message) so errors cross process lines."""
    try:
        return "ok", render_one(_worker_job, index)
    except PrscError as error:
        return "error", error.message
    except OSError as error:
        return "error", _os_error(error).message


def _run_serial(job: Job, indices: list[int], done: Callable[[tuple[int, dict, list[str]]], None]) -> None:
    for index in indices:
        done(render_one(job, index))


def _run_parallel(job: Job, indices: list[int], jobs: int, done: Callable[[tuple[int, dict, list[str]]], None]) -> None:
    context = multiprocessing.get_context("fork" if "fork" in multiprocessing.get_all_start_methods() else "spawn")
    chunk = max(1, min(16, len(indices) // (jobs * 8) or 1))
    pool = context.Pool(jobs, initializer=_worker_init, initargs=(job,))
    try:
        for status, value in pool.imap_unordered(_worker_render, indices, chunksize=chunk):
            if status == "error":
                raise PrscError(value)
            done(value)
        pool.close()
    except BaseException:
        pool.terminate()
        raise
    finally:
        pool.join()


# ------------------------------------------------------------------ output folder


def _sweep_temporaries(root: Path) -> None:
    """Remove temporary files and folders a killed writer may have left (`.name.*.tmp`)."""
    if not root.is_dir():
        return
    for folder, dirs, names in os.walk(root):
        for name in list(dirs):
            if name.startswith(".") and (name.endswith(".tmp") or name.endswith(".old")):
                shutil.rmtree(Path(folder) / name, ignore_errors=True)
                dirs.remove(name)
        for name in names:
            if name.startswith(".") and name.endswith(".tmp"):
                try:
                    os.unlink(Path(folder) / name)
                except OSError:
                    pass


def _prepare_root(output: Path, stem: str, targets: Iterable[str]) -> Path:
    """Create `output/<stem>/<target>/`, with clear errors for a broken or unwritable path."""
    root = output / stem
    try:
        for folder in [root, root / "assets"] + [root / t for t in targets]:
            if folder.exists() and not folder.is_dir():
                raise PrscError(f"output path {folder} exists and is not a folder")
            folder.mkdir(parents=True, exist_ok=True)
        if not os.access(root, os.W_OK):
            raise PrscError(f"cannot write to output folder {root}: permission denied")
    except OSError as error:
        raise PrscError(f"cannot create output folder {error.filename or root}: {os.strerror(error.errno) if error.errno else error}") from None
    return root


def _load_manifest(root: Path) -> dict | None:
    path = root / MANIFEST
    if not path.exists():
        return None
    try:
        manifest = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError, UnicodeDecodeError) as error:
        raise PrscError(f"{path} is unreadable ({error}); remove it or choose another output folder") from None
    if not isinstance(manifest, dict) or not isinstance(manifest.get("scenes"), list):
        raise PrscError(f"{path} is not a prsc manifest; remove it or choose another output folder")
    return manifest


def _remove_stale(root: Path, manifest: dict) -> None:
    """Outputs of another spec or seed in the same folder: drop them (they are not ours)."""
    for scene in manifest.get("scenes", []):
        for rel in (scene.get("files") or {}).values():
            path = root / str(rel)
            if path.resolve().is_relative_to(root.resolve()):
                if path.is_dir():
                    shutil.rmtree(path, ignore_errors=True)
                elif path.exists():
                    path.unlink()


def _write_manifest(root: Path, manifest: dict) -> None:
    from backends.files import atomic_write

    try:
        atomic_write(root / MANIFEST, json.dumps(manifest, indent=1) + "\n")
    except OSError as error:
        raise _os_error(error, root / MANIFEST) from None


# ------------------------------------------------------------------ the command


def _progress(total: int):
    """A rich progress bar on a terminal, or None."""
    if total == 0 or not sys.stderr.isatty():
        return None
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

    return Progress(TextColumn("compiling"), BarColumn(), MofNCompleteColumn(), TimeRemainingColumn(),
                    console=Console(file=sys.stderr), transient=True)


def compile_scenes(file: str, targets: list[str], n: int | None, seed: int, output: str, jobs: int = 1) -> Path:
    """Compile `n` scenes of `file` into `output/<stem>/`; returns that folder.

    For scene JSON input, `n` None or 0 means every scene in the file."""
    from backends import TARGETS

    unknown = [t for t in targets if t not in TARGETS]
    if unknown or not targets:
        raise PrscError(f"unknown target {', '.join(unknown) or '(none)'}; choose from {', '.join(TARGETS)}")
    if n is not None and n < 0:
        raise PrscError(f"-n must be >= 0, got {n}")
    if jobs < 1:
        raise PrscError(f"--jobs must be >= 1, got {jobs}")
    path = Path(file)
    try:
        data = path.read_bytes()
    except OSError as error:
        raise PrscError(f"cannot read {file}: {os.strerror(error.errno) if error.errno else error}") from None
    scenes = _read_scene_file(path) if path.suffix in (".json", ".jsonl") else None
    if scenes is not None:
        n = len(scenes) if not n else min(n, len(scenes))
    elif n is None:
        n = 1
    # Compile the spec before touching the output folder and before any worker starts:
    # a bad spec leaves nothing behind and its errors point into the spec.
    sampler = _spec_sampler(str(file), seed) if scenes is None else None
    width = max(DEFAULT_WIDTH, len(str(max(n - 1, 0))))
    root = _prepare_root(Path(output), path.stem, targets)
    _sweep_temporaries(root)
    digest = hashlib.sha256(data).hexdigest()
    manifest = _load_manifest(root)
    if manifest is not None and (manifest.get("spec_sha256") != digest or manifest.get("seed") != seed):
        _remove_stale(root, manifest)
        manifest = None
    entries: dict[int, dict[str, str]] = {}
    if manifest is not None:
        for scene in manifest["scenes"]:
            if isinstance(scene, dict) and isinstance(scene.get("index"), int):
                entries[scene["index"]] = {k: v for k, v in (scene.get("files") or {}).items() if (root / v).exists()}
    job = Job(spec=str(file), seed=seed, targets=tuple(targets), root=str(root), width=width, scenes=scenes,
              _sampler=sampler)
    todo = [k for k in range(n) if not all((root / job.relative(t, k)).exists() for t in targets)]
    pending = set(todo)
    for k in range(n):
        if k not in pending:
            entries.setdefault(k, {}).update({t: job.relative(t, k) for t in targets})

    from backends.bodies import reset_model_warnings

    reset_model_warnings()  # once per class per run, also in workers forked below
    seen_warnings: set[str] = set()
    bar = _progress(len(todo))
    task = bar.add_task("compile", total=len(todo)) if bar else None

    def done(result: tuple[int, dict[str, str], list[str]]) -> None:
        index, files, messages = result
        entries.setdefault(index, {}).update(files)
        for message in messages:
            if message not in seen_warnings:
                seen_warnings.add(message)
                sys.stderr.write(f"prsc: warning: {message}\n")
        if bar:
            bar.advance(task)

    def manifest_now() -> dict:
        return {
            "format": MANIFEST_FORMAT,
            "version": 1,
            "spec": str(file),
            "spec_sha256": digest,
            "seed": seed,
            "scenes": [{"index": k, "files": dict(sorted(entries[k].items()))} for k in sorted(entries) if entries[k]],
        }

    # Written first too: a re-run after an interruption then knows whose files these are.
    _write_manifest(root, manifest_now())
    try:
        if bar:
            bar.start()
        if jobs > 1 and len(todo) > 1:
            # The first scene in this process warms the per-process caches (robot
            # fragments, converted assets) that the forked workers then inherit.
            _run_serial(job, todo[:1], done)
            _run_parallel(job, todo[1:], jobs, done)
        else:
            _run_serial(job, todo, done)
    except BaseException:
        _sweep_temporaries(root)
        try:  # best effort: record the scenes that were completed
            _write_manifest(root, manifest_now())
        except PrscError:
            pass
        raise
    finally:
        if bar:
            bar.stop()
    _write_manifest(root, manifest_now())
    return root


def run(args: argparse.Namespace) -> int:
    """Entry point of `prsc compile`."""
    targets = list(dict.fromkeys(t.strip() for t in str(args.target).split(",") if t.strip()))
    compile_scenes(args.file, targets, args.scenes, args.seed, args.output, args.jobs)
    return 0
