"""One MuJoCo model per spec (`scenario.model()`), scenes written into it without
recompiling (`scenario.apply`), and `prsc.SceneEnv`, a Gymnasium environment on top.

- For 10 scenes each of Table-Cube, bin_picking (random part sizes), bin_ten_parts and
  bin_ten_parts_arm (the bin beside the Panda), every array that
  a scene decides (body poses, geom sizes and bounds, masses, inertias, colours, the home
  key, what mj_setConst derives) equals a freshly compiled model's, and so do the body
  poses after mj_forward (<= 1e-9 m);
- a scene the shared model cannot hold (another set of objects, shape, ground or camera
  resolution, a mesh of another size, an image the spec cannot draw) is an error naming it;
- every image a spec's `texture` can draw is loaded once: 30 scenes show a fresh model's
  image on each geom, and two scenes of each image render equal pixel for pixel;
- Gymnasium's own env checker passes (also with camera observations), and Sync and Async
  vector environments run; camera observations equal a fresh model's renderer's images;
  actions are bounded (a URDF arm's by its joints); `max_episode_steps` truncates;
- the examples in examples/ run as written.
"""

from __future__ import annotations

import copy
import os
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
           "geom_rgba", "cam_fovy", "qpos0", "qpos_spring", "key_qpos", "key_ctrl")


def _at_home(model):
    """New data of a model at its `home` key, forwarded (what `apply` leaves)."""
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
    mujoco.mj_forward(model, data)
    return data


def _fresh_at_home(scene):
    """A freshly compiled model of a scene and its data at `home`."""
    fresh = prsc.mujoco_model(scene)
    return fresh, _at_home(fresh)


@pytest.mark.parametrize("spec", ["table_cube", "bin_picking", "bin_ten_parts", "bin_ten_parts_arm"])
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
        fresh, fresh_data = _fresh_at_home(scene)
        for name in DECIDED:
            worst[name] = max(worst[name], float(np.max(np.abs(getattr(model, name) - getattr(fresh, name)), initial=0)))
        worst["stat"] = max(worst.get("stat", 0.0), float(np.max(np.abs(model.stat.center - fresh.stat.center))),
                            abs(model.stat.extent - fresh.stat.extent))
        worst["xpos"] = max(worst["xpos"], float(np.max(np.abs(data.xpos - fresh_data.xpos))))
        worst["xquat"] = max(worst["xquat"], float(np.max(np.abs(data.xquat - fresh_data.xquat))))
        sizes.add(model.geom_size.tobytes())
    assert {name: error for name, error in worst.items() if error > 1e-9} == {}
    if spec != "table_cube":
        assert len(sizes) == SCENES  # the parts' sizes really changed from scene to scene


def test_apply_writes_new_sizes_of_primitives_without_parsing_them(monkeypatch):
    # bin_ten_parts: washers of random diameter and bolts of random height. After the first scene,
    # apply neither parses nor resolves them again, and what it writes is a fresh model's.
    import prsc.backends.shared_model as shared_model
    from prsc.backends.scene import parse_scene

    scenario = Scenario(compile_sampler(REPO / "specs" / "bin_ten_parts.prs", law="sequential"))
    model = scenario.model()
    data = mujoco.MjData(model)
    scenario.apply(scenario.scene(0, 1), model, data)

    def refused(*args, **kwargs):
        raise AssertionError("parsed or resolved again")

    monkeypatch.setattr(shared_model, "parse_object", refused)
    monkeypatch.setattr(shared_model, "resolve_body", refused)
    monkeypatch.setattr(shared_model, "parse_scene", refused)
    for index in (2, 3):
        scene = scenario.scene(0, index)
        scenario.apply(scene, model, data)
        fresh = prsc.mujoco_model(scene)
        for name in ("geom_size", "geom_rbound", "geom_aabb", "body_mass", "body_inertia", "body_invweight0"):
            assert np.max(np.abs(getattr(model, name) - getattr(fresh, name))) <= 1e-9, name
    # A bad size is refused with the scene parser's own message, and the model still takes scenes.
    bad = copy.deepcopy(scenario.scene(0, 4))
    bad["objects"][2]["dimensions"][0] = -0.05
    with pytest.raises(PrscError) as refusal:
        scenario.apply(bad, model, data)
    with pytest.raises(PrscError) as parsed:
        parse_scene(bad)  # the scene parser itself (imported before the patch)
    assert refusal.value.message == parsed.value.message
    assert "dimensions" in refusal.value.message
    scenario.apply(scenario.scene(0, 4), model, data)


BAD_SIZES = (("dimensions", [0.05, float("nan"), 0.006]), ("dimensions", [0.05, True, 0.006]), ("dimensions", [0.05, 0.05]),
             ("dimensions", [0.05, 0.05, 2e6]), ("dimensions", [0.05, 0.05, 1e-7]), ("dimensions", "0.05"),
             ("mass", 0.0), ("mass", -1.0), ("mass", [0.1]), ("mass", "0.1"), ("mass", float("inf")), ("mass", None))


def test_every_bad_size_or_mass_is_refused_with_the_scene_parser_s_message():
    # apply checks a reset's new sizes and masses all at once; whatever that check refuses is read again
    # object by object, so each refusal is the parser's own.
    from prsc.backends.scene import parse_scene

    scenario = Scenario(compile_sampler(REPO / "specs" / "bin_ten_parts.prs", law="sequential"))
    model = scenario.model()
    data = mujoco.MjData(model)
    scenario.apply(scenario.scene(0, 1), model, data)
    for key, value in BAD_SIZES:
        bad = copy.deepcopy(scenario.scene(0, 2))
        bad["objects"][2][key] = value
        with pytest.raises(PrscError) as refusal:
            scenario.apply(bad, model, data)
        with pytest.raises(PrscError) as parsed:
            parse_scene(bad)
        assert refusal.value.message == parsed.value.message, (key, value)
    fine = copy.deepcopy(scenario.scene(0, 2))
    fine["objects"][2]["dimensions"] = tuple(fine["objects"][2]["dimensions"])  # a tuple is a list to the parser
    scenario.apply(fine, model, data)
    assert np.array_equal(model.geom_size, prsc.mujoco_model(scenario.scene(0, 2)).geom_size)


@pytest.mark.parametrize("pose, message", [
    (("quaternion", [1.0, 0.0, 0.0, 0.5]), "expected a unit quaternion"),
    (("position", [0.1, True, 0.8]), "expected finite numbers"),
    (("position", [0.1, "0.2", 0.8]), "expected finite numbers"),
    (("position", [0.1, 0.2]), "expected a list of 3 numbers"),
    (("quaternion", None), "expected a list of 4 numbers"),
])
def test_a_bad_pose_is_refused_with_the_scene_parser_s_message(pose, message):
    # apply reads every pose at once; a pose that fails is read again one by one for the parser's message.
    scenario = prsc.load(REPO / "specs" / "table_cube.prs")
    model = scenario.model()
    data = mujoco.MjData(model)
    bad = copy.deepcopy(scenario.scene(0, 1))
    next(o for o in bad["objects"] if o["name"] == "c1")[pose[0]] = pose[1]
    with pytest.raises(PrscError, match=f"scene JSON: object 'c1'.{pose[0]}: {message}"):
        scenario.apply(bad, model, data)


def test_plain_shape_models_are_their_primitive():
    # The cube and cylinder assets are the object's primitive (what lets apply write them by formula).
    from prsc.assets.registry import part_recipe
    from prsc.backends.bodies import PLAIN_SHAPE_MODELS, primitive_part

    for dimensions in ((0.05, 0.08, 0.02), (0.3, 0.1, 0.7), (0.01, 0.01, 0.01)):
        for model, shape in PLAIN_SHAPE_MODELS.items():
            assert part_recipe(model)(dimensions) == (primitive_part(shape, dimensions),)


def test_a_scene_the_model_cannot_hold_is_an_error_naming_what_differs():
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
    bare = copy.deepcopy(scene)
    bare["params"]["ground"] = False
    with pytest.raises(PrscError, match="it has no ground plane, the model has"):
        scenario.apply(bare, model, data)
    wide = copy.deepcopy(scene)
    next(o for o in wide["objects"] if o["name"] == "camera")["camera"]["resolution"] = [320, 240]
    with pytest.raises(PrscError, match=r"camera 'camera' has the resolution \(320, 240\) here, \(640, 480\)"):
        scenario.apply(wide, model, data)
    scenario.apply(scene, model, data)  # still fine after a refusal
    assert np.allclose(data.body("c1").xpos, next(o for o in scene["objects"] if o["name"] == "c1")["position"])
    with pytest.raises(PrscError, match="a model this scenario built"):
        scenario.apply(scene, prsc.mujoco_model(scene), data)


def test_a_mesh_whose_size_changes_is_refused():
    scenario = prsc.load(REPO / "specs" / "user_mesh.prs")
    model = scenario.model()
    data = mujoco.MjData(model)
    with pytest.raises(PrscError, match="object 'small' is a mesh whose size changes"):
        for index in range(1, 5):
            scenario.apply(scenario.scene(0, index), model, data)


def _textured_table_cube(folder: Path) -> Path:
    """Table-Cube whose cube shows one of three images per scene."""
    from PIL import Image

    rng = np.random.default_rng(0)
    for name in ("wood", "marble", "checker"):
        Image.fromarray(rng.integers(0, 255, (16, 16, 3), dtype=np.uint8)).save(folder / f"{name}.png")
    text = (REPO / "specs" / "table_cube.prs").read_text().replace(
        'c1 = Cube completely on tr_1, with color "red"',
        'c1 = Cube completely on tr_1, with texture Options(["wood.png", "marble.png", "checker.png"])')
    assert "with texture" in text
    (folder / "textured.prs").write_text(text)
    return folder / "textured.prs"


def _image_of(model, geom: int) -> bytes:
    """The pixels of the RGB texture a geom's material shows."""
    texture = model.mat_texid[model.geom_matid[geom], int(mujoco.mjtTextureRole.mjTEXROLE_RGB)]
    size = model.tex_width[texture] * model.tex_height[texture] * model.tex_nchannel[texture]
    return model.tex_data[model.tex_adr[texture]:model.tex_adr[texture] + size].tobytes()


def _close_up(renderer, model, data, body: str) -> np.ndarray:
    """An image of a body filling the view (MuJoCo's free camera aimed at it)."""
    camera = mujoco.MjvCamera()
    camera.lookat[:] = data.body(body).xpos
    camera.distance, camera.azimuth, camera.elevation = 0.12, 60.0, -35.0
    renderer.update_scene(data, camera)
    return renderer.render().copy()


def test_every_image_is_loaded_once_and_apply_shows_the_scenes(tmp_path):
    # 30 scenes: the image each geom shows equals a fresh model's; two scenes of each image also render equal.
    scenario = prsc.load(_textured_table_cube(tmp_path))
    model = scenario.model()
    data = mujoco.MjData(model)
    geom = model.geom("c1/box").id
    shown: dict[str, list[bytes]] = {}
    for index in range(1, 31):
        scene = scenario.scene(0, index)
        scenario.apply(scene, model, data)
        fresh = prsc.mujoco_model(scene)
        assert _image_of(model, geom) == _image_of(fresh, fresh.geom("c1/box").id)
        image = next(o for o in scene["objects"] if o["name"] == "c1")["properties"]["texture"]
        if len(shown.setdefault(image, [])) == 2:
            continue
        fresh_data = _at_home(fresh)
        with mujoco.Renderer(fresh, 48, 64) as renderer:
            expected = _close_up(renderer, fresh, fresh_data, "c1")
        with mujoco.Renderer(model, 48, 64) as renderer:
            seen = _close_up(renderer, model, data, "c1")
        assert np.array_equal(seen, expected)
        shown[image].append(seen.tobytes())
    assert sorted(shown) == ["checker.png", "marble.png", "wood.png"]
    assert len({views[0] for views in shown.values()}) == 3  # each image looks different


def test_a_model_whose_images_cannot_be_listed_is_refused_when_built(tmp_path):
    # `prsc check` refuses a texture that is not a file name or a choice among them; a shared
    # model told no list for a textured object refuses to be built, not at a later reset.
    from prsc.backends.shared_model import SharedModel
    from prsc.backends.store import AssetStore
    from prsc.scenario import in_memory_root

    scene = prsc.load(_textured_table_cube(tmp_path)).scene(0, 0)
    root = in_memory_root()
    with pytest.raises(PrscError, match="object 'c1': its image .* is not drawn from a list of file names"):
        SharedModel(scene, prsc.mujoco_spec(scene), AssetStore(root / "assets"), root / "mjcf", images={})


def test_an_image_the_model_did_not_load_is_refused(tmp_path):
    scenario = prsc.load(_textured_table_cube(tmp_path))
    model = scenario.model()
    data = mujoco.MjData(model)
    scene = copy.deepcopy(scenario.scene(0, 1))
    from PIL import Image

    Image.fromarray(np.zeros((4, 4, 3), np.uint8)).save(tmp_path / "other.png")
    next(o for o in scene["objects"] if o["name"] == "c1")["properties"]["texture"] = "other.png"
    with pytest.raises(PrscError, match="object 'c1' shows an image \\(other-.*\\) that is not among"):
        scenario.apply(scene, model, data)


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
    for row in ("apply (scene drawn)", "compile (scene drawn)", "draw + apply", "draw + apply (full batches)",
                "once every draw is a full batch", "SyncVectorEnv x4 reset", "SceneEnv.step",
                "mj_step(nstep=10)", "a SceneEnv step costs"):
        assert row in out


def test_camera_observations_are_the_spec_cameras_images():
    from gymnasium.utils.env_checker import check_env

    spec = REPO / "specs" / "table_cube.prs"
    env = prsc.SceneEnv(spec, observation={"camera": ("rgb", "depth", "segmentation")})
    assert set(env.observation_space["camera"].spaces) == {"rgb", "depth", "segmentation"}
    assert env.observation_space["camera"]["rgb"].shape == (480, 640, 3)
    for seed in (3, 4):  # one renderer for both scenes: the second is drawn after a reset
        observation, info = env.reset(seed=seed)
        fresh, fresh_data = _fresh_at_home(info["scene"])
        with mujoco.Renderer(fresh, 480, 640) as renderer:
            renderer.update_scene(fresh_data, "camera")
            expected = renderer.render()
        assert observation["camera"]["rgb"].std() > 1.0
        assert np.array_equal(observation["camera"]["rgb"], expected)
        assert env.observation_space.contains(observation)
    env.close()
    env = prsc.SceneEnv(spec, observation="cameras", render_mode="rgb_array", render_camera="camera", width=64, height=48)
    check_env(env, skip_render_check=False)
    assert env.render().shape == (48, 64, 3)
    env.close()
    with pytest.raises(ValueError, match="no camera 'ceiling' in this spec"):
        prsc.SceneEnv(spec, observation={"ceiling": "rgb"})


def test_steps_give_no_scene_and_truncate_at_max_episode_steps():
    env = prsc.SceneEnv(REPO / "specs" / "table_cube.prs", max_episode_steps=3)
    _, info = env.reset(seed=0)
    assert info["scene"]["index"] == 0 and info["scene"] == env.scene
    info["scene"]["objects"][0]["position"][0] += 1.0  # a copy: the caller's to edit
    assert info["scene"] != env.scene
    outcomes = [env.step(env.action_space.sample()) for _ in range(3)]
    assert [truncated for *_, truncated, _ in outcomes] == [False, False, True]
    assert all("scene" not in info for *_, info in outcomes)  # the task's status only (Table-Cube states one)
    env.reset()
    assert not env.step(env.action_space.sample())[3]  # the count starts again


def test_a_urdf_arm_s_actions_are_bounded_by_its_joint_limits():
    import pybullet_data

    env = prsc.SceneEnv(REPO / "specs" / "pybullet_arm" / "franka_pick.prs", include_dirs=[pybullet_data.getDataPath()])
    model = env.model
    joints = model.actuator_trnid[:, 0]
    assert model.nu == 9 and np.all(np.isfinite(env.action_space.low)) and np.all(np.isfinite(env.action_space.high))
    assert np.allclose(env.action_space.low, model.jnt_range[joints, 0], atol=1e-6)
    assert np.allclose(env.action_space.high, model.jnt_range[joints, 1], atol=1e-6)
    env.reset(seed=0)
    env.action_space.seed(0)
    for _ in range(50):
        env.step(env.action_space.sample())
        targets = env.data.ctrl
        assert np.all(targets >= model.jnt_range[joints, 0]) and np.all(targets <= model.jnt_range[joints, 1])
    env.step(np.full(model.nu, 100.0))  # beyond the space: clipped to it
    assert np.array_equal(env.data.ctrl, model.jnt_range[joints, 1])


def test_the_domain_randomisation_example_runs_as_written(tmp_path):
    # A fresh shell: no MUJOCO_GL, so SceneEnv picks a headless backend itself.
    shell = {k: v for k, v in os.environ.items() if k not in ("MUJOCO_GL", "PYOPENGL_PLATFORM")}
    done = subprocess.run([sys.executable, str(REPO / "examples" / "domain_randomisation.py"), "--episodes", "4",
                           "--steps", "2"], capture_output=True, text=True, cwd=tmp_path, timeout=300, env=shell)
    assert done.returncode == 0, done.stderr
    assert "4 distinct first images of 4 episodes" in done.stdout
    assert (tmp_path / "domain_randomisation.png").is_file()


def test_the_vector_env_row_times_whole_batches_of_draws():
    """`prsc bench --resets` times a vector environment over the resets its draws hold whole (64, then
    128, then 256 each): a row timed inside one untimed draw would leave the draw out."""
    from prsc.commands.bench_resets import _ramp_total

    assert [_ramp_total(n, 64, 256) for n in (1, 50, 64, 65, 192, 193, 500)] == [64, 64, 64, 192, 192, 448, 704]
