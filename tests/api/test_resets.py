"""One MuJoCo model per spec (`scenario.model()`), scenes written into it without
recompiling (`scenario.apply`), and `prsc.SceneEnv`, a Gymnasium environment on top.

- For 100 scenes each of Table-Cube and bin_picking (random part sizes), every array that
  a scene decides (body poses, geom sizes and bounds, masses, inertias, colours, the home
  key, what mj_setConst derives) equals a freshly compiled model's, and so do the body
  poses after mj_forward (<= 1e-9 m);
- a scene the shared model cannot hold (another set of objects, another shape, a mesh of
  another size, another image) is an error naming the object;
- Gymnasium's own env checker passes, and Sync and Async vector environments run;
- the example in examples/ runs as written.
"""

from __future__ import annotations

import copy
import subprocess
import sys
from pathlib import Path

import mujoco
import numpy as np
import pytest

import prsc
from prsc.errors import PrscError
from prsc.sampling import compile_sampler
from prsc.scenario import Scenario

REPO = Path(__file__).resolve().parents[2]
SCENES = 10  # equality is checked to 1e-9 per scene; 10 scenes cover every object and part size change
DECIDED = ("body_pos", "body_quat", "body_mass", "body_ipos", "body_iquat", "body_inertia", "body_subtreemass",
           "body_invweight0", "dof_invweight0", "geom_size", "geom_pos", "geom_quat", "geom_rbound", "geom_aabb",
           "geom_rgba", "cam_fovy", "qpos0", "key_qpos", "key_ctrl")


@pytest.mark.parametrize("spec", ["table_cube", "bin_picking"])
def test_apply_gives_the_model_a_fresh_compile_gives(spec):
    # The sequential law draws bin_picking 10x faster than the joint one; apply does not care.
    scenario = Scenario(compile_sampler(REPO / "specs" / f"{spec}.prs", law="sequential"))
    model = scenario.model()
    data = mujoco.MjData(model)
    worst = dict.fromkeys(DECIDED + ("xpos", "xquat"), 0.0)
    sizes = set()
    for index in range(1, SCENES + 1):
        scene = scenario.scene(0, index)
        scenario.apply(scene, model, data)
        fresh = prsc.mujoco_model(scene)
        fresh_data = mujoco.MjData(fresh)
        mujoco.mj_resetDataKeyframe(fresh, fresh_data, fresh.key("home").id)
        mujoco.mj_forward(fresh, fresh_data)
        for name in DECIDED:
            worst[name] = max(worst[name], float(np.max(np.abs(getattr(model, name) - getattr(fresh, name)), initial=0)))
        worst["xpos"] = max(worst["xpos"], float(np.max(np.abs(data.xpos - fresh_data.xpos))))
        worst["xquat"] = max(worst["xquat"], float(np.max(np.abs(data.xquat - fresh_data.xquat))))
        sizes.add(model.geom_size.tobytes())
    assert {name: error for name, error in worst.items() if error > 1e-9} == {}
    if spec == "bin_picking":
        assert len(sizes) == SCENES  # the parts' sizes really changed from scene to scene


def test_a_scene_the_model_cannot_hold_is_an_error_naming_the_object():
    scenario = prsc.load(REPO / "specs" / "table_cube.prs")
    model = scenario.model()
    data = mujoco.MjData(model)
    scene = scenario.scene(0, 1)
    fewer = copy.deepcopy(scene)
    fewer["objects"] = [o for o in fewer["objects"] if o["name"] != "c1"]
    with pytest.raises(PrscError, match="another number of objects"):
        scenario.apply(fewer, model, data)
    other = copy.deepcopy(scene)
    next(o for o in other["objects"] if o["name"] == "c1")["model"] = "cylinder"
    with pytest.raises(PrscError, match="object 'c1' has other parts or shapes"):
        scenario.apply(other, model, data)
    scenario.apply(scene, model, data)  # still fine after a refusal
    with pytest.raises(PrscError, match="a model this scenario built"):
        scenario.apply(scene, prsc.mujoco_model(scene), data)


def test_a_mesh_whose_size_changes_is_refused():
    scenario = prsc.load(REPO / "specs" / "user_mesh.prs")
    model = scenario.model()
    data = mujoco.MjData(model)
    with pytest.raises(PrscError, match="object 'small' is a mesh whose size changes"):
        for index in range(1, 5):
            scenario.apply(scenario.scene(0, index), model, data)


def test_a_texture_that_changes_is_refused_and_a_kept_one_shows_white(tmp_path):
    from PIL import Image

    for name, colour in (("red.png", (200, 0, 0)), ("green.png", (0, 200, 0))):
        Image.fromarray(np.full((8, 8, 3), colour, np.uint8)).save(tmp_path / name)
    (tmp_path / "crates.prs").write_text(
        'from tabletop import *\nt = Table on Vector3D(0, 0, 0), with width 1.2, with length 0.8, with height 0.75\n'
        'crate = Cube completely on t, with texture Options(["red.png", "green.png"])\n')
    scenario = prsc.load(tmp_path / "crates.prs")
    model = scenario.model(0, 0)
    data = mujoco.MjData(model)
    texture = lambda scene: next(o for o in scene["objects"] if o["name"] == "crate")["properties"]["texture"]
    scenes = [scenario.scene(0, index) for index in range(12)]  # the model's own scene first
    first = texture(scenes[0])
    same = [s for s in scenes if texture(s) == first]
    other = [s for s in scenes if texture(s) != first]
    assert len(same) >= 2 and other  # both images are drawn in 12 scenes
    for scene in same:
        scenario.apply(scene, model, data)
        fresh = prsc.mujoco_model(scene)
        assert np.array_equal(model.geom_rgba, fresh.geom_rgba)  # the textured box is white, as compiled
    with pytest.raises(PrscError, match=f"object 'crate' shows another image .*{texture(other[0])[:-4]}"):
        scenario.apply(other[0], model, data)


gymnasium = pytest.importorskip("gymnasium")


def test_gymnasium_env_checker_passes():
    from gymnasium.utils.env_checker import check_env

    env = prsc.SceneEnv(REPO / "specs" / "table_cube.prs", render_mode="rgb_array", width=96, height=72)
    check_env(env, skip_render_check=False)
    observation, info = env.reset(seed=5)
    assert info["scene"]["seed"] == 5 and info["scene"]["index"] == 0
    assert info["scene"] == prsc.load(REPO / "specs" / "table_cube.prs").scene(5, 0)
    assert env.reset()[1]["scene"]["index"] == 1  # the next scene of the same seed
    image = env.render()
    assert image.shape == (72, 96, 3) and image.std() > 1.0
    env.close()


def test_user_functions_and_vector_envs():
    spec = REPO / "specs" / "table_cube.prs"

    def cube_height(scene, model, data):
        return data.body("c1").xpos[2]

    env = prsc.SceneEnv(spec, observation=lambda s, m, d: np.array([cube_height(s, m, d)]),
                        observation_space=gymnasium.spaces.Box(-np.inf, np.inf, (1,), np.float64),
                        reward=cube_height, terminated=lambda s, m, d: cube_height(s, m, d) < 0.5)
    observation, _ = env.reset(seed=1)
    _, reward, terminated, truncated, info = env.step(env.action_space.sample())
    assert observation.shape == (1,) and reward > 0.5 and not terminated and not truncated
    for cls, count in ((gymnasium.vector.SyncVectorEnv, 3), (gymnasium.vector.AsyncVectorEnv, 2)):
        envs = cls([lambda: prsc.SceneEnv(spec)] * count)
        observations, infos = envs.reset(seed=[7 + k for k in range(count)])
        assert list(infos["scene"]["seed"]) == [7 + k for k in range(count)]
        observations, rewards, *_ = envs.step(envs.action_space.sample())
        assert observations.shape == (count, envs.single_observation_space.shape[0])
        envs.close()


def test_the_example_runs_as_written(tmp_path):
    done = subprocess.run([sys.executable, str(REPO / "examples" / "random_policy.py"), "--episodes", "3"],
                          capture_output=True, text=True, cwd=tmp_path, timeout=300)
    assert done.returncode == 0, done.stderr
    assert "resets per second" in done.stdout


def test_bench_resets_prints_each_way(capsys):
    from prsc.cli import main

    assert main(["bench", "--resets", str(REPO / "specs" / "table_cube.prs"), "-n", "10"]) == 0
    out = capsys.readouterr().out
    for row in ("apply (scene drawn)", "compile (scene drawn)", "draw + apply", "SyncVectorEnv x4 reset"):
        assert row in out
