"""`prsc compile`: sample scenes of a spec and write them in simulator formats.

    prsc compile FILE --target mjcf,urdf -n 100 --seed 0 -o out [--jobs 2] [-I DIR]
                 [--executor local|ray [--address ADDR]]

writes under `out/<spec stem>/` one file (or bundle folder) per scene and target, named by
the zero-padded scene index (`mjcf/00007.xml`, `urdf/00007/`, ...), the shared assets
(`assets/`) they refer to by relative paths, and `manifest.json`. Every file is written to
a temporary name and renamed, so an interrupted or failed run leaves no half-written
file; a re-run with the same spec and seed skips the scenes already written. FILE may
also be scene JSON (a `.json` document or `.jsonl` lines, e.g. from `prsc sample`).

One run at a time writes a folder, and prsc deletes only files its manifest lists
(prsc.pipeline.output_folder); it writes a changed spec or seed into a folder of other
scenes only with --force. Scenes come from prsc.pipeline.scene_sources.
"""

from __future__ import annotations

import argparse
import hashlib
import itertools
import os
import shutil
import sys
import time
import warnings
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Callable, Iterable, Sequence

from prsc.pipeline.executors import Executor, LocalExecutor, add_executor_arguments, executor_from_arguments, worker_count
from prsc.pipeline.output_folder import (
    CHECKPOINT_SECONDS, DEFAULT_WIDTH, JOURNAL, MANIFEST, MANIFEST_FORMAT, Listed, close_manifest, load_manifest,
    lock_folder, output_root, prepare_root, remove_listed, write_manifest,
)
from prsc.pipeline.scene_sources import add_law_argument, add_proposal_argument, proposal_from_json, proposal_key
from prsc.pipeline.scene_job import Job, render_one, worker_render
from prsc.pipeline.seed_jobs import check_seed_and_jobs
from prsc.pipeline.scene_sources import read_input, read_proposal, read_scene_file
from prsc.pipeline.progress import progress_bar
from prsc.commands.settle import SETTLE_HELP, settle_check, settle_targets
from prsc.errors import PrscError



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
                        help="replace the scenes of another spec, imported file, seed, law or proposal in the output folder (only files its manifest lists)")
    parser.add_argument("--settle-check", action="store_true", help=SETTLE_HELP)
    add_proposal_argument(parser)
    add_executor_arguments(parser)
    add_law_argument(parser)


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

    executor.map(worker_render, (job, listed), indices, collect)


# ------------------------------------------------------------------ the command


@dataclass(frozen=True)
class CompileOptions:
    """How `compile_scenes` runs, apart from what it compiles and where."""

    jobs: int = 1
    include_dirs: tuple[str, ...] = ()  # --include: searched for a spec's imports and meshes
    executor: Executor | None = None  # default: `jobs` forked local processes
    force: bool = False  # replace the listed scenes of another spec or seed
    meshes_anywhere: bool = False  # meshes may come from any folder
    proposal: dict | None = None  # draw from a falsify proposal
    law: str | None = None  # --law
    compiled: Any = None  # the spec's Sampler, when the caller compiled it already (with these options)
    assets_dir: str | None = None  # shared files go here, not to <root>/assets (outputs refer to them relatively)


@dataclass(frozen=True)
class _Run:
    """One compile run, as `_compile_locked` needs it once the folder is locked."""

    file: str
    root: Path
    targets: tuple[str, ...]
    n: int
    seed: int
    options: CompileOptions
    spec_digest: str
    sources_digest: str
    width: int
    scenes: list[dict] | None
    sampler: Callable[[int], dict] | None


def compile_scenes(file: str, targets: Sequence[str], n: int | None, seed: int, output: str,
                   **options: Any) -> Path:
    """Compile `n` scenes of `file` into `output/<stem>/`; returns that folder.

    For scene JSON input, `n` None or 0 means every scene in the file. `options` are the
    fields of CompileOptions. Errors that one scene shows (a mesh outside the allowed
    folders, a name too long for the file system, an impossible mass) are found before the
    output folder is touched; a run that fails later leaves the folder as it was plus only
    complete, recorded scenes."""
    from prsc.backends import TARGETS

    settings = CompileOptions(**{**options, "include_dirs": tuple(options.get("include_dirs", ()))})
    targets = tuple(targets)
    unknown = [t for t in targets if t not in TARGETS]
    if unknown or not targets:
        raise PrscError(f"unknown target {', '.join(unknown) or '(none)'}; choose from {', '.join(TARGETS)}")
    if n is not None and n < 0:
        raise PrscError(f"-n must be >= 0, got {n}")
    check_seed_and_jobs(seed, settings.jobs)
    if not output:
        raise PrscError("the output folder path is empty")
    path = Path(file)
    root = output_root(Path(output), path)
    program: Any = None  # the spec's IR, for errors a backend reports by object
    law = settings.law
    if path.suffix in (".json", ".jsonl"):
        data = read_input(path)
        scenes: list[dict] | None = read_scene_file(path, data)
        sources = hashlib.sha256(data)
        n = len(scenes) if not n else min(n, len(scenes))
        sampler = None
    else:
        scenes = None
        n = 1 if n is None else n
        # Compile the spec before touching the output folder and before any worker starts:
        # a bad spec leaves nothing behind and its errors point into the spec. (Also before
        # reading it whole for the digest: the parser refuses a huge file after 256 KiB.)
        from prsc.pipeline.static_checks import compile_checked

        compiled = settings.compiled or compile_checked(str(file), settings.include_dirs, law=law,
                                                        proposal=proposal_from_json(settings.proposal))
        law = compiled.law
        program = compiled.program
        sampler = compiled.drawer(seed)  # the next 64 scenes at once when the spec is batched
        data = read_input(path)
        sources = hashlib.sha256(data)
        sources.update(f"law={law}".encode())  # another law gives other scenes
        for imported in compiled.program.source_files[1:]:
            # The scenes also depend on every imported file (those found through --include
            # too): a change there makes them stale.
            sources.update(read_input(Path(imported)))
        sources.update(proposal_key(settings.proposal))  # scenes drawn from another proposal are stale
    if settings.executor is None:
        settings = replace(settings, jobs=worker_count(settings.jobs))
    settings = replace(settings, law=law)
    compile_run = _Run(file=str(file), root=root, targets=targets, n=n, seed=seed, options=settings,
                       spec_digest=hashlib.sha256(data).hexdigest(), sources_digest=sources.hexdigest(),
                       width=max(DEFAULT_WIDTH, len(str(max(n - 1, 0)))), scenes=scenes, sampler=sampler)
    try:
        first = _first_to_render(compile_run)
        if first is not None:
            _preflight(compile_run, first)
        created = prepare_root(root, targets, settings.assets_dir)
        lock = lock_folder(root)
        try:
            return _compile_locked(compile_run, created)
        finally:
            lock.release()
    except PrscError as error:
        raise _at_object(error, program) from None


def _job(run: _Run, root: Path, assets: str | None) -> Job:
    """The workers' job for this run, writing under `root` (shared files in `assets`, default root/assets)."""
    return Job(spec=run.file, seed=run.seed, targets=run.targets, root=str(root), width=run.width, scenes=run.scenes,
               include_dirs=run.options.include_dirs, sources=run.sources_digest,
               meshes_anywhere=run.options.meshes_anywhere, law=run.options.law, proposal=run.options.proposal,
               assets=assets, _sampler=run.sampler)


def _first_to_render(run: _Run) -> int | None:
    """The first scene this run will write (a re-run skips those its folder's manifest lists), or None."""
    try:
        manifest, entries = load_manifest(run.root)
    except PrscError:
        return 0 if run.n else None  # the run proper reports the manifest under the folder's lock
    same = manifest is not None and (manifest.get("spec_sha256"), manifest.get("sources_sha256"),
                                      manifest.get("seed")) == (run.spec_digest, run.sources_digest, run.seed)
    done = entries if same else {}
    return next((k for k in range(min(run.n, len(done) + 1)) if set(run.targets) - set(done.get(k, {}))), None)


def _preflight(run: _Run, index: int) -> None:
    """Render one scene in every target into a scratch folder outside the output, and discard
    it: what fails for every scene (paths, names, limits) fails here, before any write."""
    import tempfile

    with tempfile.TemporaryDirectory(prefix="prsc-preflight-") as scratch:
        root = Path(scratch) / run.root.name
        prepare_root(root, run.targets)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # the run proper warns again, once
                render_one(_job(run, root, None), index)
        except PrscError as error:  # named where the run would have written
            raise PrscError(error.message.replace(str(root), str(run.root)), error.span, error.notes,
                            error.obj) from None


def _at_object(error: PrscError, program: Any) -> PrscError:
    """A backend's error about an object, at the object's line in the spec (when there is one)."""
    if error.span is not None or error.obj is None or program is None:
        return error
    decl = next((o for o in program.objects if o.name == error.obj), None)
    return error if decl is None else PrscError(error.message, decl.span, error.notes)


def _undo_start(root: Path, created: list[Path], wrote_manifest: bool) -> None:
    """Leave the folder as it was before a run that finished no scene: remove the manifest
    this run wrote and the folders it created (everything in them is this run's)."""
    if wrote_manifest:
        (root / MANIFEST).unlink(missing_ok=True)
    for folder in created:
        shutil.rmtree(folder, ignore_errors=True)


def _compile_locked(run: _Run, created: list[Path]) -> Path:
    """The part of compile_scenes that runs while this process holds the folder's lock."""
    from prsc.files import remove_stale_temporaries

    root, targets, n, settings = run.root, run.targets, run.n, run.options
    remove_stale_temporaries(root, recursive=True)
    manifest, entries = load_manifest(root)
    if manifest is not None and (
        manifest.get("spec_sha256") != run.spec_digest or manifest.get("sources_sha256") != run.sources_digest
        or manifest.get("seed") != run.seed
    ):
        if entries and not settings.force:
            was = f"seed {manifest.get('seed')!r} of {manifest.get('spec', 'another spec')}"
            raise PrscError(f"{root} holds {len(entries)} scenes of another spec, imported file, seed, law or "
                            f"proposal ({was}); pass --force to replace them, or choose another output folder")
        remove_listed(root, entries)
        manifest, entries = None, {}
    had_manifest = (root / MANIFEST).exists()
    job = replace(_job(run, root, settings.assets_dir), adopt_unlisted=manifest is not None)
    listed = Listed({k: dict(v) for k, v in entries.items()})

    def todo() -> Iterable[int]:
        # Lazy: -n 10**12 neither builds a list nor checks a file before the first scene.
        return (k for k in range(n) if not all(listed(k, t) and (root / job.relative(t, k)).exists() for t in targets))

    from prsc.backends.bodies import reset_model_warnings

    reset_model_warnings()  # once per class per run, also in workers forked below
    seen_warnings: set[str] = set()
    todo_list = list(todo()) if n <= 100_000 else None  # walked once: a progress total when cheap to count
    total = len(todo_list or ())
    bar = progress_bar(total)
    task = bar.add_task("compile", total=total) if bar else None
    next_checkpoint = [time.monotonic() + CHECKPOINT_SECONDS]
    spec = Path(run.file).absolute()

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
            write_manifest(root, manifest_now())
            # A huge manifest is rewritten less often: at most 5 % of the run goes to it.
            next_checkpoint[0] = time.monotonic() + max(CHECKPOINT_SECONDS, 20 * (time.monotonic() - started))

    def manifest_now() -> dict:
        return {
            "format": MANIFEST_FORMAT,
            "version": 1,
            # Relative to this folder, so a moved dataset still finds its spec; and absolute.
            "spec": os.path.relpath(spec, root.absolute()),
            "spec_path": str(spec),
            "spec_sha256": run.spec_digest,
            "sources_sha256": run.sources_digest,
            "seed": run.seed,
            "scenes": [{"index": k, "files": dict(sorted(entries[k].items()))} for k in sorted(entries) if entries[k]],
        }

    # Written first too: a re-run after an interruption then knows whose files these are.
    write_manifest(root, manifest_now())
    executor = settings.executor
    try:
        if bar:
            bar.start()
        pending = iter(todo_list if todo_list is not None else todo())
        executor = executor or LocalExecutor(settings.jobs, start="fork")
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
        # Local workers have been stopped and joined (and this folder's lock keeps other runs
        # out), so no writer is left to lock a fresh temporary: remove them whatever their
        # age. Ray cancels its tasks without waiting, so there the usual age applies.
        joined = isinstance(executor, LocalExecutor)
        remove_stale_temporaries(root, recursive=True, **({"min_age": 0} if joined else {}))
        if not any(entries.values()) and not (root / JOURNAL).exists():
            _undo_start(root, created, wrote_manifest=not had_manifest)  # a failed first run leaves nothing
            raise
        try:  # best effort: record the scenes that were completed (the journal keeps them otherwise)
            close_manifest(root, entries, manifest_now)
        except PrscError:
            pass
        raise
    finally:
        if bar:
            bar.stop()
    close_manifest(root, entries, manifest_now)
    return root


def run(args: argparse.Namespace) -> int:
    """Entry point of `prsc compile`."""
    targets = list(dict.fromkeys(t.strip() for t in str(args.target).split(",") if t.strip()))
    jobs = worker_count(args.jobs)
    executor = executor_from_arguments(args, jobs, start="fork")
    settle_targets(targets, args.settle_check)
    root = compile_scenes(args.file, targets, args.scenes, args.seed, args.output, jobs=jobs, include_dirs=args.include,
                          executor=executor, force=args.force, meshes_anywhere=args.meshes_anywhere,
                          proposal=read_proposal(args.proposal, args.file), law=args.law)
    return settle_check(root, args.scenes, Path(args.file).suffix in (".json", ".jsonl")) if args.settle_check else 0
