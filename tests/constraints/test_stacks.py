"""`stably on X`: towers whose centres of mass stay over their contacts, as exact rows."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from prsc.constraints.stacks import MARGIN
from prsc.errors import PrscError
from prsc.ir import compile_program
from prsc.sampling import Sampler
from tests.sampling.scene_checks import check_scenes, quat_matrix

REPO = Path(__file__).resolve().parents[2]
TOWER = (
    "from tabletop import *\n"
    "table = Table on Vector3D(0, 0, 0), with height 0.8\n"
    "a = Cube completely on table, facing (0, 360 deg), with width 0.08, with length 0.06\n"
    "b = Cube {word} a, facing (0, 360 deg), with height 0.07\n"
    "c = Cube {word} b, facing (0, 360 deg), with width 0.03, with mass 0.2\n"
    "d = Cube {word} c, facing (0, 360 deg)\n"
)


def _scenes(tmp_path: Path, word: str, n: int = 100):
    spec = tmp_path / f"{word.replace(' ', '_')}.prs"
    spec.write_text(TOWER.format(word=word), encoding="utf-8")
    program = compile_program(str(spec), (str(REPO / "specs"),))
    sampler = Sampler(program, "exact")
    return program, [sampler.scene(5, i) for i in range(n)]


def _worst_overhang(scene: dict) -> float:
    """Over all supports, how far (as a fraction of the face's half-extent) the centre of mass
    of what stands on it reaches towards the contact's edge (1: at the edge)."""
    objects = {o["name"]: o for o in scene["objects"]}
    order = ["a", "b", "c", "d"]
    worst = 0.0
    for k in range(len(order) - 1):
        carried = [objects[n] for n in order[k + 1:]]
        masses = np.array([o["mass"] for o in carried])
        com = (masses[:, None] * np.array([o["position"] for o in carried])).sum(axis=0) / masses.sum()
        for face in (objects[order[k]], objects[order[k + 1]]):
            local = quat_matrix(face["quaternion"]).T @ (com - np.array(face["position"]))
            worst = max(worst, *(abs(local[i]) / (face["dimensions"][i] / 2) for i in (0, 1)))
    return worst


def test_a_stably_stacked_tower_keeps_every_centre_of_mass_over_its_contact(tmp_path):
    program, scenes = _scenes(tmp_path, "stably on")
    report = check_scenes(program, scenes)  # resting, and the checker's own centre-of-mass test
    assert not report and report.checked > 0, report
    worst = max(_worst_overhang(s) for s in scenes)
    assert worst <= 1 - MARGIN + 1e-9
    assert worst > 0.6 * (1 - MARGIN)  # the rows do not hold the tower much tighter than that


def test_a_plain_on_tower_overhangs_and_the_checker_says_so(tmp_path):
    stable, _ = _scenes(tmp_path, "stably on", 1)
    _, naive = _scenes(tmp_path, "on")
    assert max(_worst_overhang(s) for s in naive) > 1.2  # a bare `on` lets the tower lean out
    report = check_scenes(stable, naive)  # the stable spec's relations, on the naive draws
    assert any("centre of mass" in problem for problem in report), report


def test_a_random_mass_in_a_stack_is_an_error_at_its_line(tmp_path):
    spec = tmp_path / "random_mass.prs"
    spec.write_text(TOWER.format(word="stably on").replace("with mass 0.2", "with mass (0.1, 0.3)"))
    with pytest.raises(PrscError, match="its mass must be a constant") as caught:
        Sampler(compile_program(str(spec), (str(REPO / "specs"),)), "exact").scene(0, 0)
    assert caught.value.span is not None and caught.value.span.line == 5
