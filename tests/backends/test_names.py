"""Object names a format cannot hold: mapped the same way in every format (issue 12, item 5)."""

from __future__ import annotations

import json

import mujoco

from prsc.backends.names import element_names
from prsc.cli import main
from tests.backends import readback
from tests.backends.scenes import obj, scene

HOSTILE = ["world", "1abc", "a b", ".", "..", "a\\b", 'a"<b>&', "a_b", "_1abc"]


def test_element_names_are_identifiers_unique_and_stable():
    mapped = element_names(HOSTILE)
    assert mapped == ("world_", "_1abc_2", "a_b_2", "_", "__", "a_b_3", "a__b__", "a_b", "_1abc")
    assert len(set(mapped)) == len(mapped)
    assert element_names(["cube", "tray"]) == ("cube", "tray")  # ordinary names are kept


def test_hostile_names_compile_to_every_format(tmp_path):
    raw = scene([obj(n, "Object", (k * 0.3, 0, 0.5), (0.1, 0.1, 0.1)) for k, n in enumerate(HOSTILE)])
    source = tmp_path / "names.json"
    source.write_text(json.dumps(raw))
    out = tmp_path / "out"
    assert main(["compile", str(source), "--target", "json,mjcf,urdf,sdf,usd", "-o", str(out)]) == 0
    root = out / "names"
    mapped = set(element_names(HOSTILE))
    # The scene JSON keeps the user's names; every format holds the same element names.
    assert [o["name"] for o in json.loads((root / "json" / "00000.json").read_text())["objects"]] == HOSTILE
    model = readback.mjcf_model(root / "mjcf" / "00000.xml")
    assert {model.body(b).name for b in range(1, model.nbody)} == mapped
    mujoco.mj_step(model, mujoco.MjData(model))
    bundle = root / "urdf" / "00000"
    readback.urdf_validate(bundle)
    assert {p.stem for p in bundle.glob("*.urdf")} == mapped | {"ground"}
    assert set(readback.sdf_poses(root / "sdf" / "00000.sdf")) >= mapped
    assert readback.usd_errors(root / "usd" / "00000.usda") == []
    from pxr import Usd

    stage = Usd.Stage.Open(str(root / "usd" / "00000.usda"))
    assert {p.GetName() for p in stage.GetPrimAtPath("/World").GetChildren()} >= mapped


def test_an_object_named_world_passes_check_and_compiles(tmp_path):
    spec = tmp_path / "w.prs"
    spec.write_text("world = Object at Vector3D(0, 0, 1)\n")
    assert main(["check", str(spec)]) == 0
    assert main(["compile", str(spec), "--target", "mjcf,usd", "-o", str(tmp_path / "o")]) == 0
    model = readback.mjcf_model(tmp_path / "o" / "w" / "mjcf" / "00000.xml")
    assert model.body("world_").id == 1
