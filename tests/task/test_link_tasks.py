"""Task relations on links (docs/tasks.md, "Links"): `X.links["NAME"]` as a target of a task
relation, evaluated where the link is *now*. The tests' cabinet (tests/assets/data/cabinet.urdf):
a cube resting in its open drawer is `in` it; the drawer pulled out from under a pinned cube
takes the robustness with it, in MuJoCo (the runner's monitor) and in pybullet (the same
task.json); the sign agrees with the truth on random states; bad links are errors at their place."""

from __future__ import annotations

import json
import shutil
import xml.etree.ElementTree as ET
from pathlib import Path

import mujoco
import numpy as np
import pybullet
import pytest
from scipy.spatial.transform import Rotation

from prsc.cli import main
from prsc.errors import PrscError
from prsc.ir import compile_program
from prsc.runner.step_hook import PeriodicCallback, StepHook
from prsc.runner.task_monitor import CONTROL_PERIOD, TaskMonitor
from prsc.task.bind import link_object
from prsc.task.pybullet_adapter import PybulletTask
from prsc.task.robustness import Evaluator
from prsc.task.task_regions import box_corners
from prsc.task.terms import Task, TaskObject, TaskStatements, Term
from prsc.task.world import Pose, WorldState

CABINET = Path(__file__).resolve().parents[1] / "assets" / "data" / "cabinet.urdf"
SCENE = """\
from tabletop import *

class Cabinet:
    model: "cabinet.urdf"

cab = Cabinet on Vector3D(0, 0, 0), with joint "drawer_slide" (0.05, 0.1)
c1 = Cube completely in cab.links["drawer"], with color "red"
t = Table on Vector3D(0, 1.5, 0)
"""
TASK = """\
goal c1 in cab.links["drawer"] for 0.5 seconds
fail "outside" when not (c1 in cab.links["drawer"])
fail "hit the carcass" when c1 touches cab.links["carcass"]
record c1 in cab.links["drawer"] as inside
record final distance from c1 to cab.links["drawer"] as gap
"""
PULL = 0.2  # m: the drawer pulled out this far from under the pinned cube


def _urdf_boxes(link: str) -> list[tuple[np.ndarray, np.ndarray]]:
    """(low, high) of each collision box of a link of the cabinet, read from the URDF itself."""
    root = ET.parse(CABINET).getroot()
    out = []
    for collision in root.find(f"link[@name='{link}']").iter("collision"):
        centre = np.array([float(v) for v in collision.find("origin").get("xyz").split()])
        half = np.array([float(v) for v in collision.find("geometry/box").get("size").split()]) / 2
        out.append((centre - half, centre + half))
    return out


DRAWER = _urdf_boxes("drawer")
FLOOR_Z = DRAWER[0][1][2]  # the floor box's top, in the drawer frame
# inside the walls: x between the side walls, y between the back and the front
FOOTPRINT = (DRAWER[1][1][0], DRAWER[2][0][0], DRAWER[3][1][1], DRAWER[4][0][1])
CENTRE = (np.min([b[0] for b in DRAWER], axis=0) + np.max([b[1] for b in DRAWER], axis=0)) / 2


def _footprint_distance(x: float, y: float) -> float:
    """Signed distance of (x, y) in the drawer frame to the floor inside its walls (inside positive)."""
    x0, x1, y0, y1 = FOOTPRINT
    inside = min(x - x0, x1 - x, y - y0, y1 - y)
    return inside if inside >= 0 else -float(np.hypot(max(x0 - x, 0, x - x1), max(y0 - y, 0, y - y1)))


@pytest.fixture(scope="module")
def compiled(tmp_path_factory) -> Path:
    """Scene 0 of the spec as `prsc compile` writes it, in every format."""
    folder = tmp_path_factory.mktemp("links")
    shutil.copy(CABINET, folder / "cabinet.urdf")
    (folder / "cab.prs").write_text(SCENE + "\n" + TASK)
    assert main(["compile", str(folder / "cab.prs"), "-n", "1", "--target", "json,mjcf,urdf,sdf,usd",
                 "-o", str(folder / "out")]) == 0
    return folder / "out" / "cab"


def _mujoco(compiled: Path):
    scene = json.loads((compiled / "json" / "00000.json").read_text())
    model = mujoco.MjModel.from_xml_path(str(compiled / "mjcf" / "00000.xml"))
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
    mujoco.mj_forward(model, data)
    return scene, model, data


def _drawer_frame(model, data) -> tuple[np.ndarray, np.ndarray]:
    body = model.body("cab/drawer").id
    return data.xpos[body].copy(), data.xmat[body].reshape(3, 3).copy()


def test_every_format_carries_the_link_in_its_task_file(compiled):
    files = [compiled / "mjcf" / "00000.task.json", compiled / "sdf" / "00000.task.json",
             compiled / "usd" / "00000.task.json", compiled / "urdf" / "00000" / "task.json"]
    tasks = [json.loads(f.read_text()) for f in files] + [json.loads((compiled / "json" / "00000.json").read_text())["task"]]
    for data in tasks:
        assert data == tasks[0]
        drawer = next(o for o in data["objects"] if o["name"] == "cab/drawer")
        assert drawer["link"]["of"] == "cab" and drawer["link"]["name"] == "drawer"
        assert drawer["link"]["offset"] == pytest.approx(CENTRE.tolist(), abs=1e-9)
        floor = drawer["interior"]
        assert floor["high"] == pytest.approx(FLOOR_Z - CENTRE[2], abs=1e-9)
        x0, x1, y0, y1 = FOOTPRINT
        assert floor["offsets"] == pytest.approx([x1 - CENTRE[0], CENTRE[0] - x0, y1 - CENTRE[1], CENTRE[1] - y0])
        assert data["goals"][0]["expr"]["args"][1] == {"op": "link", "args": [{"op": "object", "name": "cab"}],
                                                       "name": "drawer"}
    task = Task.from_json(tasks[0])
    assert Task.from_json(task.to_json()) == task and [o.name for o in task.links()] == ["cab/drawer", "cab/carcass"]


def _run(compiled, script, seconds: float, watch: str = "update"):
    """Step the compiled scene watched by the runner's TaskMonitor through a StepHook (as `prsc run`);
    `script(t, model, data)` may pin the cube and move the drawer before each step. The statuses of
    every control step, with the drawer's frame and the cube's centre at that step."""
    scene, model, data = _mujoco(compiled)
    monitor = TaskMonitor(scene, model)
    seen = []

    def watched(model, data):
        getattr(monitor, watch)(model, data)
        if watch == "update":
            seen.append((monitor.latest, *_drawer_frame(model, data), data.body("c1").xpos.copy()))

    with StepHook(model, data, [PeriodicCallback(CONTROL_PERIOD, watched)]):
        while data.time < seconds:
            script(data.time, model, data)
            mujoco.mj_step(model, data)
    return seen, monitor.result(model, data, controller_finished=True), model, data


def test_a_cube_resting_in_the_open_drawer_is_in_it(compiled):
    seen, result, model, data = _run(compiled, lambda t, m, d: None, 0.8)
    assert result["outcome"] == "success" and result["trivial"] and result["robustness"]["goal"] > 0
    assert all(status.robustness["fail:outside"] >= 0 for status, *_ in seen)  # the first: resting, at 0 m
    assert result["robustness"]["fail:hit the carcass"] > 0  # the drawer is out, the cube clear of the carcass
    assert all(result["records"]["inside"])
    position, rotation = _drawer_frame(model, data)
    assert result["records"]["gap"] == pytest.approx(np.linalg.norm(data.body("c1").xpos - (position + rotation @ CENTRE)),
                                                     abs=1e-9)
    for watch in ("update", "log"):  # `prsc run` logs and evaluates 50 states at once: the same record
        assert _run(compiled, lambda t, m, d: None, 0.8, watch)[1] == result


def _pull_from_under(compiled):
    """The cube pinned 0.5 mm into the drawer's floor at the middle of the drawer where it starts, the
    drawer then pulled out PULL m (in 0.2 s, from t = 0.1 s) under it."""
    _, model, data = _mujoco(compiled)
    start = model.jnt_qposadr[model.joint("cab/drawer_slide").id]
    q0 = float(data.qpos[start])
    position, rotation = _drawer_frame(model, data)
    half = model.geom_size[model.body("c1").geomadr[0]][2]
    pin = position + rotation @ np.array([CENTRE[0], CENTRE[1], FLOOR_Z + half - 0.0005])

    def script(t, model, data):
        slide, cube = model.joint("cab/drawer_slide"), model.body("c1")
        data.qpos[slide.qposadr[0]] = q0 + PULL * min(1.0, max(0.0, (t - 0.1) / 0.2))
        data.qvel[slide.dofadr[0]] = 0.0
        free = model.jnt_qposadr[cube.jntadr[0]]
        data.qpos[free:free + 7] = [*pin, 1, 0, 0, 0]
        data.qvel[model.jnt_dofadr[cube.jntadr[0]]:][:6] = 0.0

    return script, q0


def test_the_robustness_follows_the_drawer_pulled_out_from_under_the_cube(compiled):
    script, q0 = _pull_from_under(compiled)
    seen, result, model, data = _run(compiled, script, 0.6)
    assert result["outcome"] == "fail:outside" and 0.1 < result["decided_at"] < 0.3
    inside = result["records"]["inside"]
    assert inside[0] and not inside[-1]  # in the drawer as sampled, out of it where the drawer is now
    last_in = max(k for k, value in enumerate(inside) if value)
    assert all(inside[:last_in + 1]) and not any(inside[last_in + 1:])  # out once, for good
    checked = 0
    for status, position, rotation, cube in seen:
        local = rotation.T @ (cube - position)
        over = _footprint_distance(local[0], local[1])
        rho = status.robustness["fail:outside"]  # minus `not in`: the robustness of `in` now
        assert (rho >= 0) == (over >= 0)
        if over < 0:  # the cube's centre is off the floor: the footprint decides, exactly
            assert rho == pytest.approx(over, abs=1e-6)
            checked += 1
    assert checked >= 10
    # at the end: the drawer went PULL along its axis, the cube stayed, so its centre sits PULL back
    local = rotation.T @ (cube - position)
    assert local[1] == pytest.approx(CENTRE[1] - PULL, abs=1e-6)
    assert data.qpos[model.jnt_qposadr[model.joint("cab/drawer_slide").id]] == pytest.approx(q0 + PULL, abs=1e-4)


def test_pybullet_scores_the_same_task_file_the_same(compiled):
    """The SDF world and the URDF bundle loaded by PybulletTask, set to the MuJoCo run's states
    (drawer value and cube pose) at every 2nd control step: the same truth, the same robustness."""
    script, q0 = _pull_from_under(compiled)
    _, model, data = _mujoco(compiled)
    states = []
    monitor = TaskMonitor(json.loads((compiled / "json" / "00000.json").read_text()), model)
    while data.time < 0.5:
        script(data.time, model, data)
        mujoco.mj_step(model, data)
        if len(states) < round(data.time / (2 * CONTROL_PERIOD)):
            status = monitor.update(model, data)
            states.append((data.time, float(data.qpos[model.jnt_qposadr[model.joint("cab/drawer_slide").id]]),
                           data.body("c1").xpos.copy(), data.body("c1").xquat.copy(), status))
    worst = 0.0
    for world in (compiled / "sdf" / "00000.sdf", compiled / "urdf" / "00000"):
        client = pybullet.connect(pybullet.DIRECT)
        try:
            task = PybulletTask.load(world, client)
            cab, cube = task.bodies["cab"], task.bodies["c1"]
            slide = next(j for j in range(pybullet.getNumJoints(cab, physicsClientId=client))
                         if pybullet.getJointInfo(cab, j, physicsClientId=client)[1] == b"drawer_slide")
            for time, value, position, (w, x, y, z), expected in states:
                pybullet.resetJointState(cab, slide, value, physicsClientId=client)
                pybullet.resetBasePositionAndOrientation(cube, position, (x, y, z, w), physicsClientId=client)
                pybullet.performCollisionDetection(physicsClientId=client)
                status = task.update(time)
                for key, rho in expected.robustness.items():
                    assert (status.robustness[key] >= 0) == (rho >= 0), (world.name, time, key)
                    if key == "fail:outside" and rho >= 0:
                        continue  # held: decided by how deep the pinned cube sinks in, each engine its own estimate
                    # out of the drawer (the footprint decides) and clear of the carcass (a separation): the same
                    assert status.robustness[key] == pytest.approx(rho, abs=2e-4), (world.name, time, key)
                    worst = max(worst, abs(status.robustness[key] - rho))
            assert task.result(states[-1][0])["outcome"] == "fail:outside"
        finally:
            pybullet.disconnect(client)
    print(f"{len(states)} states, worst robustness gap pybullet vs MuJoCo {worst:.2e} m")


def _link_task() -> tuple[Task, TaskObject]:
    drawer = link_object("cab", "drawer", tuple((tuple(lo), tuple(hi)) for lo, hi in DRAWER))
    cube = TaskObject("c1", (0.05, 0.05, 0.05), drawer.support)  # its own support is not read here
    return Task(TaskStatements(), (cube, drawer)), drawer


def test_the_sign_agrees_with_the_truth_on_12000_random_link_states():
    """Random drawer poses (any rotation) and cube poses near its floor, random contact distances: each
    relation to the link holds exactly where an independent computation from the URDF's boxes says."""
    rng = np.random.default_rng(7)
    task, drawer = _link_task()
    evaluator = Evaluator(task)
    link = Term("link", (Term("object", name="cab"),), name="drawer")
    cube = Term("object", name="c1")
    relations = {"in": Term("in", (cube, link)), "completely in": Term("in", (cube, link), completely=True),
                 "below": Term("below", (cube, link, Term("const", value=0.0))),
                 "touches": Term("touches", (cube, link)), "distance": Term("distance", (cube, link))}
    corners = box_corners((0.05, 0.05, 0.05))
    held = dict.fromkeys(("in", "completely in", "below", "touches"), 0)
    for _ in range(3000):
        frame = Rotation.random(random_state=rng.integers(1 << 31)).as_matrix()
        origin = rng.uniform(-1, 1, 3)
        # the cube near the floor, turned a little about the link's up (so its bottom stays flat mostly)
        tilt = Rotation.from_rotvec(rng.normal(0, 0.05, 3) + [0, 0, rng.uniform(-np.pi, np.pi)]).as_matrix()
        local = np.array([rng.uniform(-0.25, 0.25), rng.uniform(-0.2, 0.21), FLOOR_Z + 0.025 + rng.uniform(-0.015, 0.015)])
        cube_pose = Pose(origin + frame @ local, frame @ tilt, np.zeros(3), np.zeros(3))
        link_pose = Pose(origin + frame @ CENTRE, frame, np.zeros(3), np.zeros(3))
        distance = float(rng.uniform(-0.01, 0.01))
        world = WorldState(0.0, {"c1": cube_pose, "cab/drawer": link_pose}, lambda a, b, enough=None: distance)
        in_frame = local + corners @ tilt.T  # the cube's corners in the drawer's frame
        resting = abs(in_frame[:, 2].min() - FLOOR_Z) <= 0.01 and distance <= 0
        x0, x1, y0, y1 = FOOTPRINT
        over = [x0 <= x <= x1 and y0 <= y <= y1 for x, y in in_frame[:, :2]]
        truths = {"in": resting and _footprint_distance(*local[:2]) >= 0, "completely in": resting and all(over),
                  "below": bool(np.all(in_frame[:, 2] <= CENTRE[2])), "touches": distance <= 0}
        for word, expected in truths.items():
            value = evaluator.truth(relations[word], world)
            assert value.holds == expected and (value.robustness >= 0) == expected, word
            held[word] += expected
        assert evaluator.value(relations["distance"], world) == pytest.approx(np.linalg.norm(local - CENTRE), abs=1e-12)
    # 12,000 states, and each relation both holds and fails in a good share of them
    assert all(300 <= count <= 2700 for count in held.values()), held
    print(f"held in 3000 states: {held}")


@pytest.fixture()
def spec_folder(tmp_path) -> Path:
    shutil.copy(CABINET, tmp_path / "cabinet.urdf")
    return tmp_path


@pytest.mark.parametrize("task, column, message", [
    ('goal c1 in cab.links["drawr"]', 12, "cab.links: cabinet.urdf has no link 'drawr'"),
    ('fail "x" when c1 touches t.links["top"]', 26, "t has no links: only an object whose model is a URDF or MJCF"),
    ('goal c1 in cab.links["carcass"]', 12, "needs a hollow link (a floor walled on four sides)"),
    ('goal cab.links["drawer"] in c1', 6, "a link is the target of `in`, not its subject"),
    ('goal c1 in cab.links[3]', 22, "a link is named by a string"),
    ('goal c1 in t.parts["drawer"]', 12, 'a task names a link as X.links["NAME"]'),
])
def test_a_bad_link_is_an_error_at_its_place(spec_folder, task, column, message):
    path = spec_folder / "cab.prs"
    path.write_text(SCENE + task + "\n")
    line = len(SCENE.splitlines()) + 1
    with pytest.raises(PrscError) as caught:
        compile_program(str(path))
    assert message in caught.value.message
    assert (caught.value.span.line, caught.value.span.column) == (line, column), caught.value.message


def test_prsc_check_reports_a_bad_link_with_a_caret_and_writes_nothing(spec_folder, capsys):
    path = spec_folder / "cab.prs"
    path.write_text(SCENE + 'goal c1 in cab.links["drawr"]\n')
    assert main(["check", str(path)]) == 2
    err = capsys.readouterr().err
    line = len(SCENE.splitlines()) + 1
    assert f"{path}:{line}:12: error: cab.links: cabinet.urdf has no link 'drawr'" in err and "did you mean 'drawer'" in err
    assert "^^^^" in err and "Traceback" not in err
    assert main(["compile", str(path), "-o", str(spec_folder / "out")]) == 2
    assert not (spec_folder / "out").exists()


def test_the_docs_example_runs_as_written(tmp_path):
    """docs/tasks.md's link example: the library cabinet's spec and the pull controller, through `prsc run`."""
    import re

    text = (Path(__file__).parents[2] / "docs" / "tasks.md").read_text()
    section = text[text.index('## Links: `X.links["NAME"]`'):text.index("## Outcomes")]
    (tmp_path / "drawer.prs").write_text(re.search(r"```prs\n(.*?)```", section, re.S).group(1))
    (tmp_path / "pull.py").write_text(re.search(r"```python\n(.*?)```", section, re.S).group(1))
    assert main(["run", str(tmp_path / "drawer.prs"), "-n", "1", "--controller", f"{tmp_path / 'pull.py'}:pull",
                 "-o", str(tmp_path / "out")]) == 0
    record = json.loads((tmp_path / "out" / "results.jsonl").read_text().splitlines()[0])
    # scene 0's drawer starts 0.214 m out: pulled 8 cm, it is past 0.27 m with the cube at rest in it
    assert record["outcome"] == "pulled" and record["task"]["outcome"] == "success" and not record["task"]["trivial"]
    assert 0.5 < record["task"]["decided_at"] < 2.5
    assert record["task"]["robustness"]["fail:on the carcass"] > 0 and 0.05 < record["task"]["records"]["gap"] < 0.3


ARM = """\
from tabletop import *

cab = DrawerCabinet on Vector3D(0, 0, 0), with drawers 3, with joint "drawer1_slide" (0.15, 0.25)
c1 = Cube completely in cab.links["drawer1"], with color "red"
r1 = Robot on Vector3D(0.7, 0, 0)

fail "arm on the drawer" when r1 touches cab.links["drawer1"]
fail "drawer on the arm" when cab.links["drawer1"] touches r1
"""


def test_an_arm_touching_a_link_reads_the_link_s_own_geoms_in_mujoco_and_pybullet(tmp_path):
    """`r1 touches cab.links["drawer1"]` (either way round): minus the least distance between the arm's
    moving geoms and drawer1's own, all pairs by mj_geomDistance; pybullet within 2 mm (its own shapes)."""
    (tmp_path / "arm.prs").write_text(ARM)
    assert main(["compile", str(tmp_path / "arm.prs"), "-n", "1", "--target", "json,mjcf,sdf", "-o", str(tmp_path / "out")]) == 0
    root = tmp_path / "out" / "arm"
    scene, model, data = _mujoco(root)
    status = TaskMonitor(scene, model).update(model, data)
    drawer = model.body("cab/drawer1").id
    arm = [b for b in range(model.nbody) if model.body(b).name.startswith("r1/") and model.body_weldid[b] != 0]
    collides = (model.geom_contype != 0) | (model.geom_conaffinity != 0)
    ours = np.flatnonzero(collides & (model.geom_bodyid == drawer))
    theirs = np.flatnonzero(collides & np.isin(model.geom_bodyid, arm))
    assert len(ours) >= 5 and len(theirs) > 5
    least = min(mujoco.mj_geomDistance(model, data, int(a), int(b), 1.0, None) for a in theirs for b in ours)
    assert status.robustness["fail:arm on the drawer"] == pytest.approx(least, abs=1e-9)
    assert status.robustness["fail:drawer on the arm"] == pytest.approx(least, abs=1e-9)
    client = pybullet.connect(pybullet.DIRECT)
    try:
        bullet = PybulletTask.load(root / "sdf" / "00000.sdf", client).update(0.0)
    finally:
        pybullet.disconnect(client)
    for key in ("fail:arm on the drawer", "fail:drawer on the arm"):
        assert bullet.robustness[key] == pytest.approx(least, abs=2e-3)


def test_furniture_touches_with_its_carcass_and_a_robot_with_its_moving_links_only(compiled):
    """`c1 touches cab` counts the cabinet's fixed carcass (a cube resting on its top touches it), in
    MuJoCo and in pybullet; only a robot's base is left out (it rests where it was placed)."""
    scene, model, data = _mujoco(compiled)
    task = Task.from_json(scene["task"])
    assert task.object("cab").robot is False and Task.from_json(task.to_json()) == task
    carcass = model.body("cab/carcass").id
    assert model.body_weldid[carcass] == 0  # welded to the world: the old rule dropped it
    geoms = [g for g in range(model.ngeom) if model.geom_bodyid[g] == carcass]
    tops = [data.geom_xpos[g][2] + model.geom_size[g][2] for g in geoms]  # boxes, axis-aligned
    top = geoms[int(np.argmax(tops))]
    qpos = model.jnt_qposadr[model.body("c1").jntadr[0]]
    data.qpos[qpos:qpos + 3] = [data.geom_xpos[top][0], data.geom_xpos[top][1], max(tops) + 0.02 + 1e-4]
    data.qpos[qpos + 3:qpos + 7] = [1, 0, 0, 0]
    mujoco.mj_forward(model, data)
    monitor = TaskMonitor(scene, model)
    assert carcass in set(model.geom_bodyid[monitor.world.geoms["cab"]].tolist())
    distance = monitor.state(model, data).distance("c1", "cab")
    assert distance == pytest.approx(1e-4, abs=1e-6)  # 0.1 mm above the top: the carcass, not the drawer
    evaluator = Evaluator(task)
    touches = Term("touches", (Term("object", name="c1"), Term("object", name="cab")))
    assert evaluator.robustness(touches, monitor.state(model, data)) == pytest.approx(-1e-4, abs=1e-6)
    client = pybullet.connect(pybullet.DIRECT)
    try:
        bullet = PybulletTask.load(compiled / "sdf" / "00000.sdf", client)
        position = data.body("c1").xpos
        pybullet.resetBasePositionAndOrientation(bullet.bodies["c1"], position.tolist(), [0, 0, 0, 1], physicsClientId=client)
        assert bullet.distance("c1", "cab") == pytest.approx(1e-4, abs=2e-3)
    finally:
        pybullet.disconnect(client)
