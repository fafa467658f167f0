"""The Ray executor: a campaign's tasks on a Ray cluster, as `ray start` leaves it (docs/ray.md).

Workers get the driver's GL choice through Ray's runtime_env; a cluster with no CPU for the
tasks is said so, and given up on after `--give-up-after` seconds (exit code 2, work kept).
"""

from __future__ import annotations

import os
import sys
import uuid
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from prsc.errors import PrscError

_ray_shared: dict[str, Any] = {}  # per worker process: shared objects already fetched, by key

GIVE_UP_AFTER = 600.0
"""s: how long (--give-up-after) a Ray campaign waits while the cluster has no CPU for its tasks."""
NOTE_AFTER = 5.0  # s without a finished task and without a CPU on the cluster before prsc says so
POLL = 1.0  # s between looks at the cluster while tasks are pending


def _ray_call(fn: Callable[[Any, Any], Any], key: str, boxed: list, item: Any) -> Any:
    """A Ray task: fetch `shared` once per worker process (boxed, so Ray does not resolve it per task)."""
    if key not in _ray_shared:
        import ray

        _ray_shared.clear()  # one campaign at a time per worker
        _ray_shared[key] = ray.get(boxed[0])
    return fn(_ray_shared[key], item)


def import_ray():
    """Ray, or a PrscError saying how to install it."""
    try:
        import ray
    except ImportError:
        raise PrscError("--executor ray needs Ray: pip install 'prsc[ray]' (or pip install ray)") from None
    return ray


def _worker_environment() -> dict[str, str]:
    """The driver's GL choice (prsc.runner.gl), for every Ray worker of the job: a node started
    by `ray start` has no MUJOCO_GL, and MuJoCo reads it once, at its import, which a compile
    task may do before an episode task runs in the same worker process."""
    from prsc.runner.gl import GL_VARIABLES

    return {name: os.environ[name] for name in GL_VARIABLES if os.environ.get(name)}


@dataclass(frozen=True)
class ClusterState:
    """What a Ray cluster offers the campaign's tasks (each needs one CPU)."""

    cpus: float  # on live nodes
    free_cpus: float
    nodes: int  # live
    dead_nodes: int

    def describe(self) -> str:
        """`2 CPUs (1 free) on 3 nodes, 1 dead`."""
        dead = f", {self.dead_nodes} dead" if self.dead_nodes else ""
        return f"{self.cpus:g} CPU{'s' * (self.cpus != 1)} ({self.free_cpus:g} free) on {self.nodes} node{'s' * (self.nodes != 1)}{dead}"


def cluster_state(ray: Any) -> ClusterState:
    """The cluster's CPUs and nodes now."""
    nodes = ray.nodes()
    alive = [n for n in nodes if n.get("Alive")]
    cpus = sum(float(n.get("Resources", {}).get("CPU", 0.0)) for n in alive)
    return ClusterState(cpus, float(ray.available_resources().get("CPU", 0.0)), len(alive), len(nodes) - len(alive))


@dataclass(frozen=True)
class RayExecutor:
    """One Ray task per item, on the cluster at `address` (None: a local cluster of `cpus` CPUs started
    here, kept for the next map and stopped when this process exits; a Ray session already open in
    this process is used as it is). While the cluster has no CPU for the tasks, prsc says so after
    NOTE_AFTER s and gives up after `give_up_after` s (a PrscError: exit code 2); results already
    handed to `on_result` stay with the caller."""

    address: str | None = None
    cpus: int | None = None
    give_up_after: float = GIVE_UP_AFTER
    seen: dict = field(default_factory=dict, compare=False)  # the cluster's state at the last map: for the summary

    def summary(self) -> str:
        """Where the items ran, for a command's summary line."""
        state = self.seen.get("state")
        return f"ray, {state.cpus:g} CPUs on {state.nodes} node(s)" if state else "ray"

    def _connect(self, ray: Any) -> None:
        if ray.is_initialized():
            return
        runtime_env = {"env_vars": _worker_environment()}
        try:
            if self.address:
                ray.init(address=self.address, log_to_driver=False, runtime_env=runtime_env)
            else:
                # "local": a cluster of its own, even where `ray start` (or another prsc) runs one
                # on this machine, which ray.init would otherwise join (and refuse num_cpus).
                ray.init(address="local", num_cpus=self.cpus or os.cpu_count(), include_dashboard=False,
                         log_to_driver=False, runtime_env=runtime_env)
        except Exception as error:  # ConnectionError, TimeoutError, RuntimeError... all mean "no cluster"
            raise PrscError(f"cannot start or reach a Ray cluster{f' at {self.address}' if self.address else ''}: "
                            f"{type(error).__name__}: {error}") from None

    def map(self, fn, shared, items, on_result=None):
        """Submit every item as a task; collect results as they finish; return them in item order."""
        import time

        ray = import_ray()
        items = list(items)
        self._connect(ray)
        self.seen["state"] = cluster_state(ray)
        remote = ray.remote(num_cpus=1)(_ray_call)
        boxed = [ray.put(shared)]
        key = uuid.uuid4().hex
        pending = {remote.remote(fn, key, boxed, item): k for k, item in enumerate(items)}
        results: list[Any] = [None] * len(items)
        starved_since: float | None = None  # when the cluster was last seen with no CPU for the tasks
        noted = False
        last_result = time.monotonic()
        try:
            while pending:
                done, _ = ray.wait(list(pending), num_returns=1, timeout=POLL)
                for ref in done:
                    number = pending.pop(ref)
                    results[number] = ray.get(ref)
                    last_result = time.monotonic()
                    if on_result is not None:
                        on_result(results[number])
                if done or time.monotonic() - last_result < NOTE_AFTER:
                    continue
                state = cluster_state(ray)
                self.seen["state"] = state
                now = time.monotonic()
                if state.cpus >= 1:
                    if noted:
                        sys.stderr.write(f"prsc: the Ray cluster has {state.describe()} again; continuing\n")
                    starved_since, noted = None, False
                    continue
                starved_since = starved_since or now
                if not noted:
                    sys.stderr.write(f"prsc: waiting for the Ray cluster: {len(pending)} task(s) need 1 CPU each, "
                                     f"and it has {state.describe()}; giving up after {self.give_up_after:g} s "
                                     "(--give-up-after)\n")
                    noted = True
                if now - starved_since >= self.give_up_after:
                    raise PrscError(f"gave up after waiting {self.give_up_after:g} s for the Ray cluster"
                                    f"{f' at {self.address}' if self.address else ''}: {len(pending)} task(s) need "
                                    f"1 CPU each, and it has {state.describe()}; add a node with CPUs, or pass a "
                                    "longer --give-up-after")
        except BaseException:
            for ref in pending:
                ray.cancel(ref, force=True)
            raise
        return results
