"""The wheel, installed as a user installs it (not the editable tree): it carries the model
library, so a spec that starts `from tabletop import *` compiles from any folder."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import sysconfig
import venv
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
SPEC = """from tabletop import *
table = Table on Vector3D(0, 0, 0)
arm = Robot on (top back table).position
cube = Cube completely on table
"""  # the library's Robot: its data (prsc/library/panda.json) ships in the wheel


def test_the_installed_wheel_compiles_a_spec_that_imports_the_model_library(tmp_path):
    # A copy of the sources: setuptools builds in the tree (build/, *.egg-info), and the
    # repository's build/ is the asset cache other tests use.
    source = tmp_path / "source"
    shutil.copytree(REPO, source, ignore=shutil.ignore_patterns(".git", ".venv", "build", "out", "*.egg-info",
                                                                 "__pycache__", ".pytest_cache"))
    wheels = tmp_path / "wheels"
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q", "-w", str(wheels),
                    str(source)], check=True, cwd=tmp_path, capture_output=True)
    (wheel,) = wheels.glob("prsc-*.whl")
    target = tmp_path / "venv"
    venv.EnvBuilder(with_pip=False).create(target)
    site = Path(sysconfig.get_path("purelib", vars={"base": str(target), "platbase": str(target)}))
    # The dependencies come from this environment's site-packages, added as a plain path: its
    # .pth files (among them the editable install's finder for the repository) are not run.
    (site / "prsc-test-dependencies.pth").write_text(sysconfig.get_path("purelib") + "\n")
    python = target / "bin" / "python"
    # pip (from the same dependencies) run by the new environment's python: the console
    # script `prsc` then starts that python, as it would after `pip install prsc`.
    # --ignore-installed: pip sees this environment's editable prsc through the path above
    # and would otherwise uninstall it first.
    subprocess.run([python, "-m", "pip", "install", "-q", "--no-deps", "--no-index", "--ignore-installed", str(wheel)],
                   check=True, capture_output=True)
    env = {k: v for k, v in os.environ.items() if not k.startswith(("PYTHON", "PRSC_"))}
    env["PRSC_BUILD_DIR"] = str(tmp_path / "build")
    home = tmp_path / "elsewhere"
    home.mkdir()
    (home / "mine.prs").write_text(SPEC)
    where = subprocess.run([python, "-c", "import prsc, prsc.ir.imports as i; print(prsc.__file__); "
                            "print(i.library_dir())"], cwd=home, env=env, capture_output=True, text=True, check=True)
    package, library = where.stdout.split()
    assert Path(package).is_relative_to(target) and not Path(package).is_relative_to(REPO)
    assert (Path(library) / "tabletop.prs").is_file()
    run = subprocess.run([target / "bin" / "prsc", "compile", "mine.prs", "--target", "json,mjcf", "-n", "2",
                          "-o", "out"], cwd=home, env=env, capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    assert sorted(p.name for p in (home / "out" / "mine" / "mjcf").iterdir()) == ["00000.xml", "00001.xml"]
