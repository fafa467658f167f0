"""The parser: every construct of docs/language.md parses to the expected AST, with spans."""

from __future__ import annotations

from pathlib import Path

import pytest

from prsc.errors import PrscError
from prsc.syntax import nodes as n
from prsc.syntax import parse_file, parse_source
from tests.original import original_params

SPECS = Path(__file__).resolve().parents[2] / "specs"


def one(source: str) -> n.Statement:
    """The single statement of a source text."""
    module = parse_source(source, "t.prs")
    assert len(module.statements) == 1, module.statements
    return module.statements[0]


@pytest.mark.parametrize("path", original_params() + sorted(SPECS.glob("*.prs"))
                         + sorted((SPECS.parent / "prsc" / "library").glob("*.prs")), ids=lambda p: p.name)
def test_every_shipped_spec_parses(path):
    module = parse_file(path)
    assert module.statements


def test_object_statement_with_specifiers_and_spans():
    s = one("tr_1 = Tray completely on t, ahead of r1 by 0.1, left of (top t) by 0.2\n")
    assert isinstance(s, n.ObjectStmt)
    assert (s.name, s.class_name) == ("tr_1", "Tray")
    on, ahead, left = s.specifiers
    assert isinstance(on, n.OnSpec) and on.completely and on.target == n.Name(on.target.span, "t")
    assert (on.span.line, on.span.column, on.span.end_column) == (1, 13, 28)
    assert isinstance(ahead, n.DirectionSpec) and ahead.relation == "ahead"
    assert isinstance(ahead.by, n.Number) and ahead.by.value == 0.1
    assert isinstance(left.target, n.FacePoint) and left.target.words == ("top",)


def test_trailing_comma_continues_the_statement_on_indented_lines():
    module = parse_source("tr_2 = Tray completely on t,\n      ahead of r2,\n      right of t\n\nCube on tr_2\n", "t.prs")
    first, second = module.statements
    assert len(first.specifiers) == 3
    assert first.specifiers[2].span.line == 3
    assert isinstance(second, n.ObjectStmt) and second.name is None


def test_newlines_inside_brackets_are_ignored():
    s = one("Camera at V3D((-0.1, 0.1),\n              (-0.1, 0.1),\n              (1.9, 2.1)),\n      facing V3D(0, 0, -1)\n")
    at, facing = s.specifiers
    assert isinstance(at.point, n.Call) and all(isinstance(a, n.Pair) for a in at.point.args)
    assert isinstance(facing, n.FacingSpec)


def test_face_points_combine_words_and_brackets_close_them():
    expr = one("x = top front left t\n").value
    assert isinstance(expr, n.FacePoint) and expr.words == ("top", "front", "left")
    expr = one("x = (top back t).position - V3D(0.4, 0, 0)\n").value
    assert isinstance(expr, n.BinOp) and expr.op == "-"
    assert isinstance(expr.left, n.Attribute) and expr.left.name == "position"
    assert expr.left.target.words == ("top", "back")


def test_paper_forms():
    s = one("c2 = Cube facing towards c1, aligned with t on z, facing Toward c1\n")
    toward, aligned, toward2 = s.specifiers
    assert isinstance(toward, n.FacingTowardSpec) and isinstance(toward2, n.FacingTowardSpec)
    assert isinstance(aligned, n.AlignedSpec) and aligned.axis == "z"
    s = one("c = Cube aligned with t by \"x\"\n")
    assert s.specifiers[0].axis == "x"


def test_relative_to_deg_and_unary():
    s = one("c = Cube at V3D(0.1, 0, 0) relative to t, facing -30 deg\n")
    at, facing = s.specifiers
    assert isinstance(at.point, n.RelativeTo)
    assert isinstance(facing.direction, n.UnaryOp) and isinstance(facing.direction.operand, n.Degrees)


def test_precedence_of_arithmetic_and_comparisons():
    s = one("require[0.5] not a < b + 2 * c and d or e\n")
    assert isinstance(s, n.RequireStmt) and s.probability.value == 0.5
    top = s.condition
    assert isinstance(top, n.BoolOp) and top.op == "or"
    conj = top.operands[0]
    assert conj.op == "and"
    negated = conj.operands[0]
    assert negated.op == "not" and isinstance(negated.operand, n.Compare)
    right = negated.operand.rest[0][1]
    assert right.op == "+" and right.right.op == "*"


def test_left_associative_chains():
    expr = one("x = 1 - 2 - 3\n").value
    assert expr.op == "-" and expr.left.op == "-" and expr.right.value == 3


def test_class_bodies_docstrings_and_comments():
    src = '"""doc"""\nimport math\nclass A(B):\n    """class doc"""\n    width: 1  # one\n\n    # a comment line\n    mass: self.width * 2\nx = 1\n'
    module = parse_source(src, "t.prs")
    doc, imp, cls, assign = module.statements
    assert isinstance(doc, n.ExprStmt) and isinstance(imp, n.ImportModule)
    assert isinstance(cls, n.ClassDef) and cls.parent == "B"
    assert [p.name for p in cls.properties] == ["width", "mass"]
    assert isinstance(assign, n.Assign)


def test_strings_and_literals():
    s = one("x = ['a', \"b\\n\", True, False, 1e-3, .5, {1: 2}]\n")
    items = s.value.items
    assert [i.value for i in items[:6]] == ["a", "b\n", True, False, 1e-3, 0.5]
    assert isinstance(items[6], n.DictLit)


def test_param_and_imports():
    module = parse_source("from model import *\nparam a = 1, b = 'x'\n", "t.prs")
    imp, param = module.statements
    assert isinstance(imp, n.ImportFrom) and imp.module == "model"
    assert [item[0] for item in param.items] == ["a", "b"]


def test_file_without_final_newline_and_crlf():
    module = parse_source("x = 1\r\ny = 2", "t.prs")
    assert len(module.statements) == 2


def test_keywords_are_soft_where_only_a_name_fits():
    s = one("c = Cube with model \"m\"\n")
    assert s.specifiers[0].prop == "model"


def test_spans_point_at_the_source():
    s = one("table = Table on V3D(0, 0, 0), with width 1.8\n")
    on, width = s.specifiers
    assert (on.span.column, on.span.end_column) == (15, 30)
    assert (width.prop_span.column, width.value.span.column) == (37, 43)


def test_syntax_error_names_what_was_expected():
    with pytest.raises(PrscError) as caught:
        parse_source("c = Cube with\n", "t.prs")
    assert caught.value.span.line == 1 and caught.value.span.column == 14
    assert "expected a name" in caught.value.message


def test_too_large_file_is_rejected_before_parsing(tmp_path):
    big = tmp_path / "big.prs"
    big.write_bytes(b"x = 1\n" * (2 * 1024 * 1024 // 6))
    with pytest.raises(PrscError) as caught:
        parse_file(big)
    assert "file too large" in caught.value.message
