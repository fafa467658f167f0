"""specs/bin_picking.prs beyond its rows (compiled, settled and checked in
tests/specs/test_example_specs.py): the loop's eight objects and their class default yaws."""

from __future__ import annotations

import math
from pathlib import Path

from prsc.ir import compile_program
from prsc.ir import model as ir
from prsc.sampling import Sampler

SPEC = Path(__file__).resolve().parents[2] / "specs" / "bin_picking.prs"
LOOP_OBJECTS = [f"{kind}_{k}" for k in range(4) for kind in ("part", "can")]


def test_the_loop_declares_eight_objects_with_class_default_yaws():
    program = compile_program(str(SPEC))
    declared = {o.name: o for o in program.objects}
    assert [o.name for o in program.objects if o.name in LOOP_OBJECTS] == LOOP_OBJECTS
    draws = set()
    for name in LOOP_OBJECTS:
        specs = declared[name].specifiers
        (facing,) = [s for s in specs if isinstance(s, ir.Facing)]
        draws.add(facing.direction.draw_id)
        assert any(isinstance(s, ir.On) and s.completely and s.target.name == "bin_1" for s in specs)
    assert len(draws) == 8  # one yaw drawn per object


def test_every_loop_object_of_every_scene_has_its_own_yaw():
    sampler = Sampler(compile_program(str(SPEC)), "exact")
    yaws = set()
    for index in range(10):
        for obj in sampler.sample(0, index).objects:
            if obj.name in LOOP_OBJECTS:
                forward = obj.rotation[:, 1]
                yaws.add(round(math.atan2(-forward[0], forward[1]), 6))
    assert len(yaws) == 80
