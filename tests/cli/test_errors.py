"""The shared error renderer: `path:line:col: error: message`, source line, caret."""

from __future__ import annotations

from prsc.errors import PrscError, Span, format_error


def test_error_names_position_and_points_at_column(tmp_path):
    spec = tmp_path / "bad.prs"
    spec.write_text("c = Cube\nt = Table on 3.0, with width 1\n")
    error = PrscError("expected an object or region after 'on'", Span(str(spec), 2, 14, 2, 17))
    text = format_error(error)
    lines = text.splitlines()
    assert lines[0] == f"{spec}:2:14: error: expected an object or region after 'on'"
    assert lines[1] == "    t = Table on 3.0, with width 1"
    assert lines[2] == "    " + " " * 13 + "^^^"


def test_notes_carry_their_own_locations(tmp_path):
    spec = tmp_path / "two.prs"
    spec.write_text("a = Cube left of b\nb = Cube right of a\n")
    error = PrscError(
        "region is empty",
        Span(str(spec), 1, 10, 1, 19),
        notes=(("conflicts with this specifier", Span(str(spec), 2, 10, 2, 20)),),
    )
    text = format_error(error)
    assert f"{spec}:2:10: note: conflicts with this specifier" in text
    assert text.count("^") == 9 + 10


def test_binary_source_line_is_printable(tmp_path):
    spec = tmp_path / "garbage.prs"
    spec.write_bytes(b"\x00\xff\xfe abc\n")
    text = format_error(PrscError("unexpected character", Span(str(spec), 1, 1, 1, 2)))
    assert "\x00" not in text
    assert text.splitlines()[2].strip() == "^"


def test_error_without_span_names_the_tool():
    assert format_error(PrscError("no input files")) == "prsc: error: no input files\n"


def test_a_line_that_never_ends_is_cut_not_read_whole():
    """/dev/zero has one endless line: the caret block shows a bounded piece of it."""
    text = format_error(PrscError("file too large", Span("/dev/zero", 1, 1, 1, 2)))
    lines = text.splitlines()
    assert lines[0] == "/dev/zero:1:1: error: file too large"
    assert len(lines[1]) < 200 and lines[2].strip() == "^"
