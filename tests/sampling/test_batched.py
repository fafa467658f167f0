"""Batched sampling (prsc/sampling/batched.py, docs/sampling.md "Batched sampling").

- Scene k of seed s is the same drawn alone, in any batch, at any offset, in any order,
  as a JSON line or a dict, from the library or `prsc sample`.
- The law is the sequential sampler's: per-coordinate two-sample KS tests at fixed seeds
  against `batched=False` on Table-Cube (the trays, the cube relative to its tray, the
  camera), and the same test rejects a law that picks simplices without their areas.
- The counter stream: uniform marginals and no correlation between neighbouring scenes
  or draw sites, where a Weyl sequence (no mixing) fails the same test.
- Specs whose objects interact, or whose regions change shape, are not batched, and say why.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.stats import kstest

from prsc.errors import PrscError
from prsc.geometry.uniform_sampling import UniformSampler
from prsc.ir import compile_program
from prsc.sampling import Sampler, compile_sampler
from prsc.sampling.counter_stream import scene_keys, uniforms
from prsc.sampling.mixing import ks_per_coordinate
from prsc.sampling.scene_text import scene_encoder

REPO = Path(__file__).resolve().parents[2]
SPEC = str(REPO / "specs" / "table_cube.prs")
P_MIN = 0.01  # every coordinate: KS p >= P_MIN for the right law; some p < P_MIN for the wrong one


@pytest.fixture(scope="module")
def sampler() -> Sampler:
    return compile_sampler(SPEC)


def test_table_cube_is_batched(sampler):
    assert sampler.batched, sampler.plan.why
    assert not compile_sampler(SPEC, batched=False).batched


def test_a_scene_is_the_same_alone_in_any_batch_at_any_offset_and_in_any_order(sampler):
    n = 2500  # more than two batches of sampler.BATCH
    forward = list(sampler.scenes(9, n))
    assert [s["index"] for s in forward] == list(range(n))
    assert len({json.dumps(s["objects"][3]["position"]) for s in forward}) == n  # the trays move
    for k in (0, 1, 1023, 1024, 2499):
        assert sampler.scene(9, k) == forward[k]
    shuffled = np.random.default_rng(0).permutation(n)
    assert sampler.batch(9, shuffled) == [forward[k] for k in shuffled]
    assert list(sampler.scenes(9, 7, start=1020)) == forward[1020:1027]
    assert sampler.batch(9, range(1500, 1503)) == forward[1500:1503]
    assert sampler.scene(10, 0) != forward[0]


def test_the_json_lines_are_the_encoder_s_text_of_the_scenes(sampler):
    encode = scene_encoder()
    indices = [3, 0, 1030, 7]
    assert sampler.batch_lines(5, indices) == [encode(s) + "\n" for s in sampler.batch(5, indices)]
    out = subprocess.run(
        [sys.executable, "-m", "prsc.cli", "sample", SPEC, "-n", "40", "--start", "1000", "--seed", "5"],
        capture_output=True, text=True, check=True,
    ).stdout
    assert out == "".join(encode(sampler.scene(5, k)) + "\n" for k in range(1000, 1040))


def test_one_scene_as_a_sample_result_carries_its_draws_for_explain(sampler):
    result = sampler.sample(2, 11)
    scene = sampler.scene(2, 11)
    assert [o.position.tolist() for o in result.objects] == [o["position"] for o in scene["objects"]]
    assert result.stats.total == 0
    # The camera's `at` reads three ranges: the context memoises them as drawn.
    camera = result.objects[-1].position
    assert result.context is not None and len(result.context.draws) == 3
    assert sorted(result.context.draws.values()) == pytest.approx(sorted([camera[0], camera[1], camera[2]]))


def test_a_seed_or_index_out_of_range_is_an_error(sampler):
    for seed, index in ((-1, 0), (2 ** 64, 0), (0, -3), (True, 0)):
        with pytest.raises(PrscError):
            sampler.scene(seed, index)
    with pytest.raises(PrscError):
        sampler.batch(0, np.array([1, -2]))


def _coordinates(scenes: list[dict]) -> np.ndarray:
    """Per scene: tr_1 (x, y), tr_2 (x, y), c1 relative to tr_1 (x, y), camera (x, y, z)."""
    rows = []
    for scene in scenes:
        p = {o["name"]: np.array(o["position"]) for o in scene["objects"]}
        rows.append([*p["tr_1"][:2], *p["tr_2"][:2], *(p["c1"] - p["tr_1"])[:2], *p["camera"]])
    return np.array(rows)


@pytest.fixture(scope="module")
def reference() -> np.ndarray:
    """The sequential sampler's law, one scene at a time from per-scene Generators."""
    one_at_a_time = compile_sampler(SPEC, batched=False, law="sequential")
    return _coordinates([one_at_a_time.scene(31, k) for k in range(1500)])


def test_the_batched_law_is_the_sequential_sampler_s(sampler, reference):
    p = [p for _, p in ks_per_coordinate(_coordinates(list(sampler.scenes(32, 3000))), reference)]
    assert min(p) >= P_MIN, p


def test_the_law_test_fails_on_simplices_drawn_with_wrong_weights(sampler, reference):
    tray = sampler._batch.plan.objects[3]  # tr_1 on its free space: pieces weighted by their areas
    assert tray.name == "tr_1" and len(tray.region.measures) > 2
    wrong = Sampler(sampler.program, spec=SPEC)
    # Table-Cube's pieces now have nearly equal areas (0.25 each), so drawing them without their
    # areas is nearly right: the wrong law puts four times the weight on the first piece.
    weights = np.asarray(tray.region.measures, dtype=float) * np.r_[4.0, np.ones(len(tray.region.measures) - 1)]
    wrong_tray = UniformSampler(tray.region.simplices, weights)
    objects = list(wrong._batch.plan.objects)
    objects[3] = type(tray)(**{**tray.__dict__, "region": wrong_tray})
    object.__setattr__(wrong._batch.plan, "objects", tuple(objects))
    p = [p for _, p in ks_per_coordinate(_coordinates(list(wrong.scenes(32, 3000))), reference)]
    assert min(p) < P_MIN, p


def test_the_counter_stream_is_uniform_and_uncorrelated_where_a_weyl_sequence_is_not():
    n = 20_000
    keys = scene_keys(7, np.arange(n))
    u = uniforms(keys, 5, 2)
    assert kstest(u[:, 0], "uniform").pvalue >= P_MIN
    bound = 4.0 / np.sqrt(n)  # |r| of independent uniforms exceeds 4 sigma with p ~ 6e-5
    pairs = {
        "neighbouring scenes": (u[:-1, 0], u[1:, 0]),
        "two uniforms of one site": (u[:, 0], u[:, 1]),
        "two sites": (u[:, 0], uniforms(keys, 6, 1)[:, 0]),
        "two seeds": (u[:, 0], uniforms(scene_keys(8, np.arange(n)), 5, 1)[:, 0]),
    }
    for what, (a, b) in pairs.items():
        assert abs(np.corrcoef(a, b)[0, 1]) < bound, what
    weyl = (np.arange(n) * 0.6180339887498949) % 1.0  # uniform marginals, no mixing
    assert kstest(weyl, "uniform").pvalue >= P_MIN
    assert abs(np.corrcoef(weyl[:-1], weyl[1:])[0, 1]) > bound


@pytest.mark.parametrize("text, because", [
    ("a = Cube at Vector3D(0, 0, 1)\nb = Cube at Vector3D((0, 0.03), 0, 1)\n", "b and a may touch"),
    ("t = Cube at Vector3D(0, 0, 1), facing (0, 90 deg)\n", "t's size or rotation changes"),
    ("t = Cube at Vector3D(0, 0, 1), with width (0.1, 0.2)\n", "t's size or rotation changes"),
    ("x = (0, 1)\nrequire x > 0.5\nt = Cube at Vector3D(0, 0, 1)\n", "requires checked per scene"),
    ("t = Cube at Vector3D((0, 3), 0, 1)\n", "t's `at` point may leave its other rows"),
])
def test_a_spec_that_is_not_batched_says_why(tmp_path, text, because):
    spec = tmp_path / "spec.prs"
    spec.write_text("from tabletop import *\n" + text)
    sampler = Sampler(compile_program(str(spec), ()), "exact")
    assert not sampler.batched
    assert because in sampler.plan.why


def test_a_compile_worker_s_drawer_hands_out_the_same_scenes_in_any_order(sampler):
    """`Sampler.drawer` (what compile jobs call) draws 64 scenes ahead: scene k is still scene k,
    asked in order, out of order, or twice."""
    drawer = sampler.drawer(3)
    for k in (0, 1, 2, 70, 5, 5, 63, 64, 1000):
        assert drawer(k) == sampler.scene(3, k), k


def test_a_growing_drawer_takes_twice_the_last_draw_and_gives_the_same_scenes(monkeypatch):
    # A reset loop's drawer (SceneEnv): the first draw small, each later one twice the last up to a cap.
    # bin_ten_parts: Gibbs rounds, which draw all of a chunk at once (as batches do).
    sampler = Sampler(compile_program(str(REPO / "specs" / "bin_ten_parts.prs")), "exact")
    scenes = sampler.batch(7, range(40))
    draws: list[int] = []
    group = sampler._group  # the drawer takes Gibbs rounds' scenes as it hands them out, each made when asked for
    lazily = group.draw_lazily
    monkeypatch.setattr(group, "draw_lazily", lambda seed, chunk: draws.append(len(chunk)) or lazily(seed, chunk))
    drawer = sampler.drawer(7, 2, grow_to=8)
    assert [drawer(k) for k in range(30)] == scenes[:30]
    assert draws == [2, 4, 8, 8, 8]
    assert drawer(35) == scenes[35] and drawer(33) == scenes[33]  # out of order: drawn again, still scene k
    assert draws[-2:] == [8, 8]
