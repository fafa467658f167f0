"""MuJoCo's simulation options come from one place, and the runner keeps a file's own (issue 12, item 11)."""

from __future__ import annotations

import json

import mujoco

from prsc.assets.simulation import IMPRATIO, TIMESTEP
from prsc.runner.harness import load_model
from prsc.commands.compile import compile_scenes
from tests.backends.scenes import table_cube


def test_compiled_scenes_carry_the_options_and_the_runner_keeps_them(tmp_path):
    source = tmp_path / "scene.json"
    source.write_text(json.dumps(table_cube()))
    root = compile_scenes(str(source), ["mjcf"], 1, 0, str(tmp_path / "out"))
    path = root / "mjcf" / "00000.xml"
    model = load_model(path)
    assert model.opt.timestep == TIMESTEP and model.opt.impratio == IMPRATIO
    assert model.opt.integrator == mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    assert model.opt.cone == mujoco.mjtCone.mjCONE_ELLIPTIC
    # A user who edits the compiled file's options gets what the file says.
    text = path.read_text()
    assert 'impratio="10"' in text and "timestep=" not in text  # 0.002 is MuJoCo's default: not written
    path.write_text(text.replace('impratio="10"', 'impratio="3" timestep="0.001"'))
    edited = load_model(path)
    assert edited.opt.timestep == 0.001 and edited.opt.impratio == 3.0


def _sources() -> dict[str, str]:
    from pathlib import Path

    repo = Path(__file__).resolve().parents[2]
    return {str(p.relative_to(repo)): p.read_text() for folder in ("prsc", "backends", "assets")
            for p in (repo / folder).rglob("*.py")}


def test_one_atomic_write_helper_and_one_options_setter():
    """Only prsc/files.py renames temporaries into place; only assets/simulation.py sets options."""
    import re

    renames = {path for path, text in _sources().items() if re.search(r"os\.replace\(|mkstemp\(|mkdtemp\(", text)}
    assert renames == {"prsc/files.py"}
    setters = {path for path, text in _sources().items()
               if re.search(r"\b(option|opt)\.(timestep|integrator|cone|impratio)\s*=", text)}
    assert setters == {"assets/simulation.py"}


def test_backends_never_import_the_commands():
    """Layering: backends read scene JSON, never spec text, the IR, the constraint IR, the sampler or prsc.commands."""
    import re

    offenders = {path for path, text in _sources().items() if path.startswith("backends/")
                 and re.search(r"^\s*(from|import) prsc\.(commands|ir|syntax|constraints|sampling)\b", text, re.M)}
    assert offenders == set()
