"""The scene JSON writer: schema, compat property mapping, colours, masses."""

from __future__ import annotations

from pathlib import Path

import pytest

from prsc.errors import PrscError
from prsc.ir import compile_program
from prsc.sampling import Sampler, compile_sampler
from prsc.sampling.scene_json import color_rgba
from tests.original import ORIGINAL, needs_original

REPO = Path(__file__).resolve().parents[2]
KEYS = ["name", "class", "position", "quaternion", "dimensions", "static", "mass", "color", "shape", "model", "camera", "properties"]


@needs_original
def test_original_table_cube_maps_compat_properties():
    scene = compile_sampler(str(ORIGINAL / "tableCube.prs")).scene(0, 0)
    assert scene["format"] == "prsc-scene" and scene["version"] == 1
    assert scene["seed"] == 0 and scene["index"] == 0 and scene["params"] == {"ground": True}
    objects = {o["name"]: o for o in scene["objects"]}
    assert list(objects) == ["table", "r1", "r2", "tr_1", "tr_2", "c1", "camera"]
    for o in objects.values():
        # an arm (the library Panda is a file arm) also lists its joints (docs/scene-json.md)
        assert list(o) == KEYS + (["joints"] if o["name"] in ("r1", "r2") else [])
        assert len(o["position"]) == 3 and len(o["quaternion"]) == 4 and len(o["color"]) == 4
    assert objects["r1"]["model"] == "panda" and objects["r1"]["static"] is True
    assert objects["r1"]["color"] == [0.5, 0.5, 0.5, 1.0] and objects["r2"]["color"] == [1.0, 1.0, 1.0, 1.0]
    assert objects["table"]["model"] == "table" and objects["table"]["mass"] == pytest.approx(500 * 1.8 * 0.8 * 0.8)
    assert objects["tr_1"]["model"] == "tray" and objects["tr_1"]["static"] is False
    assert objects["tr_1"]["color"] == [0.75, 0.75, 0.75, 1.0]
    assert objects["c1"]["shape"] == "box" and objects["c1"]["model"] == "cube" and objects["c1"]["color"] == [0.0, 0.0, 1.0, 1.0]
    cam = objects["camera"]
    assert cam["model"] == "camera" and cam["static"] is True
    assert cam["camera"] == {"fovy": 60.0, "resolution": [640, 480]}
    # facing Vector3D(0, 0, -1): local +y turned to -z, a -90 degree turn about x
    assert cam["quaternion"] == pytest.approx([2**-0.5, -(2**-0.5), 0.0, 0.0])


def test_anonymous_objects_shapes_extra_properties_and_params(tmp_path):
    spec = tmp_path / "anon.prs"
    spec.write_text(
        "class Can:\n"
        "    width: 0.1\n"
        "    length: 0.1\n"
        "    height: 0.2\n"
        "    shape_type: 'CYLINDER'\n"
        "    color: [0.1, 0.2, 0.3]\n"
        "    label: 'soup'\n"
        "    mass: 0.4\n"
        "param ground = False\n"
        "param lighting = 'dim'\n"
        "Can at Vector3D(0, 0, 0.1)\n"
        "Can at Vector3D(1, 0, 0.1), with static True, with color 'r'\n"
    )
    scene = Sampler(compile_program(str(spec), ())).scene(0, 0)
    assert scene["params"] == {"ground": False, "lighting": "dim"}
    a, b = scene["objects"]
    assert (a["name"], b["name"]) == ("can_1", "can_2")
    assert a["shape"] == "cylinder" and a["model"] is None and a["mass"] == 0.4
    assert a["color"] == [0.1, 0.2, 0.3, 1.0] and a["properties"] == {"label": "soup"}
    assert b["static"] is True and b["color"] == [1.0, 0.0, 0.0, 1.0]


def test_colours():
    assert color_rgba("brown") == [0.55, 0.35, 0.17, 1.0]
    assert color_rgba("0.25") == [0.25, 0.25, 0.25, 1.0]
    assert color_rgba([1, 0, 0, 0.5]) == [1.0, 0.0, 0.0, 0.5]
    assert color_rgba("#00ff00") == [0.0, 1.0, 0.0, 1.0]
    with pytest.raises(PrscError):
        color_rgba("not-a-colour")
    with pytest.raises(PrscError):
        color_rgba("1.5")


@pytest.mark.parametrize("props,message", [
    ('with color "nocolour"', "unknown colour 'nocolour' of c"),
    ('with color "3"', "grey level '3' of c is not in [0, 1]"),
    ('with shape "cone"', "unknown shape 'cone'"),
    ("with mass -5", "mass of c must be a number >= 0 (kg), got -5.0"),
    ("with camera True, with fovy 200", "fovy of c must be an angle in (0, 180) degrees, got 200.0"),
    ('with camera True, with resolution [640, "a"]', "resolution of c must be [width, height] in whole pixels"),
    ("with camera True, with resolution [640.5, 480]", "resolution of c must be [width, height] in whole pixels"),
])
@pytest.mark.parametrize("width", ["0.1", "(0.1, 0.2)"], ids=["same_every_scene", "random"])
def test_bad_property_values_are_errors_at_the_object(tmp_path, props, message, width):
    spec = tmp_path / "props.prs"
    spec.write_text(f"x = 1\nc = Object at Vector3D(0, 0, 1), with width {width}, {props}\n")
    with pytest.raises(PrscError) as info:
        compile_sampler(str(spec)).scene(0, 0)
    assert message in info.value.message
    # A constant mass is checked by the front end, at the value; the others at the object.
    column = spec.read_text().splitlines()[1].index("-5") + 1 if "mass" in props else 1
    assert (info.value.span.path, info.value.span.line, info.value.span.column) == (str(spec), 2, column)


def test_scene_lists_every_object_class_with_its_ancestors(tmp_path):
    spec = tmp_path / "sub.prs"
    spec.write_text(
        "from tabletop import *\n"
        "class RedCube(Cube):\n"
        "    color: 'red'\n"
        "table = Table on Vector3D(0, 0, 0)\n"
        "c = RedCube completely on table\n"
    )
    scene = compile_sampler(str(spec)).scene(0, 0)
    assert scene["classes"] == {"Table": ["Object"], "RedCube": ["Cube", "Object"]}
    assert [o["class"] for o in scene["objects"]] == ["Table", "RedCube"]
