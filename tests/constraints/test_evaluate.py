"""The expression evaluator over hand-built IR (no front end involved)."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from prsc.constraints.context import SceneContext
from prsc.constraints.evaluate import ExprCompiler
from prsc.constraints.values import ObjectValue, OrientedPoint
from prsc.errors import PrscError, Span
from prsc.ir import model as ir
from prsc.ir.program import Program, Variable

S = Span("hand.prs", 3, 5, 3, 9)
T = ir.Type


def num(v):
    return ir.Const(S, T.SCALAR, float(v))


def vec(x, y, z):
    return ir.VectorExpr(S, T.VECTOR, num(x), num(y), num(z))


def binop(op, left, right, typ=T.SCALAR):
    return ir.BinOp(S, typ, op, left, right)


def rng_range(lo, hi, draw_id):
    return ir.Distribution(S, T.SCALAR, "range", (num(lo), num(hi)), draw_id)


def program(variables=()):
    return Program("hand.prs", (), tuple(variables), (), (), None)


def compiler(variables=()):
    return ExprCompiler(program(variables))


def ctx(seed=0, objects=()):
    c = SceneContext(np.random.default_rng(seed))
    for o in objects:
        c.objects[o.name] = o
    return c


def box(name="t", pos=(1.0, 2.0, 0.5), rot=None, dims=(2.0, 1.0, 0.4)):
    return ObjectValue(name, "Table", S, np.array(pos), np.eye(3) if rot is None else rot, dims)


def test_arithmetic_on_constants_is_folded():
    c = compiler().compile(binop("+", vec(1, 2, 3), binop("*", vec(1, 1, 1), num(2), T.VECTOR), T.VECTOR))
    assert c.const
    np.testing.assert_allclose(c.value, [3, 4, 5])


def test_division_by_zero_is_a_user_error_with_its_span():
    with pytest.raises(PrscError) as info:
        compiler().compile(binop("/", num(1), num(0)))
    assert info.value.span == S


def test_a_distribution_is_drawn_once_per_scene_and_shared_by_its_uses():
    d = rng_range(0, 1, draw_id=7)
    c = compiler().compile(binop("-", d, d))
    assert not c.const
    assert c.fn(ctx()) == 0.0
    a = compiler().compile(d).fn
    first = a(ctx(seed=1))
    assert 0 <= first < 1 and a(ctx(seed=1)) == first and a(ctx(seed=2)) != first


def test_a_random_variable_is_one_value_per_scene():
    var = Variable("x", rng_range(2, 3, draw_id=1), S)
    comp = compiler([var])
    ref = ir.VarRef(S, T.SCALAR, "x")
    total = comp.compile(binop("-", ref, ref))
    scene = ctx(5)
    assert total.fn(scene) == 0.0
    assert 2 <= scene.variables["x"] < 3


def test_rollback_forgets_only_later_draws():
    c = compiler()
    early, late = c.compile(rng_range(0, 1, 1)).fn, c.compile(rng_range(0, 1, 2)).fn
    scene = ctx(3)
    scene.level = 0
    a = early(scene)
    scene.level = 1
    b = late(scene)
    scene.rollback(1)
    assert 1 in scene.draws and 2 not in scene.draws
    assert early(scene) == a and late(scene) != b


@pytest.mark.parametrize(
    "words, offset",
    [
        (("top",), (0, 0, 0.2)),
        (("back", "right"), (1.0, -0.5, 0)),  # the original returned the front-left point here
        (("top", "front", "left"), (-1.0, 0.5, 0.2)),
        (("bottom",), (0, 0, -0.2)),
    ],
)
def test_face_points_follow_the_words(words, offset):
    yaw = 0.3
    rot = np.array([[math.cos(yaw), -math.sin(yaw), 0], [math.sin(yaw), math.cos(yaw), 0], [0, 0, 1]])
    t = box(rot=rot)
    fp = compiler().compile(ir.FacePoint(S, T.ORIENTED_POINT, ir.ObjectRef(S, T.OBJECT, "t"), words))
    point = fp.fn(ctx(objects=[t]))
    assert isinstance(point, OrientedPoint)
    np.testing.assert_allclose(point.position, t.position + rot @ np.array(offset), atol=1e-12)
    np.testing.assert_array_equal(point.rotation, rot)


def test_relative_to_an_object_uses_its_frame_and_to_a_vector_adds():
    rot = np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]])  # 90 degrees about z
    t = box(rot=rot)
    obj = ir.ObjectRef(S, T.OBJECT, "t")
    c = compiler()
    rel_obj = c.compile(ir.RelativeTo(S, T.VECTOR, vec(1, 0, 0), obj)).fn(ctx(objects=[t]))
    np.testing.assert_allclose(rel_obj, [1, 3, 0.5])
    rel_vec = c.compile(ir.RelativeTo(S, T.VECTOR, vec(1, 0, 0), vec(0, 0, 1)))
    assert rel_vec.const
    np.testing.assert_allclose(rel_vec.value, [1, 0, 1])


def test_properties_of_objects_and_vectors():
    t = box()
    c = compiler()
    obj = ir.ObjectRef(S, T.OBJECT, "t")
    scene = ctx(objects=[t])
    assert c.compile(ir.PropertyRef(S, T.SCALAR, obj, "y")).fn(scene) == 2.0
    assert c.compile(ir.PropertyRef(S, T.SCALAR, vec(4, 5, 6), "z")).value == 6.0
    t.property_fns["width"] = lambda ctx: 2.0
    assert c.compile(ir.PropertyRef(S, T.SCALAR, obj, "width")).fn(scene) == 2.0


def test_distributions_of_every_kind_stay_in_their_support():
    c = compiler()
    kinds = [
        ir.Distribution(S, T.SCALAR, "normal", (num(1), num(0.1)), 1),
        ir.Distribution(S, T.SCALAR, "truncnormal", (num(0), num(1), num(-0.5), num(0.2)), 2),
        ir.Distribution(S, T.ANY, "uniform", (num(1), num(2), num(3)), 3),
        ir.Distribution(S, T.ANY, "discrete", (num(10), num(20)), 4, (num(1), num(0))),
    ]
    fns = [c.compile(k).fn for k in kinds]
    for seed in range(200):
        scene = ctx(seed)
        values = [f(scene) for f in fns]
        assert -0.5 <= values[1] <= 0.2
        assert values[2] in (1.0, 2.0, 3.0)
        assert values[3] == 10.0


def test_math_functions_and_comparisons():
    c = compiler()
    hyp = c.compile(ir.Call(S, T.SCALAR, "hypot", (num(3), num(4))))
    assert hyp.const and hyp.value == 5.0
    cond = c.compile(ir.BoolOp(S, T.BOOL, "and", (ir.Compare(S, T.BOOL, "<", num(1), num(2)), ir.Compare(S, T.BOOL, ">=", num(1), num(2)))))
    assert cond.const and cond.value is False
    with pytest.raises(PrscError):
        c.compile(ir.Call(S, T.SCALAR, "sqrt", (num(-1),)))


def test_regions_evaluate_to_h_representations():
    c = compiler()
    cuboid = ir.RegionExpr(S, T.REGION, "cuboid", (("position", vec(0, 0, 1)), ("orientation", vec(0, 0, 0)), ("width", num(2)), ("length", num(4)), ("height", num(2))))
    region = c.compile(cuboid).value
    assert region.poly.contains(np.array([0.9, 1.9, 1.9])) and not region.poly.contains(np.array([1.1, 0, 1]))
    rect = ir.RegionExpr(S, T.REGION, "rectangle", (("position", vec(0, 0, 0)), ("orientation", vec(0, 0, 0)), ("width", num(5)), ("length", num(5))))
    plane = c.compile(rect).value
    assert plane.planar and np.allclose(plane.normal, [0, 0, 1])


def test_overflow_to_infinity_is_a_user_error_at_the_expression():
    """1e300 * 1e300 is an error where it is written, not an infinite size or coordinate later."""
    with pytest.raises(PrscError, match="too large") as info:
        compiler().compile(binop("*", num(1e300), num(1e300)))
    assert info.value.span == S
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # numpy's overflow warning would print before the error
        with pytest.raises(PrscError, match="too large") as info:
            compiler().compile(binop("*", vec(0, 0, 1e300), num(1e300), T.VECTOR))
    assert info.value.span == S
    drawn = compiler().compile(binop("*", rng_range(1e300, 2e300, draw_id=1), num(1e300)))
    with pytest.raises(PrscError, match="too large"):
        drawn.fn(ctx())
