"""Furniture's support surfaces (`shelf.boards[k]`) and `in X` for a container X: the rows,
checked by the independent scene checker, against the parts the asset recipe builds, and
the errors at the right line."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from prsc.assets.furniture import shelf_parts
from prsc.errors import PrscError
from prsc.ir import compile_program
from prsc.sampling import Sampler
from tests.sampling.scene_checks import check_scenes, quat_matrix

REPO = Path(__file__).resolve().parents[2]
HEAD = "from tabletop import *\nshelf = Shelf on Vector3D(0.2, 0.5, 0), facing 30 deg, with width 0.9, with height 1.3\n"


def _program(tmp_path: Path, text: str):
    spec = tmp_path / "spec.prs"
    spec.write_text(text, encoding="utf-8")
    return compile_program(str(spec), (str(REPO / "specs"),))


def _scenes(program, n: int) -> list[dict]:
    sampler = Sampler(program, "exact")
    return [sampler.scene(3, i) for i in range(n)]


def test_objects_on_every_board_stand_on_the_boards_the_asset_builds(tmp_path):
    text = HEAD + "".join(f"b{k} = Bottle completely on shelf.boards[{k}]\n" for k in range(4))
    program = _program(tmp_path, text)
    scenes = _scenes(program, 60)
    report = check_scenes(program, scenes)  # resting on the board, footprint inside it, under the next
    assert not report and report.checked > 0, report
    for scene in scenes:
        objects = {o["name"]: o for o in scene["objects"]}
        shelf = objects["shelf"]
        rot, centre = quat_matrix(shelf["quaternion"]), np.array(shelf["position"])
        parts = {p.name: p for p in shelf_parts(tuple(shelf["dimensions"]))}
        for k in range(4):
            bottle = objects[f"b{k}"]
            local = rot.T @ (np.array(bottle["position"]) - centre)
            board = parts[f"board_{k}"]
            # The bottle's bottom is the built board's top, its footprint within the board's
            # extent, which lies between the side panels and in front of the back panel.
            assert abs(local[2] - bottle["dimensions"][2] / 2 - (board.position[2] + board.size[2] / 2)) < 1e-9
            for axis in (0, 1):
                reach = bottle["dimensions"][axis] / 2
                assert abs(local[axis] - board.position[axis]) <= board.size[axis] / 2 - reach + 1e-9
            side = parts["side_right"]
            assert local[0] + bottle["dimensions"][0] / 2 <= side.position[0] - side.size[0] / 2 + 1e-9
            if k < 3:  # below the next board
                above = parts[f"board_{k + 1}"]
                assert local[2] + bottle["dimensions"][2] / 2 <= above.position[2] - above.size[2] / 2 + 1e-9


def test_a_tables_top_is_the_same_surface_as_on_the_table(tmp_path):
    text = ("from tabletop import *\ntable = Table on Vector3D(0, 0, 0), with height 0.8\n"
            "a = Cube completely on table.tabletop[0]\nb = Cube completely on table\n")
    program = _program(tmp_path, text)
    scenes = _scenes(program, 30)
    assert not check_scenes(program, scenes)
    for scene in scenes:
        a, b = (o for o in scene["objects"] if o["name"] in "ab")
        assert abs(a["position"][2] - b["position"][2]) < 1e-12


def test_completely_in_a_container_is_completely_on_its_floor(tmp_path):
    body = "bin = Bin at Vector3D(0, 0, 0.1), facing 20 deg\ntray = Tray on floor, right of bin by 0.2\n"
    inside = _program(tmp_path, "from tabletop import *\n" + body + "c = Cube completely in bin\nd = Cube in tray\n")
    on = _program(tmp_path, "from tabletop import *\n" + body + "c = Cube completely on bin\nd = Cube on tray\n")
    a, b = _scenes(inside, 40), _scenes(on, 40)
    assert not check_scenes(inside, a)
    for x, y in zip(a, b):  # the same rows, so the same draws
        assert [o["position"] for o in x["objects"]] == [o["position"] for o in y["objects"]]


@pytest.mark.parametrize(("line", "message"), [
    ("b = Bottle completely on shelf.boards[4]\n", r"shelf.boards has 4 surfaces, indexed 0 to 3"),
    ("b = Bottle completely on shelf.boards\n", r"boards is a list of support surfaces: pick one by its index"),
    ("b = Bottle completely on shelf.sides[0]\n", r"unknown property 'sides'"),
    ("b = Bottle completely on shelf.width[0]\n", r"only a support-surface list can be indexed"),
    ("b = Bottle completely on shelf.boards[1], with height 0.5\n", r"does not fit under the next board"),
    ("t = Table on floor, left of shelf by 0.5\nb = Bottle completely in t\n", r"`completely in t` needs a container"),
    ("cam = Camera at Vector3D(0, -1, 1)\nb = Bottle on floor, facing toward cam, not visible from cam\n",
     r"`not visible from C` needs b's rotation before its position"),
    ("b = Bottle on floor, visible from shelf\n", r"'visible from' needs a camera"),
])
def test_a_bad_surface_container_or_camera_is_an_error_at_its_line(tmp_path, line, message):
    text = HEAD + line
    with pytest.raises(PrscError, match=message) as caught:
        Sampler(_program(tmp_path, text), "exact").scene(0, 0)
    assert caught.value.span is not None and caught.value.span.line == text.count("\n")


@pytest.mark.parametrize("marker", ["shelf.boards[", "completely in bin", "stably on", "visible from camera"])
def test_the_guides_example_samples_and_every_scene_checks(tmp_path, marker):
    blocks = re.findall(r"```prs\n(.*?)```", (REPO / "docs" / "language.md").read_text(), re.S)
    program = _program(tmp_path, next(b for b in blocks if marker in b))
    report = check_scenes(program, _scenes(program, 20))
    assert not report and report.checked > 0, report


def test_the_checker_flags_a_bottle_off_its_board_or_a_box_out_of_view(tmp_path):
    text = (HEAD + "b = Bottle completely on shelf.boards[2]\n"
            "cam = Camera at Vector3D(0, -1, 1.2), facing 0 deg\nc = Cube on floor, visible from cam\n")
    program = _program(tmp_path, text)
    scene = _scenes(program, 1)[0]
    assert not check_scenes(program, [scene])
    objects = {o["name"]: o for o in scene["objects"]}
    for name, axis, shift, words in (("b", 2, 0.01, "not resting on the surface"), ("b", 0, 0.3, "outside the surface"),
                                     ("c", 1, -1.5, "outside the view of cam")):
        moved = {**objects[name], "position": list(objects[name]["position"])}
        moved["position"][axis] += shift
        bad = {**scene, "objects": [moved if o["name"] == name else o for o in scene["objects"]]}
        assert any(words in problem for problem in check_scenes(program, [bad])), (name, words)
