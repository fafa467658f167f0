"""Containers' interiors in the constraint rows: where `on X` rests, and what is refused."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from prsc.errors import PrscError
from prsc.ir import compile_program
from prsc.sampling import Sampler
from tests.sampling.scene_checks import check_scenes

REPO = Path(__file__).resolve().parents[2]
GUIDE = REPO / "docs" / "language.md"


def _program(tmp_path: Path, text: str):
    spec = tmp_path / "spec.prs"
    spec.write_text(text, encoding="utf-8")
    return compile_program(str(spec), (str(REPO / "specs"),))


def test_the_guides_box_and_round_containers_hold_their_contents(tmp_path):
    example = next(b for b in re.findall(r"```prs\n(.*?)```", GUIDE.read_text(), re.S) if "floorThickness" in b)
    program = _program(tmp_path, example)
    sampler = Sampler(program, "exact")
    scenes = [sampler.scene(0, i) for i in range(200)]
    report = check_scenes(program, scenes)  # floor, 16-gon interior, no other collisions
    assert not report, report
    for scene in scenes:
        objects = {o["name"]: o for o in scene["objects"]}
        pail, ball = objects["pail"], objects["ball"]
        # Inside the pail's box, below its rim: the ball is in it, not on it.
        assert ball["position"][2] + ball["dimensions"][2] / 2 < pail["position"][2] + pail["dimensions"][2] / 2


@pytest.mark.parametrize(("declaration", "message"), [
    ("class Crate:\n    width: 0.3\n    length: 0.3\n    height: 0.2\n    container: \"box\"\n    floorThickness: 0.01\n"
     "crate = Crate completely on t\n", "missing wallThickness"),
    ("crate = Tray completely on t, with floorThickness (0.01, 0.02)\n", "floorThickness must be constants"),
    ("crate = Tray completely on t, with container \"oval\"\n", "container must be one of box, round"),
])
def test_a_bad_container_declaration_is_an_error_at_its_line(tmp_path, declaration, message):
    text = "from tabletop import *\nt = Table on Vector3D(0, 0, 0)\n" + declaration + "cube = Cube completely on crate\n"
    with pytest.raises(PrscError, match=message) as caught:
        Sampler(_program(tmp_path, text), "exact").scene(0, 0)
    assert caught.value.span is not None
