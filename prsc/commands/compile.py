"""`prsc compile`: sample scenes of a spec and write them in simulator formats.

    prsc compile FILE --target mjcf,urdf -n 100 --seed 0 -o out [--jobs 2] [-I DIR]
                 [--executor local|ray [--address ADDR]]

writes under `out/<spec stem>/` one file (or bundle folder) per scene and target, named by
the zero-padded scene index (`mjcf/00007.xml`, `urdf/00007/`, ...), the shared assets
(`assets/`) they refer to by relative paths, and `manifest.json`. Every file is written to
a temporary name and renamed, so an interrupted or failed run leaves no half-written
file; a re-run with the same spec and seed skips the scenes already written. FILE may
also be scene JSON (a `.json` document or `.jsonl` lines, e.g. from `prsc sample`).

One run at a time writes a folder (a second one is refused). Each file is recorded in
`manifest.jsonl` the moment it is in place, and `manifest.json` (the whole list) is
rewritten every few seconds and at the end, when it absorbs `manifest.jsonl`: after a
kill, the two together list every finished file. prsc deletes only files its manifest
lists, and writes a changed spec or seed into a folder of other scenes only with --force.
"""

from __future__ import annotations

import argparse
import fcntl
import functools
import hashlib
import itertools
import json
import os
import shutil
import sys
import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterable, Sequence

from prsc.commands.executors import Executor, LocalExecutor, add_executor_arguments, make_executor, worker_count
from prsc.commands.outputs import write_error
from prsc.errors import PrscError, Span

MANIFEST = "manifest.json"
JOURNAL = "manifest.jsonl"  # one line per file put in place since manifest.json was written
LOCK = ".prsc-lock"
MANIFEST_FORMAT = "prsc-manifest"
DEFAULT_WIDTH = 5
MAX_JSON_DEPTH = 100  # reported when a scene file is nested too deeply for Python's JSON reader
CHECKPOINT_SECONDS = 2.0  # manifest.json is rewritten at most this often during a run


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
    parser.add_argument("--meshes-anywhere", action="store_true",
                        help="let `with mesh` read absolute paths and paths outside the spec's and --include folders")
    parser.add_argument("--force", action="store_true",
                        help="replace the scenes of another spec or seed in the output folder (only files its manifest lists)")
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

    def too_deep(document: str, first_line: int) -> PrscError:
        line, column = _nesting_place(document, MAX_JSON_DEPTH)
        return PrscError(f"JSON nested more than {MAX_JSON_DEPTH} levels deep",
                         Span(str(path), first_line + line - 1, column, first_line + line - 1, column + 1))

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
                except RecursionError:
                    raise too_deep(line, number) from None
    else:
        try:
            loaded = json.loads(text)
        except json.JSONDecodeError as error:
            raise invalid(error, error.lineno) from None
        except RecursionError:
            raise too_deep(text, 1) from None
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


def _nesting_place(text: str, limit: int) -> tuple[int, int]:
    """(line, column) of the bracket that opens level `limit + 1` of a JSON text (strings skipped)."""
    depth, line, column, in_string, escaped = 0, 1, 0, False, False
    for char in text:
        column += 1
        if char == "\n":
            line, column = line + 1, 0
        elif in_string:
            escaped, in_string = (False, True) if escaped else (char == "\\", char != '"')
        elif char == '"':
            in_string = True
        elif char in "[{":
            depth += 1
            if depth > limit:
                return line, column
        elif char in "]}":
            depth -= 1
    return 1, 1


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
    # A file at one of this run's names that the manifest does not list: rewritten when the
    # folder's manifest is this run's (a kill between rename and record), else refused.
    adopt_unlisted: bool = True
    meshes_anywhere: bool = False  # --meshes-anywhere
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


def _record(root: Path, index: int, target: str, rel: str) -> None:
    """Append one finished file to the journal: a single O_APPEND write, so lines never interleave."""
    line = json.dumps({"index": index, "files": {target: rel}}, separators=(",", ":")) + "\n"
    handle = os.open(root / JOURNAL, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
    try:
        os.write(handle, line.encode())
    finally:
        os.close(handle)


def render_one(job: Job, index: int, listed: Callable[[int, str], bool] = lambda index, target: False
               ) -> tuple[int, dict[str, str], list[str]]:
    """Render and write the outputs of one scene that `listed` does not already record.

    Returns its files and warnings; each file is journalled as soon as it is in place."""
    from prsc.backends import TARGETS
    from prsc.backends.scene import parse_scene
    from prsc.backends.store import AssetStore
    from prsc.files import atomic_write, atomic_write_tree

    root = Path(job.root)
    store = AssetStore(root / "assets", job.include_dirs, job.meshes_anywhere)
    files: dict[str, str] = {}
    missing = []
    for target in job.targets:
        rel = job.relative(target, index)
        files[target] = rel
        if listed(index, target) and (root / rel).exists():
            continue
        if (root / rel).exists() and not job.adopt_unlisted:
            raise PrscError(f"{root / rel} exists and is not listed in {root / MANIFEST}: prsc did not write it "
                            "and will not replace it; move it away or choose another output folder")
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
                _record(root, index, target, files[target])
            except OSError as error:
                raise write_error(error, path) from None
    from prsc.backends.bodies import UnknownModelWarning

    for w in caught:  # others (e.g. MuJoCo's mesh decoder) go back to Python's filters
        if not issubclass(w.category, UnknownModelWarning):
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    messages = [str(w.message) for w in caught if issubclass(w.category, UnknownModelWarning)]
    return index, files, messages


# ------------------------------------------------------------------ workers
# Scene indices on an executor's workers (prsc.commands.executors), apart from the output
# folder's bookkeeping.

def _worker_render(shared: tuple[Job, Callable[[int, str], bool]], index: int) -> tuple[str, Any]:
    """Worker entry: ('ok', result) or ('error', (message, span, notes, obj)) so errors cross process lines."""
    job, listed = shared
    try:
        return "ok", render_one(_worker_copy(job), index, listed)
    except PrscError as error:
        return "error", (error.message, error.span, error.notes, error.obj)  # parts: the exception does not pickle whole
    except OSError as error:
        return "error", (write_error(error).message, None, (), None)


_worker_jobs: dict[tuple, Job] = {}


def _worker_copy(job: Job) -> Job:
    """The worker's own copy of a job, so its sampler is compiled once per worker, not per scene."""
    if job._sampler is not None or job.scenes is not None:
        return job  # forked from the driver with its sampler, or given scenes: nothing to compile
    key = (job.spec, job.seed, job.targets, job.root, job.width, job.include_dirs, job.sources)
    return _worker_jobs.setdefault(key, job)


def _run_serial(job: Job, indices: Iterable[int], done: Callable[[tuple[int, dict, list[str]]], None],
                listed: Callable[[int, str], bool]) -> None:
    for index in indices:
        done(render_one(job, index, listed))


def _run_parallel(job: Job, indices: Iterable[int], executor: Executor,
                  done: Callable[[tuple[int, dict, list[str]]], None], listed: Callable[[int, str], bool]) -> None:
    """Render `indices` (a lazy iterable, however long) on the executor's workers."""
    def collect(answer: tuple[str, Any]) -> None:
        status, value = answer
        if status == "error":
            raise PrscError(*value)
        done(value)

    executor.map(_worker_render, (job, listed), indices, collect)


# ------------------------------------------------------------------ output folder


def _output_root(output: Path, path: Path) -> Path:
    """`output/<stem>`: the stem must name a folder inside `output`, never `output` itself or its parent."""
    stem = path.stem
    if stem in ("", ".", "..") or "/" in stem or "\\" in stem or not stem.isprintable():
        raise PrscError(f"cannot name an output folder after {path} (its name without the suffix is {stem!r}); "
                        "rename the file")
    return output / stem


def _prepare_root(root: Path, targets: Iterable[str]) -> None:
    """Create `root/<target>/`, with clear errors for a broken or unwritable path."""
    try:
        for folder in [root, root / "assets"] + [root / t for t in targets]:
            if folder.exists() and not folder.is_dir():
                raise PrscError(f"output path {folder} exists and is not a folder")
            folder.mkdir(parents=True, exist_ok=True)
        if not os.access(root, os.W_OK):
            raise PrscError(f"cannot write to output folder {root}: permission denied")
    except OSError as error:
        raise PrscError(f"cannot create output folder {error.filename or root}: {os.strerror(error.errno) if error.errno else error}") from None


def _lock_folder(root: Path) -> int:
    """An exclusive lock on the output folder for this run (released when the process and its workers end)."""
    try:
        handle = os.open(root / LOCK, os.O_RDWR | os.O_CREAT, 0o644)
    except OSError as error:
        raise write_error(error, root / LOCK) from None
    try:
        fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        os.close(handle)
        raise PrscError(f"output folder {root} is being written by another prsc run; "
                        "wait for it to finish or choose another output folder") from None
    return handle


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
    for target, rel in files.items():
        if target not in TARGETS or not isinstance(rel, str):
            raise bad(f"scene {index}: {target!r}: {rel!r} is not an output of prsc")
        suffix = TARGETS[target].suffix
        folder, _, name = rel.partition("/")
        digits = name[: len(name) - len(suffix)] if suffix else name
        if folder != target or not name.endswith(suffix) or not digits.isdigit() or not digits.isascii() \
                or int(digits) != index or len(digits) < DEFAULT_WIDTH:
            raise bad(f"scene {index}: {target!r}: {rel!r} is not an output of prsc")
    return index, dict(files)


def _load_manifest(root: Path) -> tuple[dict | None, dict[int, dict[str, str]]]:
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
            entry = None
        index, files = _entry_files(root, entry, f"{JOURNAL} line {number}")
        entries.setdefault(index, {}).update(files)


def _remove_listed(root: Path, entries: dict[int, dict[str, str]]) -> None:
    """Delete the files a validated manifest lists (outputs of another spec or seed), and nothing else."""
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


def _write_manifest(root: Path, manifest: dict) -> None:
    from prsc.files import atomic_write

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
                   include_dirs: Sequence[str] = (), executor: Executor | None = None, force: bool = False,
                   meshes_anywhere: bool = False) -> Path:
    """Compile `n` scenes of `file` into `output/<stem>/`; returns that folder.

    For scene JSON input, `n` None or 0 means every scene in the file; `include_dirs`
    (--include) are searched for a spec's imports and meshes; `executor` (default: `jobs`
    forked local processes) runs the scenes; `force` replaces the listed scenes of another
    spec or seed; `meshes_anywhere` lets meshes come from any folder."""
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
    root = _output_root(Path(output), path)
    program: Any = None  # the spec's IR, for errors a backend reports by object
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
        # reading it whole for the digest: the parser refuses a huge file after 256 KiB.)
        from prsc.sampling import compile_sampler

        compiled = compile_sampler(str(file), include_dirs=include_dirs)
        program = compiled.program
        sampler = functools.partial(compiled.scene, seed)
        data = _read_input(path)
        sources = hashlib.sha256(data)
        for imported in compiled.program.source_files[1:]:
            # The scenes also depend on every imported file (those found through --include
            # too): a change there makes them stale.
            sources.update(_read_input(Path(imported)))
    if executor is None:
        jobs = worker_count(jobs)
    width = max(DEFAULT_WIDTH, len(str(max(n - 1, 0))))
    # The topmost folder this run creates: removed again if the run fails before any scene.
    created = next((p for p in (*reversed(root.absolute().parents), root.absolute()) if not p.exists()), None)
    _prepare_root(root, targets)
    lock = _lock_folder(root)
    try:
        return _compile_locked(root, file, targets, n, seed, jobs, include_dirs, force, data, sources, scenes,
                               sampler, width, created, meshes_anywhere, executor)
    except PrscError as error:
        raise _at_object(error, program) from None
    finally:
        os.close(lock)


def _at_object(error: PrscError, program: Any) -> PrscError:
    """A backend's error about an object, at the object's line in the spec (when there is one)."""
    if error.span is not None or error.obj is None or program is None:
        return error
    decl = next((o for o in program.objects if o.name == error.obj), None)
    return error if decl is None else PrscError(error.message, decl.span, error.notes)


def _compile_locked(root: Path, file: str, targets: list[str], n: int, seed: int, jobs: int,
                    include_dirs: Sequence[str], force: bool, data: bytes, sources: Any, scenes: list[dict] | None,
                    sampler: Callable[[int], dict] | None, width: int, created: Path | None,
                    meshes_anywhere: bool, executor: Executor | None) -> Path:
    """The part of compile_scenes that runs while this process holds the folder's lock."""
    from prsc.files import remove_stale_temporaries

    remove_stale_temporaries(root, recursive=True)
    digest = hashlib.sha256(data).hexdigest()
    sources_digest = sources.hexdigest()
    manifest, entries = _load_manifest(root)
    if manifest is not None and (
        manifest.get("spec_sha256") != digest or manifest.get("sources_sha256") != sources_digest
        or manifest.get("seed") != seed
    ):
        if entries and not force:
            was = f"seed {manifest.get('seed')!r} of {manifest.get('spec', 'another spec')}"
            raise PrscError(f"{root} holds {len(entries)} scenes of another spec or seed ({was}); "
                            "pass --force to replace them, or choose another output folder")
        _remove_listed(root, entries)
        manifest, entries = None, {}
    job = Job(spec=str(file), seed=seed, targets=tuple(targets), root=str(root), width=width, scenes=scenes,
              include_dirs=tuple(include_dirs), sources=sources_digest, adopt_unlisted=manifest is not None,
              meshes_anywhere=meshes_anywhere, _sampler=sampler)
    listed = _Listed(root, {k: dict(v) for k, v in entries.items()})

    def todo() -> Iterable[int]:
        # Lazy: -n 10**12 neither builds a list nor checks a file before the first scene.
        return (k for k in range(n) if not all(listed(k, t) and (root / job.relative(t, k)).exists() for t in targets))

    from prsc.backends.bodies import reset_model_warnings

    reset_model_warnings()  # once per class per run, also in workers forked below
    seen_warnings: set[str] = set()
    total = sum(1 for _ in todo()) if n <= 100_000 else 0  # a progress total only when cheap to count
    bar = _progress(total)
    task = bar.add_task("compile", total=total) if bar else None
    next_checkpoint = [time.monotonic() + CHECKPOINT_SECONDS]

    def done(result: tuple[int, dict[str, str], list[str]]) -> None:
        index, files, messages = result
        entries.setdefault(index, {}).update(files)
        for message in messages:
            if message not in seen_warnings:
                seen_warnings.add(message)
                sys.stderr.write(f"prsc: warning: {message}\n")
        if bar:
            bar.advance(task)
        if time.monotonic() > next_checkpoint[0]:
            started = time.monotonic()
            _write_manifest(root, manifest_now())
            # A huge manifest is rewritten less often: at most 5 % of the run goes to it.
            next_checkpoint[0] = time.monotonic() + max(CHECKPOINT_SECONDS, 20 * (time.monotonic() - started))

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
        pending = iter(todo())
        executor = executor or LocalExecutor(jobs, start="fork")
        if isinstance(executor, LocalExecutor) and executor.jobs > 1:
            # The first scene in this process warms the per-process caches (robot
            # fragments, converted assets) that the forked workers then inherit.
            _run_serial(job, itertools.islice(pending, 1), done, listed)
            _run_parallel(job, pending, executor, done, listed)
        elif isinstance(executor, LocalExecutor):
            _run_serial(job, pending, done, listed)
        else:
            _run_parallel(job, pending, executor, done, listed)
    except BaseException:
        remove_stale_temporaries(root, recursive=True)
        if created is not None and not any(entries.values()) and not (root / JOURNAL).exists():
            shutil.rmtree(created, ignore_errors=True)  # a failed first run leaves nothing behind
            raise
        try:  # best effort: record the scenes that were completed (the journal keeps them otherwise)
            _close_manifest(root, entries, manifest_now)
        except PrscError:
            pass
        raise
    finally:
        if bar:
            bar.stop()
    _close_manifest(root, entries, manifest_now)
    return root


def _close_manifest(root: Path, entries: dict[int, dict[str, str]], manifest_now: Callable[[], dict]) -> None:
    """Write manifest.json with every journalled file (the workers have stopped), then drop the journal."""
    _absorb_journal(root, entries)
    _write_manifest(root, manifest_now())
    (root / JOURNAL).unlink(missing_ok=True)  # manifest.json now holds every line of it


@dataclass
class _Listed:
    """Whether the manifest lists a scene's file for a target (picklable, for the workers)."""

    root: Path
    entries: dict[int, dict[str, str]]

    def __call__(self, index: int, target: str) -> bool:
        return target in self.entries.get(index, {})


def run(args: argparse.Namespace) -> int:
    """Entry point of `prsc compile`."""
    targets = list(dict.fromkeys(t.strip() for t in str(args.target).split(",") if t.strip()))
    jobs = worker_count(args.jobs)
    executor = make_executor(args.executor, jobs, args.address, start="fork")
    compile_scenes(args.file, targets, args.scenes, args.seed, args.output, jobs, args.include, executor,
                   args.force, args.meshes_anywhere)
    return 0
