"""Where a command's per-scene work runs: this machine's processes or a Ray cluster.

`executor.map(fn, shared, items, on_result)` calls `fn(shared, item)` for every item and
returns the results in item order; `on_result(result)` sees each as soon as it finishes
(in completion order). `fn` must be a module-level function (workers import it by name);
`shared` is sent to each worker once, not with every item. A worker keeps its process
between items, so it may cache what it builds (GL contexts, compiled IK models). Items may
be a lazy iterable of any length: local workers are handed bounded batches of it.
"""

from __future__ import annotations

import itertools
import multiprocessing
import os
import signal
import sys
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any, Protocol

from prsc.errors import PrscError
from prsc.pipeline.ray_executor import GIVE_UP_AFTER, NOTE_AFTER, RayExecutor, import_ray

EXECUTORS = ("local", "ray")


class Executor(Protocol):
    """Runs `fn(shared, item)` over items; results in item order."""

    def map(self, fn: Callable[[Any, Any], Any], shared: Any, items: Iterable[Any],
            on_result: Callable[[Any], None] | None = None) -> list[Any]: ...

    def summary(self) -> str: ...


def cpu_seconds() -> float:
    """CPU time (user + system) of this process and its finished children (local workers only)."""
    import resource

    own, children = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


def worker_count(jobs: int) -> int:
    """--jobs, capped at the cores this process may use (with a note when capped)."""
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # not Linux
        cores = os.cpu_count() or 1
    if jobs > cores:
        sys.stderr.write(f"prsc: note: --jobs {jobs} is more than the {cores} cores available; using {cores}\n")
        return cores
    return jobs


# ------------------------------------------------------------------ local processes

BATCH_PER_WORKER = 32  # items handed out per worker and batch: what is pending stays bounded


def _die_with_parent(parent: int) -> None:
    """Have the kernel kill this worker when its parent dies (Linux), so none writes on after a kill -9."""
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        PR_SET_PDEATHSIG = 1
        libc.prctl(PR_SET_PDEATHSIG, signal.SIGKILL)
    except (OSError, AttributeError):  # not Linux: the parent's own shutdown still applies
        pass
    if os.getppid() != parent:  # the parent died before prctl took effect
        os._exit(1)


def _worker_main(connection: Any, fn: Callable[[Any, Any], Any], shared: Any, parent: int) -> None:
    """A local worker: chunks of (number, item) in, [(number, result)] or ("error", exception) out."""
    # Ctrl-C reaches the whole process group: the parent alone reports it and stops the workers.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    _die_with_parent(parent)
    while True:
        try:
            chunk = connection.recv()
        except EOFError:  # the parent closed its end: nothing more to do
            return
        if chunk is None:
            return
        try:
            answer: Any = ("ok", [(number, fn(shared, item)) for number, item in chunk])
        except BaseException as error:  # the parent raises it, as Pool did
            answer = ("error", error)
        try:
            connection.send(answer)
        except Exception as error:  # an exception or result that does not pickle
            connection.send(("error", PrscError(f"a worker's answer could not be sent back: {error}")))


class _Workers:
    """Local worker processes, each with a pipe of its own to the parent.

    No lock or queue is shared between workers (multiprocessing.Pool shares two): a worker
    killed anywhere, by the parent's stop or by the system, leaves nothing the others or
    the parent wait for. Pool.terminate() could wait forever for a queue lock that a worker
    it had just killed still held, and a compile then never ended after SIGTERM."""

    def __init__(self, context: Any, count: int, fn: Callable[[Any, Any], Any], shared: Any) -> None:
        self.processes: list[Any] = []
        self.connections: list[Any] = []
        for _ in range(count):
            mine, theirs = context.Pipe()
            process = context.Process(target=_worker_main, args=(theirs, fn, shared, os.getpid()), daemon=True)
            process.start()
            theirs.close()
            self.processes.append(process)
            self.connections.append(mine)

    def run(self, chunks: Iterable[list[tuple[int, Any]]], on_chunk: Callable[[list[tuple[int, Any]]], None],
            check: Callable[[], None]) -> None:
        """Hand each worker one chunk at a time until `chunks` run out; `on_chunk` sees each
        answer; `check` runs between answers (it may raise to stop)."""
        from multiprocessing.connection import wait

        pending = iter(chunks)
        busy: dict[Any, Any] = {}
        for connection, process in zip(self.connections, self.processes):
            chunk = next(pending, None)
            if chunk is None:
                break
            connection.send(chunk)
            busy[connection] = process
        while busy:
            check()
            for connection in wait(list(busy), timeout=SIGNAL_POLL):
                try:
                    kind, answer = connection.recv()
                except EOFError:
                    process = busy[connection]
                    process.join(timeout=1.0)
                    raise PrscError(f"a worker process ended unexpectedly (exit code {process.exitcode}); "
                                    "the system may have run out of memory") from None
                if kind == "error":
                    raise answer
                chunk = next(pending, None)
                if chunk is None:
                    del busy[connection]
                else:
                    connection.send(chunk)
                on_chunk(answer)

    def close(self) -> None:
        """Let every worker finish and end (their CPU time then counts as this process's children's)."""
        for connection in self.connections:
            try:
                connection.send(None)
            except OSError:
                pass
        for process in self.processes:
            process.join()
        for connection in self.connections:
            connection.close()

    def kill(self) -> None:
        """End every worker at once (SIGKILL): nothing of theirs can keep the parent waiting."""
        for process in self.processes:
            process.kill()
        for process in self.processes:
            process.join()
        for connection in self.connections:
            connection.close()


@dataclass(frozen=True)
class LocalExecutor:
    """`jobs` worker processes on this machine (none: in this process when jobs is 1).

    `start` is the multiprocessing start method: `fork` shares what the parent already
    built; `spawn` gives each worker a clean process (its own GL context)."""

    jobs: int = 1
    start: str = "spawn"

    def summary(self) -> str:
        """Where the items ran, for a command's summary line."""
        return f"{self.jobs} job(s), local"

    def map(self, fn, shared, items, on_result=None):
        """Run the items here (jobs 1) or in worker processes; results in item order."""
        pending = iter(items)
        batch = list(itertools.islice(pending, self.jobs * BATCH_PER_WORKER))
        if self.jobs <= 1 or len(batch) <= 1:
            results: list[Any] = []
            for item in itertools.chain(batch, pending):
                results.append(fn(shared, item))
                if on_result is not None:
                    on_result(results[-1])
            return results
        method = self.start if self.start in multiprocessing.get_all_start_methods() else "spawn"
        # One item per message for spawn (each may be a long episode); small chunks for fork.
        size = 1 if method == "spawn" else max(1, min(16, len(batch) // (self.jobs * 8)))
        numbered = enumerate(itertools.chain(batch, pending))
        chunks = iter(lambda: list(itertools.islice(numbered, size)), [])
        answers: dict[int, Any] = {}

        def record(chunk: list[tuple[int, Any]]) -> None:
            for number, result in chunk:
                answers[number] = result
                if on_result is not None:
                    on_result(result)

        with _DeferredSignals() as signals:
            workers = _Workers(multiprocessing.get_context(method), min(self.jobs, len(batch)), fn, shared)
            try:
                workers.run(chunks, record, signals.check)
            except BaseException:
                workers.kill()
                raise
            workers.close()
        return [answers[number] for number in range(len(answers))]


SIGNAL_POLL = 0.1  # s: how soon a deferred Ctrl-C or SIGTERM stops a local pool


class _DeferredSignals:
    """While local workers run, Ctrl-C and SIGTERM are noted, then acted on between results.

    Their handlers raise (KeyboardInterrupt, the CLI's Terminated); raised at an arbitrary
    point, in the middle of a message on a worker's pipe or between a lock's acquire and the
    block that releases it (bpo-29988), the exception could leave a message half sent or a
    lock held. Here the previous handler runs where nothing is in flight. Off the main thread
    signals cannot be set: nothing changes."""

    SIGNALS = (signal.SIGINT, signal.SIGTERM)

    def __init__(self) -> None:
        self.previous: dict[int, Any] = {}
        self.pending: list[int] = []

    def __enter__(self) -> "_DeferredSignals":
        try:
            for signum in self.SIGNALS:
                self.previous[signum] = signal.signal(signum, lambda number, frame: self.pending.append(number))
        except ValueError:  # not the main thread
            self.__exit__()
        return self

    def __exit__(self, kind: Any = None, *exc: Any) -> None:
        previous, self.previous = self.previous, {}
        for signum, handler in previous.items():
            signal.signal(signum, handler)
        if kind is None:  # a signal that came with the last result still counts
            self._act(previous)

    def check(self) -> None:
        """Run the handler a noted signal would have run (it raises), where it is safe."""
        self._act(self.previous)

    def _act(self, handlers: dict[int, Any]) -> None:
        if not (self.pending and handlers):
            return
        signum = self.pending.pop(0)
        handler = handlers[signum]
        if callable(handler):
            handler(signum, None)
        elif handler == signal.SIG_DFL:
            os.kill(os.getpid(), signum)  # its handler is back in place: the default action


def make_executor(kind: str, jobs: int = 1, address: str | None = None, start: str = "spawn",
                  give_up_after: float = GIVE_UP_AFTER) -> Executor:
    """The executor `--executor KIND [--address A] [--jobs J] [--give-up-after S]` asks for."""
    if kind not in EXECUTORS:
        raise PrscError(f"unknown executor {kind!r}; choose from {', '.join(EXECUTORS)}")
    if address and kind != "ray":
        raise PrscError("--address needs --executor ray")
    if not give_up_after > 0:
        raise PrscError(f"--give-up-after must be > 0, got {give_up_after:g}")
    if kind == "ray":
        import_ray()
        return RayExecutor(address=address, cpus=jobs if jobs > 1 else None, give_up_after=give_up_after)
    return LocalExecutor(jobs=jobs, start=start)


def executor_from_arguments(args: Any, jobs: int, start: str) -> Executor:
    """The executor a command's --executor, --address and --give-up-after ask for, with `jobs` workers."""
    return make_executor(args.executor, jobs, args.address, start=start, give_up_after=args.give_up_after)


def add_executor_arguments(parser: Any) -> None:
    """--executor, --address and --give-up-after, shared by `prsc run`, `prsc falsify` and `prsc compile`."""
    parser.add_argument("--executor", choices=EXECUTORS, default="local",
                        help="where scenes run: local worker processes (default) or a Ray cluster")
    parser.add_argument("--address", default=None, metavar="ADDR",
                        help="with --executor ray: an existing cluster (e.g. ray://head:10001 or auto); "
                             "default: start a local one")
    parser.add_argument("--give-up-after", type=float, default=GIVE_UP_AFTER, metavar="S",
                        help="with --executor ray: stop (exit code 2, finished work kept) when the cluster has had "
                             f"no CPU for the tasks for S seconds (default {GIVE_UP_AFTER:g}); prsc says so after "
                             f"{NOTE_AFTER:g} s")
