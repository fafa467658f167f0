"""One scene of a compile run, as a worker renders it: the job (source, targets, layout) and
the rendering and writing of a scene's files, each recorded the moment it is in place."""

from __future__ import annotations

import shutil
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

from prsc.pipeline.output_folder import MANIFEST, record_files, task_key
from prsc.pipeline.outputs import write_error
from prsc.pipeline.scene_sources import spec_sampler
from prsc.errors import PrscError
from prsc.task.terms import TASK_FILE, TASK_SUFFIX


# ------------------------------------------------------------------ jobs


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
    law: str | None = None  # --law: the law a worker compiling the spec again samples
    proposal: dict | None = None  # --proposal: a falsification proposal's JSON (prsc/sampling/proposal.py)
    assets: str | None = None  # the shared files' folder, when not `root/assets` (falsify's rounds share one)
    _sampler: Callable[[int], dict] | None = field(default=None, repr=False)

    def scene(self, index: int) -> dict:
        """Scene JSON of scene `index`."""
        if self.scenes is not None:
            return self.scenes[index]
        if self._sampler is None:
            self._sampler = spec_sampler(self.spec, self.seed, self.include_dirs, self.law, self.proposal)
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

    def task_relative(self, target: str, index: int) -> str | None:
        """Path of a scene's task file beside its output for one target, or None when the output
        holds the task itself (the scene JSON, a bundle's task.json)."""
        from prsc.backends import TARGETS

        return None if TARGETS[target].task_inside else f"{target}/{index:0{self.width}d}{TASK_SUFFIX}"


# ------------------------------------------------------------------ one scene

def task_json(scene: dict) -> str | None:
    """The scene's compiled task as the text of task.json, or None when the spec states no task."""
    import json

    task = scene.get("task")
    return None if task is None else json.dumps(task, indent=1, allow_nan=False) + "\n"



def render_one(job: Job, index: int, listed: Callable[[int, str], bool] = lambda index, target: False
               ) -> tuple[int, dict[str, str], list[str]]:
    """Render and write the outputs of one scene that `listed` does not already record.

    Returns its files and warnings; each file is journalled as soon as it is in place."""
    from prsc.backends import TARGETS
    from prsc.backends.scene import parse_scene
    from prsc.backends.store import AssetStore
    from prsc.files import atomic_write, atomic_write_tree

    root = Path(job.root)
    store = AssetStore(Path(job.assets) if job.assets else root / "assets", job.include_dirs, job.meshes_anywhere)
    files: dict[str, str] = {}
    missing = []
    for target in job.targets:
        rel = job.relative(target, index)
        files[target] = rel
        if listed(index, target) and (root / rel).exists():
            continue
        _refuse_unlisted(job, root, rel)
        missing.append(target)
    messages: list[str] = []
    if not missing:
        return index, files, messages
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scene_data = job.scene(index)
        scene = parse_scene(scene_data)
        task = task_json(scene_data)
        tasks = {t: job.task_relative(t, index) if task is not None else None for t in missing}
        for rel in tasks.values():
            if rel is not None:
                _refuse_unlisted(job, root, rel)
        for target in missing:
            path = root / files[target]
            try:
                data = TARGETS[target].render()(scene, path, store)
            except OSError as error:
                raise write_error(error, path) from None
            # The compiled task (docs/tasks.md): a bundle holds it as task.json (in place with the
            # bundle, whole or not at all); a file target's task file is renamed into place first
            # and journalled with the scene's file in one line.
            written = {target: files[target]}
            if tasks[target] is not None:
                written = {task_key(target): tasks[target], **written}
            placed: list[Path] = []
            current = path
            try:
                for key, rel in written.items():
                    current = root / rel
                    if key == target and TARGETS[target].bundle:
                        atomic_write_tree(current, {**data, TASK_FILE: task} if task is not None else data)
                    else:
                        atomic_write(current, task if key != target else data)
                    placed.append(current)
                current = path  # a journal that cannot take the line fails the scene's output
                record_files(root, index, written)
            except OSError as error:
                for done in placed:  # in place but not recorded: this run just wrote them, so they go
                    _remove_written(done)
                raise write_error(error, current) from None
            files.update(written)
    from prsc.backends.bodies import UnknownModelWarning

    for w in caught:  # others (e.g. MuJoCo's mesh decoder) go back to Python's filters
        if not issubclass(w.category, UnknownModelWarning):
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    messages = [str(w.message) for w in caught if issubclass(w.category, UnknownModelWarning)]
    return index, files, messages


def _refuse_unlisted(job: Job, root: Path, rel: str) -> None:
    """A file at one of this run's names that prsc did not write (the manifest is not this run's) stops it."""
    if (root / rel).exists() and not job.adopt_unlisted:
        raise PrscError(f"{root / rel} exists and is not listed in {root / MANIFEST}: prsc did not write it "
                        "and will not replace it; move it away or choose another output folder")


def _remove_written(path: Path) -> None:
    """Remove an output this process has just put in place (a file or a bundle folder)."""
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path, ignore_errors=True)
    else:
        path.unlink(missing_ok=True)


# ------------------------------------------------------------------ workers
# Scene indices on an executor's workers (prsc.pipeline.executors), apart from the output
# folder's bookkeeping.

def worker_render(shared: tuple[Job, Callable[[int, str], bool]], index: int) -> tuple[str, Any]:
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
