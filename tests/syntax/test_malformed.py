"""Malformed specs: every error names its exact line and column and says what is wrong."""

from __future__ import annotations

import pytest

from prsc.errors import PrscError
from prsc.ir import compile_program

H = "from tabletop import *\n"

# (name, source, line, column, a fragment of the message)
CASES = [
    ("missing_expression", H + "c = Cube on\n", 2, 12, "expected an expression"),
    ("unknown_specifier", H + "c = Cube near table\n", 2, 10, "unknown specifier 'near'"),
    ("unclosed_bracket", H + "c = Cube on Vector3D(0, 0, 0\nd = 3\n", 3, 1, "expected an operator, ',' or ')'"),
    ("indented_statement", H + "  c = Cube\n", 2, 3, "unexpected indentation"),
    ("on_scalar", H + "c = Cube on 3.0\n", 2, 13, "`on` needs an object, a planar region or a point, not a scalar"),
    ("unknown_class", H + "t = Tabel on Vector3D(0, 0, 0)\n", 2, 5, "did you mean 'Table'?"),
    ("unknown_name", H + "table = Table\nc = Cube on tabel\n", 3, 13, "unknown name 'tabel'; did you mean 'table'?"),
    ("unknown_property", H + "c = Cube with colr \"red\"\n", 2, 15, "unknown property 'colr' for a Cube; did you mean 'color'?"),
    ("unknown_read_property", H + "t = Table\nx = t.hieght\n", 3, 7, "did you mean 'height'?"),
    ("import_not_found", "from nowhere import *\n", 1, 6, "import not found: no file nowhere.prs"),
    ("python_import", "import numpy\n", 1, 8, "cannot import Python module 'numpy'"),
    ("duplicate_property", H + "class A:\n    width: 1\n    width: 2\n", 4, 5, "duplicate property 'width' in class A"),
    ("orientation_twice", H + "c = Cube facing toward Vector3D(1, 0, 0), facing Vector3D(0, 1, 0)\n", 2, 43,
     "orientation is set twice"),
    ("unterminated_string", "x = \"abc\n", 1, 5, "unterminated string"),
    ("bad_character", "x = 1 $ 2\n", 1, 7, "unexpected character '$'"),
    ("empty_file", "", 1, 1, "empty spec"),
    ("comments_only", "\n# nothing\n\n", 1, 1, "empty spec"),
    ("unknown_parent", H + "class A(B):\n    width: 1\n", 2, 9, "unknown class 'B'"),
    ("vector_plus_scalar", H + "c = Cube on Vector3D(0, 0, 0) + 1\n", 2, 13, "cannot add a vector and a scalar"),
    ("bad_axis", H + "t = Table\nc = Cube aligned with t on w\n", 3, 28, "the axis x, y or z, not 'w'"),
    ("probability_range", H + "require[2] True\n", 2, 9, "must lie in [0, 1]"),
    ("probability_not_constant", H + "require[(0, 1)] True\n", 2, 9, "must be a constant number"),
    ("use_before_definition", H + "c = Cube on d\nd = Cube\n", 2, 13, "unknown name 'd': it is defined later (line 3)"),
    ("class_body_not_indented", H + "class A:\nwidth: 1\n", 3, 1, "expected an indented class body"),
    ("face_words_same_axis", H + "t = Table\nc = Cube on top bottom t\n", 3, 13, "'top' and 'bottom' are on the same axis"),
    ("in_scalar", H + "c = Cube in 3\n", 2, 13, "`in` needs a region, not a scalar"),
    ("width_string", H + "c = Cube with width \"wide\"\n", 2, 21, "`with width` needs a scalar, not a string"),
    ("self_position", H + "class A:\n    height: self.position.z\n", 3, 13, "cannot read self.position"),
    ("math_not_imported", H + "x = math.pi\n", 2, 5, "add `import math`"),
    ("math_unknown_function", "import math\nx = math.exp(1)\n", 2, 10, "math has no function 'exp'"),
    ("object_redefined", H + "c = Cube\nc = Cube\n", 3, 1, "'c' is already defined as the object c"),
    ("face_point_of_vector", H + "x = top Vector3D(0, 0, 0)\n", 2, 9, "must be an object, not a vector"),
    ("range_of_vectors", H + "x = (Vector3D(0, 0, 0), 1)\n", 2, 6, "must be a scalar, not a vector"),
    ("wrong_arity", H + "x = Vector3D(1, 2)\n", 2, 5, "wrong number of arguments to Vector3D (2)"),
    ("on_cuboid_region", H + "c = Cube on Cuboid(Vector3D(0, 0, 0), Vector3D(0, 0, 0), 1, 1, 1)\n", 2, 13,
     "`on` needs a planar region"),
    ("bad_dedent", H + "class A:\n        width: 1\n    length: 2\n", 4, 5, "matches no enclosing block"),
    ("property_cycle", H + "class A:\n    width: self.length\n    length: self.width\n", 4, 13,
     "depend on each other in a cycle"),
    ("expression_statement", H + "1 + 2\n", 2, 1, "does nothing on its own"),
    ("require_not_bool", H + "require 3\n", 2, 9, "require needs a condition"),
    ("missing_comma", H + "t = Table\nc = Cube on t left of t\n", 3, 15, "unexpected 'left'"),
    ("class_as_value", H + "x = Cube.width\n", 2, 5, "'Cube' is a class, not a value"),
    ("workspace_not_region", "workspace = 3\n", 1, 13, "workspace must be a region"),
    ("by_string", H + "t = Table\nc = Cube left of t by \"far\"\n", 3, 23, "must be a scalar, not a string"),
    ("width_set_twice", H + "c = Cube with width 1, with width 2\n", 2, 24, "width is set twice"),
    ("invalid_utf8", b"x = 1\ny = '\xff'\n", 2, 6, "not valid UTF-8"),
    ("dict_outside_discrete", "x = {1: 2}\n", 1, 5, "only allowed in Discrete"),
    ("call_unknown_function", "x = sine(1)\n", 1, 5, "did you mean 'sin'?"),
    ("comparison_of_vectors", H + "require Vector3D(0, 0, 0) < 1\n", 2, 9, "each side of < must be a scalar"),
    ("from_import_name", "from math import pi\n", 1, 18, "expected '*'"),
    ("too_deep", "x = " + "(" * 150 + "1" + ")" * 150 + "\n", 1, 105, "nested more than 100 deep"),
    ("invalid_escape", "x = \"\\N{nope}\"\n", 1, 5, "invalid string literal"),
    ("call_a_class", H + "c = Cube(1)\n", 2, 5, "'Cube' is a class"),
    ("number_too_large", H + "c = Cube with width 1e400\n", 2, 21, "number 1e400 is too large"),
    ("non_ascii_name", "class Th\u00efng:\n    width: 1\n", 1, 9, "names are ASCII letters, digits and _"),
    ("redefined_article", H + "c = Object\nc = Cube\n", 3, 1, "already defined as the object c (an Object)"),
]


@pytest.mark.parametrize("name,source,line,column,fragment", CASES, ids=[c[0] for c in CASES])
def test_error_has_exact_position(tmp_path, name, source, line, column, fragment):
    spec = tmp_path / f"{name}.prs"
    spec.write_bytes(source if isinstance(source, bytes) else source.encode())
    with pytest.raises(PrscError) as caught:
        compile_program(str(spec))
    error = caught.value
    assert error.span is not None, error.message
    assert (error.span.path, error.span.line, error.span.column) == (str(spec), line, column), error.message
    assert fragment in error.message


def test_there_are_at_least_25_cases():
    assert len(CASES) >= 25
