"""The IR builder: names, classes, types, imports, specifier order, on real and small specs."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from prsc.errors import PrscError
from prsc.ir import compile_program, format_program
from prsc.ir import model as ir
from prsc.ir.program import ObjectDecl, Program, SelfRef
from prsc.ir.walk import walk
from tests.original import ORIGINAL, needs_original, original_params

REPO = Path(__file__).resolve().parents[2]
H = "from tabletop import *\n"


def compile_text(tmp_path, text: str, name: str = "spec.prs", **kwargs) -> Program:
    """Compile a spec written to tmp_path."""
    path = tmp_path / name
    path.write_text(text)
    return compile_program(str(path), **kwargs)


def obj(program: Program, name: str) -> ObjectDecl:
    return next(o for o in program.objects if o.name == name)


def all_exprs(program: Program):
    for o in program.objects:
        for _, e in o.properties:
            yield from walk(e)
        for s in o.specifiers:
            for value in vars(s).values():
                if isinstance(value, ir.Expr):
                    yield from walk(value)
    for v in program.variables:
        yield from walk(v.value)
    for r in program.requires:
        yield from walk(r.condition)


@pytest.mark.parametrize("path", original_params() + sorted((REPO / "specs").glob("*.prs"))
                         + sorted((REPO / "prsc" / "library").glob("*.prs")),
                         ids=lambda p: p.name)
def test_shipped_specs_compile(path):
    program = compile_program(str(path))
    assert format_program(program)


def test_table_cube_objects_in_statement_order():
    program = compile_program(str(REPO / "specs" / "table_cube.prs"))
    assert [o.name for o in program.objects] == ["table", "r1", "r2", "tr_1", "tr_2", "c1", "camera"]
    assert [o.class_name for o in program.objects] == ["Table", "Robot", "Robot", "Tray", "Tray", "Cube", "Camera"]
    table = obj(program, "table")
    assert [type(s).__name__ for s in table.specifiers] == ["With", "With", "With", "On"]
    assert table.prop("width").value == 1.8 and table.prop("static").value is True
    tray = obj(program, "tr_1")
    assert tray.depends_on == ("table", "r1")
    on, ahead, left = tray.specifiers
    assert isinstance(on, ir.On) and on.completely and on.reads == ("width", "length", "height", "orientation")
    assert isinstance(ahead, ir.Direction) and ahead.relation == "ahead" and ahead.by.value == 0.1
    assert isinstance(left.target, ir.FacePoint) and left.target.words == ("top",)
    camera = obj(program, "camera")
    assert camera.prop("camera").value is True and camera.prop("model").value == "camera"
    at = camera.specifiers[0]
    assert isinstance(at.point, ir.VectorExpr) and isinstance(at.point.z, ir.Distribution)
    assert program.workspace is not None and program.workspace.kind == "cuboid"


@needs_original
def test_original_table_cube_keeps_compat_names():
    program = compile_program(str(ORIGINAL / "tableCube.prs"))
    robot = obj(program, "r1")
    assert robot.prop("model_name").value == "Panda"
    assert robot.prop("color").value == "0.5"
    assert obj(program, "c1").prop("shape_type").value == "CUBOID"
    point = robot.specifiers[0].target
    assert point.type == ir.Type.VECTOR and isinstance(point.left, ir.PropertyRef)
    assert point.left.target.words == ("top", "back")


def test_draw_ids_are_unique_and_class_defaults_are_fresh_per_object(tmp_path):
    program = compile_text(tmp_path, H + "class Rnd(Cube):\n    width: (0.1, 0.2)\n    length: self.width\n"
                                          "a = Rnd\nb = Rnd\nx = (0, 1)\ny = (0, 1)\n")
    draws = [e for e in all_exprs(program) if isinstance(e, ir.Distribution)]
    a_width, b_width = obj(program, "a").prop("width"), obj(program, "b").prop("width")
    assert a_width.draw_id != b_width.draw_id
    ids = [d.draw_id for d in draws]
    assert len(set(ids)) == len(ids)
    length = obj(program, "a").prop("length")
    assert length == ir.PropertyRef(length.span, ir.Type.SCALAR, ir.ObjectRef(length.span, ir.Type.OBJECT, "a"), "width")
    names = [k for k, _ in obj(program, "a").properties]
    assert names.index("width") < names.index("length")


def test_with_overrides_the_default_and_stays_a_specifier(tmp_path):
    program = compile_text(tmp_path, H + "c = Cube with width 0.5, with length (0.2, 0.4)\n")
    c = obj(program, "c")
    assert c.prop("width").value == 0.5
    assert isinstance(c.prop("length"), ir.Distribution)
    withs = [s for s in c.specifiers if isinstance(s, ir.With)]
    assert [w.prop for w in withs] == ["width", "length"]
    assert withs[1].value is c.prop("length")


def test_anonymous_objects_are_named_by_class_and_skip_taken_names(tmp_path):
    program = compile_text(tmp_path, H + "Cube\nCube at Vector3D(0, 0, 1)\ncube_2 = Tray\n")
    assert [o.name for o in program.objects] == ["cube_1", "cube_3", "cube_2"]
    assert [o.anonymous for o in program.objects] == [True, True, False]


def test_deg_relative_to_and_ranges(tmp_path):
    program = compile_text(tmp_path, H + "t = Table\nc = Cube at Vector3D(0, 0.1, 0) relative to t, "
                                          "facing 30 deg\nd = Cube facing (0, 360 deg)\n")
    at, facing = obj(program, "c").specifiers
    assert isinstance(at, ir.At) and isinstance(at.point, ir.RelativeTo)
    assert at.point.frame == ir.ObjectRef(at.point.frame.span, ir.Type.OBJECT, "t")
    assert facing.direction.value == pytest.approx(math.pi / 6)
    yaw = obj(program, "d").specifiers[0].direction
    assert yaw.kind == "range" and yaw.args[1].value == pytest.approx(2 * math.pi)


def test_facing_toward_breaks_the_false_cycle_with_the_orientation_free_bound(tmp_path):
    program = compile_text(tmp_path, H + "t = Table\nc = Cube facing toward t, completely on t, left of t\n")
    specs = obj(program, "c").specifiers
    assert [type(s).__name__ for s in specs] == ["On", "Direction", "FacingToward"]
    assert all(s.orientation_free and "orientation" not in s.reads for s in specs[:2])
    assert specs[2].reads == ("position",) and not specs[2].orientation_free


def test_specifier_order_follows_reads_and_sets(tmp_path):
    program = compile_text(tmp_path, H + "t = Table\nc = Cube on t, facing 1.0, with width 0.2\n")
    assert [type(s).__name__ for s in obj(program, "c").specifiers] == ["Facing", "With", "On"]


def test_dependency_cycle_names_both_specifiers():
    from prsc.errors import Span
    from prsc.ir.order import order_specifiers

    span_a, span_b = Span("s.prs", 1, 1, 1, 5), Span("s.prs", 2, 1, 2, 5)
    const = ir.Const(span_a, ir.Type.SCALAR, 1.0)
    a = ir.With(span_a, ("width",), ("height",), "width", const)
    b = ir.With(span_b, ("height",), ("width",), "height", const)
    with pytest.raises(PrscError) as caught:
        order_specifiers([a, b])
    assert "cycle" in caught.value.message
    assert "with width 1" in caught.value.message and "with height 1" in caught.value.message
    assert {caught.value.span.line, caught.value.notes[0][1].line} == {1, 2}


def test_variables_rebinding_and_random_values(tmp_path):
    program = compile_text(tmp_path, H + "x = (0, 1)\ny = x + x\nx = 2\nc = Cube at Vector3D(x, y, 0)\n")
    assert [v.name for v in program.variables][-3:] == ["x", "y", "x#2"]
    y = next(v for v in program.variables if v.name == "y").value
    assert (y.left.name, y.right.name, y.left.type) == ("x", "x", ir.Type.SCALAR)
    at = obj(program, "c").specifiers[0]
    assert at.point.x.name == "x#2"


def test_object_aliases_and_dependencies_through_variables(tmp_path):
    program = compile_text(tmp_path, H + "t = Table\nsame = t\nh = t.height\nc = Cube on same, with height h\n")
    c = obj(program, "c")
    assert c.specifiers[-1].target.name == "t"
    assert c.depends_on == ("t",)


def test_requires_params_and_workspace(tmp_path):
    program = compile_text(tmp_path, H + "param ground = False, label = 'a'\nt = Table\n"
                                          "require t.x < 1 < 2\nrequire[0.25] t.y > 0\nworkspace = All()\n")
    assert [(p.name, p.value.value) for p in program.params] == [("ground", False), ("label", "a")]
    chain, soft = program.requires
    assert chain.probability == 1.0 and isinstance(chain.condition, ir.BoolOp) and len(chain.condition.operands) == 2
    assert soft.probability == 0.25
    assert program.workspace.kind == "all"


def test_math_module_and_functions(tmp_path):
    program = compile_text(tmp_path, "import math\nx = math.sin(math.pi / 2) + sqrt(4) + max(1, 2, 3)\n")
    value = program.variables[0].value
    calls = [e.func for e in walk(value) if isinstance(e, ir.Call)]
    assert sorted(calls) == ["max", "sin", "sqrt"]
    assert any(isinstance(e, ir.Const) and e.value == pytest.approx(math.pi) for e in walk(value))


def test_regions_are_normalised(tmp_path):
    program = compile_text(tmp_path, (
        "a = Cuboid(Vector3D(0, 0, 1), Vector3D(0, 0, 0), Vector3D(1, 2, 3))\n"
        "b = Rectangle3D(1, 2, Vector3D(0, 0, 0), Vector3D(0, 0, 0))\n"
        "c = Rect3D(Vector3D(0, 0, 0), Vector3D(0, 0, 0), Vector3D(1, 2, 0))\n"
        "d = HalfSpace(Vector3D(0, 0, 0), Vector3D(0, 0, 1))\n"
        "e = ConvexPolygon3D([Vector3D(0, 0, 0), Vector3D(1, 0, 0), Vector3D(0, 1, 0)])\n"
        "f = ConvexPolyhedron([Vector3D(0, 0, 0), Vector3D(1, 0, 0), Vector3D(0, 1, 0), Vector3D(0, 0, 1)])\n"
        "g = Intersection(a, d)\nh = Empty()\n"
        "i = Uniform(1, 2)\nj = Discrete({1: 0.5, 2: 1.5})\nk = Options([1, 2])\nl = Normal(0, 1)\n"
        "m = TruncatedNormal(0, 1, -1, 1)\n"))
    v = {x.name: x.value for x in program.variables}
    assert v["a"].kind == "cuboid" and v["a"].arg("height").value == 3
    assert v["b"].kind == "rectangle" and v["b"].arg("length").value == 2
    assert v["c"].kind == "rectangle" and v["c"].arg("width").value == 1
    assert v["d"].kind == "halfspace" and v["d"].arg("dist").value == 0
    assert v["e"].kind == "polygon" and v["f"].kind == "polyhedron"
    assert v["g"].kind == "intersection" and len(v["g"].arg("regions").items) == 2
    assert v["h"].kind == "empty"
    assert (v["i"].kind, v["j"].kind, v["k"].kind) == ("uniform", "discrete", "uniform")
    assert [w.value for w in v["j"].weights] == [0.5, 1.5]
    assert (v["l"].kind, v["m"].kind) == ("normal", "truncnormal")


def test_imports_search_next_to_file_then_include_dirs(tmp_path):
    lib = tmp_path / "lib"
    lib.mkdir()
    (lib / "parts.prs").write_text("size = 0.3\nclass Widget:\n    width: size\n")
    (tmp_path / "local.prs").write_text("class Gadget(Widget):\n    height: 0.2\n")
    with pytest.raises(PrscError):
        compile_text(tmp_path, "from parts import *\nWidget\n")
    program = compile_text(tmp_path, "from parts import *\nfrom local import *\nGadget\nimport parts\n"
                                     "s = parts.size\n", include_dirs=[str(lib)])
    gadget = program.objects[0]
    assert gadget.class_chain == ("Gadget", "Widget", "Object")
    assert gadget.prop("width").name == "size" and gadget.prop("height").value == 0.2
    assert program.variables[-1].value.name == "size"
    assert len(program.source_files) == 3


def test_an_include_dir_that_is_not_a_folder_is_an_error(tmp_path):
    """A mistyped --include is reported, even when no import needs it."""
    with pytest.raises(PrscError) as caught:
        compile_text(tmp_path, "x = 1\n", include_dirs=[str(tmp_path / "nowhere")])
    assert caught.value.message == f"--include {tmp_path / 'nowhere'}: no such folder"
    (tmp_path / "a_file").write_text("")
    with pytest.raises(PrscError, match="is not a folder"):
        compile_text(tmp_path, "x = 1\n", include_dirs=[str(tmp_path / "a_file")])


def test_import_cycle_names_the_chain(tmp_path):
    (tmp_path / "a.prs").write_text("from b import *\n")
    (tmp_path / "b.prs").write_text("from a import *\n")
    with pytest.raises(PrscError) as caught:
        compile_text(tmp_path, "from a import *\n", name="main.prs")
    assert caught.value.message == "import cycle: a.prs -> b.prs -> a.prs"
    assert caught.value.span.path.endswith("b.prs")


def test_a_file_imported_twice_runs_once(tmp_path):
    (tmp_path / "base.prs").write_text("class Thing:\n    width: 1\n")
    (tmp_path / "mid.prs").write_text("from base import *\n")
    program = compile_text(tmp_path, "from base import *\nfrom mid import *\nThing\n")
    assert [c.name for c in program.classes].count("Thing") == 1


def test_object_builtin_defaults(tmp_path):
    program = compile_text(tmp_path, "Object\n")
    o = program.objects[0]
    assert o.name == "object_1"
    assert {k: e.value for k, e in o.properties} == {
        "width": 1.0, "length": 1.0, "height": 1.0, "allowCollisions": False, "shape": "box", "camera": False}


@needs_original
def test_every_expression_is_typed_and_no_selfref_survives():
    program = compile_program(str(ORIGINAL / "tableCubeNaive.prs"))
    for e in all_exprs(program):
        assert isinstance(e.type, ir.Type)
        assert not isinstance(e, SelfRef)
    assert len(program.requires) == 14
