"""`prsc compile`: sample scenes of a spec and write them in simulator formats.

    prsc compile FILE --target mjcf,urdf -n 100 --seed 0 -o out [--jobs 2] [-I DIR]
                 [--executor local|ray [--address ADDR]]

writes under `out/<spec stem>/` one file (or bundle folder) per scene and target, named by
the zero-padded scene index (`mjcf/00007.xml`, `urdf/00007/`, ...), the shared assets
(`assets/`) they refer to by relative paths, and `manifest.json`. Every file is written to
a temporary name and renamed, so an interrupted or failed run leaves no half-written
file; a re-run with the same spec and seed skips the scenes already written. FILE may
also be scene JSON (a `.json` document or `.jsonl` lines, e.g. from `prsc sample`).
"""

from __future__ import annotations

import argparse
import functools
import hashlib
import json
import os
import shutil
import sys
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterable, Sequence

from prsc.commands.executors import Executor, LocalExecutor, add_executor_arguments, make_executor
from prsc.commands.outputs import write_error
from prsc.errors import PrscError, Span

MANIFEST = "manifest.json"
MANIFEST_FORMAT = "prsc-manifest"
DEFAULT_WIDTH = 5


def add_parser(subparsers: Any) -> None:
    """Register `prsc compile`."""
    parser = subparsers.add_parser("compile", help="sample scenes and write simulator files", description=__doc__,
                                   formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("file", metavar="FILE", help="a .prs spec, or scene JSON (.json / .jsonl)")
    parser.add_argument("--target", "-t", default="json", help="comma-separated: json, mjcf, urdf, sdf, usd (default json)")
    parser.add_argument("-n", "--scenes", type=int, default=None,
                        help="number of scenes (default 1; for scene JSON input, all of them, as does 0)")
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    parser.add_argument("-o", "--output", default="out", help="output folder (default out)")
    parser.add_argument("--jobs", "-j", type=int, default=1, help="worker processes (default 1)")
    parser.add_argument("--include", "-I", action="append", default=[], metavar="DIR", help="also search DIR for imports")
    add_executor_arguments(parser)


# ------------------------------------------------------------------ scene sources


def _read_input(path: Path) -> bytes:
    """The bytes of an input file, or a PrscError saying why it cannot be read."""
    try:
        return path.read_bytes()
    except IsADirectoryError:
        raise PrscError(f"{path} is a directory, not a spec or scene file") from None
    except OSError as error:
        raise PrscError(f"cannot read {path}: {os.strerror(error.errno) if error.errno else error}") from None


def _read_scene_file(path: Path, data: bytes | None = None) -> list[dict]:
    """Scenes of a .json (one scene or a list) or .jsonl file, each validated.

    Validated here, before any output is written, so that an error points into the file
    (line of a .jsonl, position in a list) rather than surfacing halfway through a run."""
    from prsc.backends.scene import parse_scene
    from prsc.syntax import decode_text

    text = decode_text(_read_input(path) if data is None else data, str(path))

    def invalid(error: json.JSONDecodeError, line: int) -> PrscError:
        return PrscError(f"invalid JSON: {error.msg}", Span(str(path), line, error.colno, line, error.colno + 1))

    # (line number, scene): split on "\n" only, as the error renderer counts lines.
    found: list[tuple[int | None, object]] = []
    listed = True  # several scenes: name the one at fault
    if path.suffix == ".jsonl":
        for number, line in enumerate(text.split("\n"), start=1):
            if line.strip():
                try:
                    found.append((number, json.loads(line)))
                except json.JSONDecodeError as error:
                    raise invalid(error, number) from None
    else:
        try:
            loaded = json.loads(text)
        except json.JSONDecodeError as error:
            raise invalid(error, error.lineno) from None
        listed = isinstance(loaded, list)
        found = [(None, s) for s in loaded] if listed else [(None, loaded)]
    if not found:
        raise PrscError(f"{path}: no scenes in the file")
    for k, (line, scene) in enumerate(found):
        try:
            parse_scene(scene)  # type: ignore[arg-type]
        except PrscError as error:
            message = error.message.removeprefix("scene JSON: ")  # the file name says as much
            if line is not None:
                raise PrscError(message, Span(str(path), line, 1, line, 2)) from None
            raise PrscError(f"{path}: {f'scene {k}: ' if listed else ''}{message}") from None
    return [scene for _, scene in found]  # type: ignore[misc]


def _spec_sampler(spec: str, seed: int, include_dirs: Sequence[str] = ()) -> Callable[[int], dict]:
    """Scene k of a .prs spec as scene JSON (the sampler is imported only when needed)."""
    from prsc.sampling import compile_sampler

    sampler = compile_sampler(spec, include_dirs=include_dirs)
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
    include_dirs: tuple[str, ...] = ()  # --include: a worker compiling the spec again resolves the same imports
    sources: str = ""  # digest of the spec and its imports: a worker's cached sampler is for these sources
    _sampler: Callable[[int], dict] | None = field(default=None, repr=False)

    def scene(self, index: int) -> dict:
        """Scene JSON of scene `index`."""
        if self.scenes is not None:
            return self.scenes[index]
        if self._sampler is None:
            self._sampler = _spec_sampler(self.spec, self.seed, self.include_dirs)
        return self._sampler(index)

    def __getstate__(self) -> dict:
        # A spawned worker compiles the spec again rather than pickling the sampler.
        state = dict(self.__dict__)
        state["_sampler"] = None
        return state

    def relative(self, target: str, index: int) -> str:
        """Path of a scene's output for one target, relative to the manifest."""
        from prsc.backends import TARGETS

        return f"{target}/{TARGETS[target].filename(index, self.width)}"


# ------------------------------------------------------------------ one scene


def render_one(job: Job, index: int) -> tuple[int, dict[str, str], list[str]]:
    """Render and write the missing outputs of one scene; returns its files and warnings."""
    from prsc.backends import TARGETS
    from prsc.backends.files import atomic_write, atomic_write_tree
    from prsc.backends.scene import parse_scene
    from prsc.backends.store import AssetStore

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
                raise write_error(error, path) from None
    from prsc.backends.bodies import UnknownModelWarning

    for w in caught:  # others (e.g. MuJoCo's mesh decoder) go back to Python's filters
        if not issubclass(w.category, UnknownModelWarning):
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    messages = [str(w.message) for w in caught if issubclass(w.category, UnknownModelWarning)]
    return index, files, messages


# ------------------------------------------------------------------ workers

def _worker_render(job: Job, index: int) -> tuple[str, Any]:
    """Worker entry: ('ok', result) or ('error', (message, span, notes)) so errors cross process lines."""
    try:
        return "ok", render_one(_worker_copy(job), index)
    except PrscError as error:
        return "error", (error.message, error.span, error.notes)  # parts: the exception does not pickle whole
    except OSError as error:
        return "error", (write_error(error).message, None, ())


_worker_jobs: dict[tuple, Job] = {}


def _worker_copy(job: Job) -> Job:
    """The worker's own copy of a job, so its sampler is compiled once per worker, not per scene."""
    if job._sampler is not None or job.scenes is not None:
        return job  # forked from the driver with its sampler, or given scenes: nothing to compile
    key = (job.spec, job.seed, job.targets, job.root, job.width, job.include_dirs, job.sources)
    return _worker_jobs.setdefault(key, job)


def _run_serial(job: Job, indices: list[int], done: Callable[[tuple[int, dict, list[str]]], None]) -> None:
    for index in indices:
        done(render_one(job, index))


def _run_parallel(job: Job, indices: list[int], executor: Executor,
                  done: Callable[[tuple[int, dict, list[str]]], None]) -> None:
    def collect(answer: tuple[str, Any]) -> None:
        status, value = answer
        if status == "error":
            raise PrscError(*value)
        done(value)

    executor.map(_worker_render, job, indices, collect)


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
    from prsc.backends.files import atomic_write

    try:
        atomic_write(root / MANIFEST, json.dumps(manifest, indent=1) + "\n")
    except OSError as error:
        raise write_error(error, root / MANIFEST) from None


# ------------------------------------------------------------------ the command


def _progress(total: int):
    """A rich progress bar on a terminal, or None."""
    if total == 0 or not sys.stderr.isatty():
        return None
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

    return Progress(TextColumn("compiling"), BarColumn(), MofNCompleteColumn(), TimeRemainingColumn(),
                    console=Console(file=sys.stderr), transient=True)


def compile_scenes(file: str, targets: list[str], n: int | None, seed: int, output: str, jobs: int = 1,
                   include_dirs: Sequence[str] = (), executor: Executor | None = None) -> Path:
    """Compile `n` scenes of `file` into `output/<stem>/`; returns that folder.

    For scene JSON input, `n` None or 0 means every scene in the file; `include_dirs`
    (--include) are searched for a spec's imports. `executor` (default: `jobs` forked
    local processes) runs the scenes."""
    from prsc.backends import TARGETS

    unknown = [t for t in targets if t not in TARGETS]
    if unknown or not targets:
        raise PrscError(f"unknown target {', '.join(unknown) or '(none)'}; choose from {', '.join(TARGETS)}")
    if n is not None and n < 0:
        raise PrscError(f"-n must be >= 0, got {n}")
    if jobs < 1:
        raise PrscError(f"--jobs must be >= 1, got {jobs}")
    if seed < 0:
        raise PrscError(f"--seed must be >= 0, got {seed}")
    if not output:
        raise PrscError("the output folder path is empty")
    path = Path(file)
    if path.suffix in (".json", ".jsonl"):
        data = _read_input(path)
        scenes: list[dict] | None = _read_scene_file(path, data)
        sources = hashlib.sha256(data)
        n = len(scenes) if not n else min(n, len(scenes))
        sampler = None
    else:
        scenes = None
        n = 1 if n is None else n
        # Compile the spec before touching the output folder and before any worker starts:
        # a bad spec leaves nothing behind and its errors point into the spec. (Also before
        # reading it whole for the digest: the parser refuses a huge file after 1 MiB.)
        from prsc.sampling import compile_sampler

        compiled = compile_sampler(str(file), include_dirs=include_dirs)
        sampler = functools.partial(compiled.scene, seed)
        data = _read_input(path)
        sources = hashlib.sha256(data)
        for imported in compiled.program.source_files[1:]:
            # The scenes also depend on every imported file (those found through --include
            # too): a change there makes them stale.
            sources.update(_read_input(Path(imported)))
    width = max(DEFAULT_WIDTH, len(str(max(n - 1, 0))))
    root = Path(output) / path.stem
    # The topmost folder this run creates: removed again if the run fails before any scene.
    created = next((p for p in (*reversed(root.absolute().parents), root.absolute()) if not p.exists()), None)
    _prepare_root(Path(output), path.stem, targets)
    _sweep_temporaries(root)
    digest = hashlib.sha256(data).hexdigest()
    sources_digest = sources.hexdigest()
    manifest = _load_manifest(root)
    if manifest is not None and (
        manifest.get("spec_sha256") != digest or manifest.get("sources_sha256") != sources_digest
        or manifest.get("seed") != seed
    ):
        _remove_stale(root, manifest)
        manifest = None
    entries: dict[int, dict[str, str]] = {}
    if manifest is not None:
        for scene in manifest["scenes"]:
            if isinstance(scene, dict) and isinstance(scene.get("index"), int):
                entries[scene["index"]] = {k: v for k, v in (scene.get("files") or {}).items() if (root / v).exists()}
    job = Job(spec=str(file), seed=seed, targets=tuple(targets), root=str(root), width=width, scenes=scenes,
              include_dirs=tuple(include_dirs), sources=sources_digest, _sampler=sampler)
    todo = [k for k in range(n) if not all((root / job.relative(t, k)).exists() for t in targets)]
    pending = set(todo)
    for k in range(n):
        if k not in pending:
            entries.setdefault(k, {}).update({t: job.relative(t, k) for t in targets})

    from prsc.backends.bodies import reset_model_warnings

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
            "sources_sha256": sources_digest,
            "seed": seed,
            "scenes": [{"index": k, "files": dict(sorted(entries[k].items()))} for k in sorted(entries) if entries[k]],
        }

    # Written first too: a re-run after an interruption then knows whose files these are.
    _write_manifest(root, manifest_now())
    try:
        if bar:
            bar.start()
        executor = executor or LocalExecutor(jobs, start="fork")
        if isinstance(executor, LocalExecutor) and executor.jobs > 1 and len(todo) > 1:
            # The first scene in this process warms the per-process caches (robot
            # fragments, converted assets) that the forked workers then inherit.
            _run_serial(job, todo[:1], done)
            _run_parallel(job, todo[1:], executor, done)
        elif isinstance(executor, LocalExecutor):
            _run_serial(job, todo, done)
        else:
            _run_parallel(job, todo, executor, done)
    except BaseException:
        _sweep_temporaries(root)
        if created is not None and not any(entries.values()):
            shutil.rmtree(created, ignore_errors=True)  # a failed first run leaves nothing behind
            raise
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
    executor = make_executor(args.executor, args.jobs, args.address, start="fork")
    compile_scenes(args.file, targets, args.scenes, args.seed, args.output, args.jobs, args.include, executor)
    return 0
