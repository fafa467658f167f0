"""`prsc compile --settle-check`: compiled scenes at rest in MuJoCo, and the causes when not."""

from __future__ import annotations

import json
import re
from pathlib import Path

import mujoco
import numpy as np

from prsc.runner.settle_check import LIMIT, settle_scenes
from prsc.pipeline.output_folder import compiled_scenes
from prsc.cli import main
from prsc.commands.compile import compile_scenes
from prsc.ir import compile_program, model as ir

REPO = Path(__file__).resolve().parents[2]
GUIDE = REPO / "docs" / "language.md"
DATA = Path(__file__).resolve().parents[1] / "data"


def completely_on(spec: Path) -> set[str]:
    """The objects a spec places `completely on` something."""
    program = compile_program(str(spec))
    return {o.name for o in program.objects if any(isinstance(s, ir.On) and s.completely for s in o.specifiers)}


# Every spec's `completely on` objects at rest: tests/backends/test_specs_formats.py, on the
# scenes it compiles anyway. table_cube_naive.prs places its cube with a bare `on` (and
# requires), which keeps it clear of the tray's walls too; a cube across a wall is what
# test_the_settle_check_lists_a_cube_tipping_over_a_wall shows the check listing.


def test_the_cube_on_a_tray_rests_on_its_floor_inside_the_walls(tmp_path):
    root = compile_scenes(str(REPO / "specs" / "table_cube.prs"), ["json", "mjcf"], 3, 0, str(tmp_path / "out"))
    for index in range(3):
        model = mujoco.MjModel.from_xml_path(str(root / "mjcf" / f"{index:05d}.xml"))
        data = mujoco.MjData(model)
        mujoco.mj_forward(model, data)
        cube = model.geom("c1/box").id
        floor = model.geom("tr_1/floor").id
        bottom = data.geom_xpos[cube][2] - model.geom_size[cube][2]
        assert abs(bottom - (data.geom_xpos[floor][2] + model.geom_size[floor][2])) < 1e-6
        # Inside the walls: the cube's footprint between the inner faces (the tray is unrotated).
        lo = data.geom_xpos[cube][:2] - model.geom_size[cube][:2]
        hi = data.geom_xpos[cube][:2] + model.geom_size[cube][:2]
        left, right = (model.geom(f"tr_1/wall_{side}").id for side in ("left", "right"))
        back, front = (model.geom(f"tr_1/wall_{side}").id for side in ("back", "front"))
        assert lo[0] >= data.geom_xpos[left][0] + model.geom_size[left][0] - 1e-9
        assert hi[0] <= data.geom_xpos[right][0] - model.geom_size[right][0] + 1e-9
        assert lo[1] >= data.geom_xpos[back][1] + model.geom_size[back][1] - 1e-9
        assert hi[1] <= data.geom_xpos[front][1] - model.geom_size[front][1] + 1e-9
        # The scene JSON says the same: bottom on the declared floor's top.
        scene = json.loads((root / "json" / f"{index:05d}.json").read_text())
        objects = {o["name"]: o for o in scene["objects"]}
        tray, c1 = objects["tr_1"], objects["c1"]
        floor_top = tray["position"][2] - tray["dimensions"][2] / 2 + tray["properties"]["floorThickness"]
        assert abs(c1["position"][2] - c1["dimensions"][2] / 2 - floor_top) < 1e-6


def _guide_container_example() -> str:
    return next(b for b in re.findall(r"```prs\n(.*?)```", GUIDE.read_text(), re.S) if "floorThickness" in b)


def test_the_guides_own_container_class_is_at_rest(tmp_path, capsys):
    spec = tmp_path / "baskets.prs"
    spec.write_text(_guide_container_example())
    assert main(["compile", str(spec), "-t", "json,mjcf", "-n", "3", "-o", str(tmp_path / "out"), "--settle-check"]) == 0
    out = capsys.readouterr().out
    assert out.count("(at rest)") == 3 and "3 of 3 scenes at rest" in out


def test_an_unknown_model_for_a_declared_container_shows_in_the_settle_check(tmp_path, capsys):
    spec = tmp_path / "baskets.prs"
    spec.write_text(_guide_container_example().replace("    color: 'brown'\n", "    color: 'brown'\n    model: \"wickerbasket\"\n"))
    code = main(["compile", str(spec), "-t", "json,mjcf", "-n", "2", "-o", str(tmp_path / "out"), "--settle-check"])
    assert code == 1
    out, err = capsys.readouterr()
    assert "unknown model 'wickerbasket'" in err
    assert re.search(r"cube moved [\d.]+ mm: placed on the declared floor of basket, whose model 'wickerbasket' is unknown", out)
    assert "0 of 2 scenes at rest" in out


def test_the_settle_check_lists_a_cube_on_a_hollow_trays_rim(tmp_path, capsys):
    # A stored scene JSON of an older prsc: the cube at the tray's rim, no interior declared.
    assert main(["compile", str(DATA / "table_cube_scene.json"), "-t", "json,mjcf", "-o", str(tmp_path / "out"),
                 "--settle-check"]) == 1
    out = capsys.readouterr().out
    assert re.search(r"c1 moved (\d+\.\d) mm: placed on the rim of tr_1 .* hollow: it falls in", out)
    moved = float(re.search(r"c1 moved (\d+\.\d) mm", out).group(1))
    assert moved > 15


def test_the_settle_check_lists_a_cube_tipping_over_a_wall(tmp_path):
    # The sampler keeps a cube `on` a tray clear of its walls (tests/constraints/test_containers.py);
    # a scene written otherwise (by hand, or by a prsc before 2026-11-27) with the cube's centre
    # inside the walls and its footprint across one is what the check lists. Scene 1 is that
    # scene, scene 0 the same as sampled.
    import prsc
    from prsc.geometry.container import declared_interior
    from prsc.geometry.rotations import quat_to_matrix

    scenes = []
    for k in range(2):
        scene = json.loads(json.dumps(prsc.load(REPO / "specs" / "table_cube_naive.prs").scene(4, 0)))
        scene["index"] = k
        objects = {o["name"]: o for o in scene["objects"]}
        tray, cube = objects["tr_1"], objects["c1"]
        if k == 1:  # the centre 5 mm inside the tray's +x wall
            half = declared_interior(tuple(tray["dimensions"]), tray["properties"]).edges()[1][0]
            across = np.array(tray["position"]) + quat_to_matrix(tray["quaternion"])[:, 0] * (half - 0.005)
            cube["position"] = [float(across[0]), float(across[1]), cube["position"][2]]
        scenes.append(scene)
    source = tmp_path / "scenes.jsonl"
    source.write_text("".join(json.dumps(scene) + "\n" for scene in scenes))
    root = compile_scenes(str(source), ["json", "mjcf"], None, 0, str(tmp_path / "out"))
    results = settle_scenes(compiled_scenes(root))
    tipped = [d for r in results for d in r.drifts]
    assert tipped and all(d.name == "c1" and "across a wall of tr_1" in d.cause and d.distance > LIMIT for d in tipped)
    assert [bool(r.drifts) for r in results] == [False, True]
    assert all(r.largest < LIMIT for r in results if not r.drifts)
    assert np.isfinite([r.largest for r in results]).all()


def test_the_settle_check_needs_json_and_mjcf(tmp_path, capsys):
    assert main(["compile", str(REPO / "specs" / "table_cube.prs"), "-t", "mjcf", "-o", str(tmp_path / "out"),
                 "--settle-check"]) == 2
    assert "--target json,mjcf" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_completely_on_a_container_asset_without_a_declared_interior_rests_on_its_floor(tmp_path, capsys):
    """The original project's model library declares no interiors: `completely on` a class
    built as the tray asset (here by the compat `model_name`) rests on the floor the backends
    build; a bare `on` keeps the rim, and the settle check says the object falls in."""
    (tmp_path / "model.prs").write_text(
        "class Tray:\n    width: 0.2364\n    length: 0.4522\n    height: 0.028964\n    model_name: \"Tray\"\n\n"
        "class Table:\n    width: 1.8\n    length: 0.8\n    height: 0.8\n    model_name: \"Table\"\n\n"
        "class Cube:\n    width: 0.0468\n    length: 0.0468\n    height: 0.0468\n    color: \"red\"\n"
    )
    head = "from model import *\n\ntable = Table at Vector3D(0, 0, 0.4)\ntr = Tray completely on table\n"
    inside, rim = tmp_path / "inside.prs", tmp_path / "rim.prs"
    inside.write_text(head + "c = Cube completely on tr\n")
    rim.write_text(head + "c = Cube on tr\n")
    out = tmp_path / "out"
    assert main(["compile", str(inside), "-t", "json,mjcf", "-n", "3", "-o", str(out), "--settle-check"]) == 0
    assert "3 of 3 scenes at rest" in capsys.readouterr().out
    for index in range(3):
        model = mujoco.MjModel.from_xml_path(str(out / "inside" / "mjcf" / f"{index:05d}.xml"))
        data = mujoco.MjData(model)
        mujoco.mj_forward(model, data)
        cube, floor = model.geom("c/box").id, model.geom("tr/floor").id
        bottom = data.geom_xpos[cube][2] - model.geom_size[cube][2]
        assert abs(bottom - (data.geom_xpos[floor][2] + model.geom_size[floor][2])) < 1e-6
    assert main(["compile", str(rim), "-t", "json,mjcf", "-n", "2", "-o", str(out), "--settle-check"]) == 1
    assert re.search(r"c moved [\d.]+ mm: placed on the rim of tr .* hollow: it falls in", capsys.readouterr().out)
