"""`--executor ray` on a local Ray cluster the tests start: the same files and results as local processes."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

from prsc.cli import main

ray = pytest.importorskip("ray", reason="Ray is not installed (make setup installs it: pip install -e '.[dev,ray]')")

REPO = Path(__file__).resolve().parents[2]
CUBES = REPO / "tests" / "data" / "three_cubes.prs"
INCLUDE = ["-I", str(REPO / "specs")]


@pytest.fixture(scope="module")
def cluster():
    """A two-CPU local Ray cluster for this module's tests, shut down after them."""
    # address "local": its own cluster, never one another test file (test_ray_nodes.py) runs meanwhile
    ray.init(address="local", num_cpus=2, include_dashboard=False, object_store_memory=80 * 1024 * 1024,
             log_to_driver=False, configure_logging=False)
    yield ray.get_runtime_context().gcs_address
    ray.shutdown()


def _records(path: Path) -> list[dict]:
    return [{k: v for k, v in json.loads(line).items() if k != "wall_seconds"} for line in path.read_text().splitlines()]


def _tree(root: Path) -> dict[str, bytes]:
    return {str(p.relative_to(root)): p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()}


def test_a_campaign_on_ray_matches_the_local_one(cluster, stay_put, tmp_path):
    common = [str(CUBES), *INCLUDE, "-n", "6", "--controller", stay_put]
    assert main(["run", *common, "-o", str(tmp_path / "local"), "--jobs", "2"]) == 0
    assert main(["run", *common, "-o", str(tmp_path / "ray"), "--executor", "ray", "--address", cluster]) == 0
    local, on_ray = _records(tmp_path / "local" / "results.jsonl"), _records(tmp_path / "ray" / "results.jsonl")
    assert [r["index"] for r in on_ray] == list(range(6))
    assert on_ray == local
    assert {r["outcome"] for r in on_ray} == {"still"}
    assert _tree(tmp_path / "ray" / "three_cubes") == _tree(tmp_path / "local" / "three_cubes")


def test_compile_on_ray_writes_the_same_files(cluster, tmp_path):
    common = [str(REPO / "specs" / "table_cube.prs"), "--target", "json,mjcf,urdf", "-n", "5", "--seed", "3"]
    assert main(["compile", *common, "-o", str(tmp_path / "local")]) == 0
    assert main(["compile", *common, "-o", str(tmp_path / "ray"), "--executor", "ray"]) == 0
    local, on_ray = _tree(tmp_path / "local"), _tree(tmp_path / "ray")
    assert len(local) > 10 and on_ray == local


def test_executor_ray_without_ray_is_a_clear_error(tmp_path, monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "ray", None)  # as if Ray were not installed
    assert main(["compile", str(CUBES), *INCLUDE, "-o", str(tmp_path / "out"), "--executor", "ray"]) == 2
    assert "--executor ray needs Ray: pip install 'prsc[ray]'" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_falsify_on_ray_matches_the_local_one(cluster, tmp_path):
    corner = str(REPO / "tests" / "data" / "corner_controller.py") + ":corner"
    common = [str(REPO / "specs" / "table_cube.prs"), "--budget", "6", "--rounds", "2", "--seed", "1", "--controller", corner]
    assert main(["falsify", *common, "-o", str(tmp_path / "local"), "--jobs", "2"]) == 0
    assert main(["falsify", *common, "-o", str(tmp_path / "ray"), "--executor", "ray", "--address", cluster]) == 0
    assert _records(tmp_path / "local" / "results.jsonl") == _records(tmp_path / "ray" / "results.jsonl")
    assert (tmp_path / "local" / "proposal.json").read_bytes() == (tmp_path / "ray" / "proposal.json").read_bytes()
