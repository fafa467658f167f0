"""One campaign path for `prsc run`, `prsc falsify` and `prsc bench --episodes`: episodes as
tasks over a compiled folder, one executor call that turns worker faults into errors, and
one resume format.

The format: OUT/campaign.json says what the campaign is (command, spec and controller
hashes, seed, limits); OUT/results.jsonl holds one line per finished episode, appended and
flushed the moment it finishes, so a kill loses none. A re-run of the same campaign keeps
those episodes and runs the others; at the end the file is rewritten in index order, as
an uninterrupted run writes it.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Callable, Iterable

from prsc.errors import PrscError

RESULTS = "results.jsonl"
CAMPAIGN = "campaign.json"


def episode_tasks(root: Path, indices: Iterable[int] | None, seed: int, controller: Any, max_sim_seconds: float,
                  first: int = 0) -> tuple[list[Any], list[dict]]:
    """(EpisodeTask per compiled scene of `root`, the scenes), numbered from `first`, in index order."""
    from prsc.runner.episode_records import EpisodeTask
    from prsc.pipeline.output_folder import compiled_scenes

    tasks, scenes = [], []
    for k, (_, scene_path, mjcf) in enumerate(compiled_scenes(root, indices)):
        scene = json.loads(scene_path.read_text(encoding="utf-8"))
        tasks.append(EpisodeTask(first + k, scene, str(mjcf), int(scene.get("seed", seed)), controller, max_sim_seconds))
        scenes.append(scene)
    return tasks, scenes


def _line(record: dict) -> str:
    return json.dumps(record, separators=(", ", ": "))


class Results:
    """A campaign's OUT/campaign.json and OUT/results.jsonl."""

    def __init__(self, out: Path, key: dict) -> None:
        self.out = Path(out)
        self.key = key
        self.records: dict[int, dict] = {}
        self._file: Any = None

    @property
    def path(self) -> Path:
        """The results file."""
        return self.out / RESULTS

    def stored_key(self) -> dict | None:
        """What campaign the folder holds (None when no readable campaign.json)."""
        try:
            stored = json.loads((self.out / CAMPAIGN).read_text(encoding="utf-8"))
        except (OSError, ValueError):
            return None
        return stored if isinstance(stored, dict) else None

    def recorded(self) -> dict[int, dict]:
        """Episodes already finished in the folder by this same campaign, by index (a torn last line is dropped)."""
        if self.stored_key() != self.key or not self.path.is_file():
            return {}
        done: dict[int, dict] = {}
        for line in self.path.read_text(encoding="utf-8", errors="replace").splitlines():
            try:
                record = json.loads(line)
                done[int(record["index"])] = record
            except (ValueError, KeyError, TypeError):
                continue  # the line a kill cut short
        return done

    def begin(self, kept: dict[int, dict]) -> None:
        """Start (or continue) the campaign with the `kept` episodes, in index order. A campaign
        with none writes its files with its first episode: one that fails before leaves none."""
        self.records = dict(kept)
        if kept:
            self._open()

    def _open(self) -> None:
        """Write campaign.json and the recorded episodes, and open the results file to append."""
        from prsc.files import atomic_write

        self.out.mkdir(parents=True, exist_ok=True)
        atomic_write(self.out / CAMPAIGN, json.dumps(self.key, indent=1) + "\n")
        atomic_write(self.path, "".join(_line(self.records[k]) + "\n" for k in sorted(self.records)))
        self._file = open(self.path, "a", encoding="utf-8")

    def add(self, record: dict) -> None:
        """Append one finished episode at once (flushed)."""
        if self._file is None:
            self._open()
        self.records[int(record["index"])] = record
        try:
            self._file.write(_line(record) + "\n")
            self._file.flush()
        except OSError as error:
            from prsc.pipeline.outputs import write_error

            raise write_error(error, self.path) from None

    def finish(self) -> list[dict]:
        """Close, rewrite the file in index order and return the episodes in that order."""
        from prsc.files import atomic_write

        self.close()
        ordered = [self.records[k] for k in sorted(self.records)]
        self.out.mkdir(parents=True, exist_ok=True)
        atomic_write(self.out / CAMPAIGN, json.dumps(self.key, indent=1) + "\n")
        atomic_write(self.path, "".join(_line(r) + "\n" for r in ordered))
        return ordered

    def close(self) -> None:
        """Close the file (a failed run leaves every finished episode in it)."""
        if self._file is not None:
            self._file.close()
            self._file = None


def run_episodes(executor: Any, config: Any, tasks: list[Any], on_record: Callable[[dict], None],
                 extras: Callable[[int], dict] | None = None,
                 on_recording: Callable[[int, Any], None] | None = None) -> None:
    """Run the tasks on `executor`; each finished episode's record (plus `extras(index)`) goes to
    `on_record` as it finishes, and its recording (when the config records) to `on_recording`.
    A worker's infrastructure fault stops the campaign."""
    from prsc.runner.worker import run_task

    def finished(answer: tuple) -> None:
        status, value = answer[:2]
        if status == "fault":
            from prsc.runner.faults import InfrastructureError

            raise InfrastructureError(value)
        record = value.to_json()
        if extras is not None:
            record.update(extras(record["index"]))
        on_record(record)
        if on_recording is not None and len(answer) > 2:
            on_recording(record["index"], answer[2])

    executor.map(run_task, config, tasks, finished)


def refuse_foreign_results(out: Path, command: str, force: bool) -> None:
    """A results.jsonl another command (or nothing of prsc's) wrote is never replaced without --force."""
    results = Results(out, {})
    if results.path.exists() and not force:
        stored = results.stored_key() or {}
        if stored.get("command") != command:
            raise PrscError(f"{out} holds a results.jsonl that prsc {command} did not write; "
                            "choose another output folder, or pass --force to replace it")
