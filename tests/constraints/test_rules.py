"""The constraint IR as data: rule records, analyses without probing, source text, JSON, re-entrancy."""

from __future__ import annotations

import dataclasses
import json
import threading
from pathlib import Path

import pytest

from prsc.cli import main
from prsc.constraints import lower_program
from prsc.errors import PrscError
from prsc.ir import compile_program
from prsc.sampling import Sampler
from prsc.sampling.engine import SequentialSampler

REPO = Path(__file__).resolve().parents[2]
PRSC = REPO / "prsc"
SPECS = sorted((REPO / "specs").glob("*.prs"))


def _write(tmp_path, text, name="spec.prs"):
    spec = tmp_path / name
    spec.write_text(text, encoding="utf-8")
    return spec


def test_rules_are_frozen_records_and_the_analyses_read_their_templates():
    cprog = lower_program(compile_program(str(REPO / "specs" / "table_cube.prs"), ()))
    plans = {p.name: p for p in cprog.objects}
    rule = plans["c1"].rules[0]
    assert (rule.kind, cprog.labels[rule.label_id].text, rule.span.line) == ("on", "completely on tr_1", 21)
    assert rule.option("completely") is True and rule.template.anchor == "tr_1"
    with pytest.raises(dataclasses.FrozenInstanceError):
        rule.kind = "in"  # type: ignore[misc]
    assert [r.kind for r in plans["tr_1"].rules] == ["on", "direction", "direction", "workspace"]
    assert all(r.static for r in plans["tr_1"].rules) and plans["tr_1"].region.anchor is None
    # The camera's `at` has random arguments: no template, rows built per scene, solved as a point.
    camera = plans["camera"].region
    at = next(r for r in camera.rules if r.kind == "at")
    assert at.template is None and camera.rules[camera.point_rule] is at
    assert plans["camera"].orientation.kind == "facing" and plans["camera"].orientation.static_value is not None


def test_no_probing_is_left_and_no_module_is_over_400_lines():
    # Rules are never run to learn about them: no probe helper, raising memo or shift test.
    banned = ("_probe(", "NotStatic", "_RaisingDict", "StaticContext", "_TEST_SHIFTS", "_find_anchor", "_fixed_point")
    long = []
    for path in sorted(PRSC.rglob("*.py")):
        text = path.read_text(encoding="utf-8")
        assert not [b for b in banned if b in text], path
        if text.count("\n") > 400:
            long.append(str(path.relative_to(REPO)))
    assert long == [], long


def test_beyond_a_point_from_itself_fails_check_at_its_position(tmp_path, capsys):
    spec = _write(tmp_path, "from tabletop import *\nV = Vector3D(0, 0, 1)\nc = Cube beyond V by 0.3 from V\n")
    assert main(["check", str(spec)]) == 2
    err = capsys.readouterr().err
    assert f"{spec}:3:10: error: `beyond X by d from P` needs X and P to differ" in err
    spec2 = _write(tmp_path, "from tabletop import *\nc = Cube beyond Vector3D(0, 0, 1) by 0.3 from Vector3D(0, 0, 1.0)\n", "b.prs")
    assert main(["check", str(spec2)]) == 2
    assert f"{spec2}:2:10: error" in capsys.readouterr().err


def test_an_error_in_a_rule_with_constant_arguments_is_reported_when_lowering(tmp_path):
    # X and P only coincide after folding: the lowering reports it (it used to be swallowed
    # by a probe and fail only when sampled).
    spec = _write(tmp_path, "from tabletop import *\n"
                            "t = Table at Vector3D(0, 0, 0.4), with width 1, with length 1, with height 0.8\n"
                            "c = Cube beyond t by 0.3 from Vector3D(0, 0, 0.4)\n")
    with pytest.raises(PrscError, match="'beyond X from P' needs X and P to differ") as caught:
        lower_program(compile_program(str(spec), ()))
    assert caught.value.span is not None and caught.value.span.line == 3


def test_specifier_text_comes_from_the_compiled_ir_not_the_file_now(tmp_path):
    head = "from tabletop import *\nt = Table at Vector3D(0, 0, 0.4), with width 1, with length 1, with height 0.8\n"
    spec = _write(tmp_path, head + "c = Cube completely on t\n")
    program = compile_program(str(spec), ())
    spec.write_text(head + "c = Cube on t, left of t\n", encoding="utf-8")  # edited after compiling
    labels = [lab.text for lab in lower_program(program).labels if lab.object == "c"]
    assert "completely on t" in labels and "on t, left" not in " ".join(labels)
    labels = [lab.text for lab in lower_program(compile_program(str(spec), ())).labels if lab.object == "c"]
    assert "on t" in labels and "left of t" in labels


def test_one_sampler_serves_interleaved_scenes_from_two_threads():
    program = compile_program(str(REPO / "specs" / "cluttered_table.prs"), ())
    sampler = Sampler(program, "exact")
    assert isinstance(sampler._engine, SequentialSampler)
    expected = {i: sampler.scene(5, i) for i in range(24)}
    got: dict[int, dict] = {}

    def work(indices):
        for i in indices:
            got[i] = sampler.scene(5, i)

    threads = [threading.Thread(target=work, args=(range(k, 24, 2),)) for k in (0, 1)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert got == expected


@pytest.mark.parametrize("spec", SPECS, ids=[p.name for p in SPECS])
def test_explain_json_has_one_entry_per_rule(spec, capsys):
    assert main(["explain", str(spec), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    cprog = lower_program(compile_program(str(spec), ()))
    count = sum(len(p.rules) + len(p.exclusions) + len(p.checks) + (p.orientation is not None)
                for p in cprog.objects) + len(cprog.scene_checks)
    assert len(data["rules"]) == count and data["order"] == [p.name for p in cprog.objects]
    for entry in data["rules"]:
        assert entry["kind"] and entry["label"] and isinstance(entry["line"], int), entry
        assert entry["source"]["path"].endswith(".prs")


def test_explain_json_is_only_for_the_constraints_stage(capsys):
    assert main(["explain", str(SPECS[0]), "--json", "--stage", "ir"]) == 2
    assert "--json prints the constraints stage" in capsys.readouterr().err
