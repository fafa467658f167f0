"""Ray as a user starts it (docs/ray.md): a local multi-node cluster (`ray.cluster_utils.Cluster`:
a head without CPUs, worker nodes of one CPU), no MUJOCO_GL in any node's environment nor in
the driver's, and `prsc run --executor ray --address ...` run as a user runs it, a process of
its own. A worker node killed mid-campaign loses no episode; a cluster left without CPUs is
reported and given up on; a campaign that fails before its first episode leaves nothing.

Small on purpose (`make test` runs it): episodes of a controller that steps 0.2 s, renders a
camera image (GL on the node) and sleeps 0.5 s of wall time, so a kill lands mid-campaign while
costing little CPU."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import threading
import time
from contextlib import contextmanager
from pathlib import Path

import pytest

ray = pytest.importorskip("ray", reason="Ray is not installed (make setup installs it: pip install -e '.[dev,ray]')")
from ray.cluster_utils import Cluster  # noqa: E402

pytestmark = pytest.mark.cluster  # make test-cluster; CI runs it after make test

REPO = Path(__file__).resolve().parents[2]
CUBES = REPO / "tests" / "data" / "three_cubes.prs"
GL = ("MUJOCO_GL", "PYOPENGL_PLATFORM")
STORE = 80 * 1024 * 1024
EPISODES = 6
SLOW = '''
import time

import mujoco

from prsc.runner.rendering import OffscreenRenderer


def steady(scene, model, data):
    while data.time < 0.2:
        mujoco.mj_step(model, data)
    image = OffscreenRenderer(model, 32, 32).rgb(data, mujoco.MjvCamera())  # a camera: GL on the node
    time.sleep(0.5)  # wall time, not CPU: a kill lands mid-campaign
    cube = model.body("a").id
    return {"outcome": "success", "reason": "", "height": round(float(data.xpos[cube][2]), 6),
            "image": list(image.shape)}
'''


@contextmanager
def _without_gl():
    """This process's environment without MUJOCO_GL, as a fresh shell's (and `ray start`'s)."""
    saved = {name: os.environ.pop(name) for name in GL if name in os.environ}
    try:
        yield
    finally:
        os.environ.update(saved)


@pytest.fixture(scope="module")
def cluster():
    """A head node without CPUs; each test adds the worker nodes it kills."""
    with _without_gl():
        # A killed node is found dead after 3 missed health checks 0.5 s apart (Ray's default: 5 of 3 s).
        made = Cluster(initialize_head=True, head_node_args={
            "num_cpus": 0, "object_store_memory": STORE,
            "_system_config": {"health_check_period_ms": 500, "health_check_failure_threshold": 3}})
    yield made
    made.shutdown()


def _add_node(cluster: Cluster):
    with _without_gl():
        return cluster.add_node(num_cpus=1, object_store_memory=STORE)


@pytest.fixture(scope="module")
def controller(tmp_path_factory) -> str:
    path = tmp_path_factory.mktemp("controller") / "steady.py"
    path.write_text(SLOW)
    return f"{path}:steady"


def _command(controller: str, out: Path, *extra: str, source: Path = CUBES) -> list[str]:
    return [sys.executable, "-m", "prsc.cli", "run", str(source), "-I", str(REPO / "specs"), "-n", str(EPISODES),
            "--controller", controller, "-o", str(out), *extra]


def _records(path: Path) -> list[dict]:
    return [{k: v for k, v in json.loads(line).items() if k != "wall_seconds"} for line in path.read_text().splitlines()]


@pytest.fixture(scope="module")
def local_run(controller, tmp_path_factory) -> Path:
    """The campaign run locally: its output folder."""
    out = tmp_path_factory.mktemp("local") / "out"
    done = subprocess.run(_command(controller, out, "--jobs", "2"), capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    return out


@pytest.fixture(scope="module")
def local_records(local_run) -> list[dict]:
    return _records(local_run / "results.jsonl")


class _Run:
    """`prsc run` on the cluster in a process of its own, its stderr read as it comes (with times)."""

    def __init__(self, command: list[str], env: dict[str, str] | None = None) -> None:
        environment = {k: v for k, v in os.environ.items() if k not in GL}
        self.process = subprocess.Popen(command, env={**environment, **(env or {})}, stderr=subprocess.PIPE, text=True)
        self.lines: list[tuple[float, str]] = []
        self.reader = threading.Thread(target=self._read, daemon=True)
        self.reader.start()

    def _read(self) -> None:
        for line in self.process.stderr:
            self.lines.append((time.monotonic(), line))

    def wait_for_records(self, path: Path, count: int, timeout: float = 240) -> int:
        """Wait until `path` holds `count` episodes (or the run ends); how many it holds."""
        end = time.monotonic() + timeout
        while time.monotonic() < end and self.process.poll() is None:
            if path.is_file() and path.read_text().count("\n") >= count:
                break
            time.sleep(0.1)
        return path.read_text().count("\n") if path.is_file() else 0

    def finish(self, timeout: float = 240) -> tuple[int, str]:
        code = self.process.wait(timeout=timeout)
        self.reader.join(timeout=10)
        return code, "".join(line for _, line in self.lines)


def test_a_node_killed_mid_campaign_loses_no_episode(cluster, controller, local_records, tmp_path):
    """Two worker nodes; one killed after two episodes: every episode recorded once, in index
    order, each equal to the local run's; the summary gives the cluster's CPUs."""
    first, second = _add_node(cluster), _add_node(cluster)
    try:
        out = tmp_path / "out"
        run = _Run(_command(controller, out, "--executor", "ray", "--address", cluster.address))
        recorded = run.wait_for_records(out / "results.jsonl", 2)
        assert run.process.poll() is None and 2 <= recorded < EPISODES, "the node must die mid-campaign"
        cluster.remove_node(first, allow_graceful=False)
        code, stderr = run.finish()
        assert code == 0, stderr
        records = _records(out / "results.jsonl")
        assert [r["index"] for r in records] == list(range(EPISODES))
        assert records == local_records
        assert "ray, 2 CPUs on 3 node(s)" in stderr
    finally:
        cluster.remove_node(second, allow_graceful=False)


def test_a_cluster_without_cpus_is_reported_and_given_up_on(cluster, controller, local_records, tmp_path):
    """The only worker node killed after one episode: prsc says what it waits for and what the
    cluster has within 30 s, gives up after --give-up-after with exit code 2, and keeps the
    episodes it finished."""
    node = _add_node(cluster)
    out = tmp_path / "out"
    run = _Run(_command(controller, out, "--executor", "ray", "--address", cluster.address, "--give-up-after", "4"))
    assert run.wait_for_records(out / "results.jsonl", 1) >= 1
    cluster.remove_node(node, allow_graceful=False)
    killed = time.monotonic()
    code, stderr = run.finish()
    assert code == 2, stderr
    noted = [at for at, line in run.lines if "waiting for the Ray cluster" in line]
    assert noted and noted[0] - killed < 30, stderr
    assert "need 1 CPU each, and it has 0 CPUs (0 free) on 1 node, " in stderr
    assert "gave up after waiting 4 s" in stderr and "Traceback" not in stderr
    records = _records(out / "results.jsonl")
    assert records and all(r == local_records[r["index"]] for r in records)
    assert len({r["index"] for r in records}) == len(records)


def test_a_failure_before_the_first_episode_leaves_nothing(cluster, controller, local_run, tmp_path):
    """On the cluster: scenes of which the second fails to compile there, and episodes whose GL
    backend cannot render (a MUJOCO_GL the nodes lack): exit code 2, and no output folder."""
    node = _add_node(cluster)
    try:
        first, broken = (json.loads((local_run / "three_cubes" / "json" / f"0000{k}.json").read_text()) for k in (0, 1))
        broken["objects"][1]["properties"] = {"texture": "nowhere.png"}  # found on the cluster, at scene 1
        (tmp_path / "scenes.jsonl").write_text(json.dumps(first) + "\n" + json.dumps(broken) + "\n")
        address = ["--executor", "ray", "--address", cluster.address]
        run = _Run(_command(controller, tmp_path / "bad_scene", *address, source=tmp_path / "scenes.jsonl"))
        code, stderr = run.finish()
        assert code == 2 and "nowhere.png" in stderr, stderr
        assert not (tmp_path / "bad_scene").exists()
        run = _Run(_command(controller, tmp_path / "no_gl", *address, "-n", "2"), env={"MUJOCO_GL": "glfw"})
        code, stderr = run.finish()
        assert code == 2 and "MUJOCO_GL='glfw'" in stderr, stderr
        assert not (tmp_path / "no_gl").exists()
    finally:
        cluster.remove_node(node, allow_graceful=False)
