"""The README as a user reads it: short, the two commands and a spec first, and every code
block runs as written in a fresh clone (a copy of specs/ in an empty folder, prsc on PATH, a
fresh shell's environment without MUJOCO_GL).

How each block is checked:
- the untagged block (`make demo`, `make test`): each line names a Makefile target (not run:
  `make test` is the whole suite and `make demo` is CI's own first step);
- ```prs: the blocks together are specs/table_cube.prs as shipped (after its docstring), and it compiles;
- ```console: each `$ ` line runs in bash, exits 0, and the lines shown after it appear in
  what it printed;
- ```python: runs, and prints what the sentence after the block says it prints;
- ```sh (installing): not run (a fresh environment's install takes minutes;
  tests/test_wheel.py builds and installs the wheel), but the extras it names exist in
  pyproject.toml and the wheel's name carries the package's version.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
README = (REPO / "README.md").read_text(encoding="utf-8")
BLOCKS = [(m.group(1), m.group(2), m.end()) for m in re.finditer(r"^```(\w*)\n(.*?)^```$", README, re.S | re.M)]
KINDS = {"", "prs", "console", "python", "sh"}


def _fresh_clone_env() -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith(("MUJOCO_GL", "PYOPENGL", "PYTEST", "PRSC_"))}
    env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"
    env["PRSC_BUILD_DIR"] = os.environ["PRSC_BUILD_DIR"]  # the suite's asset cache (conftest.py)
    return env


@pytest.fixture
def clone(tmp_path: Path) -> Path:
    shutil.copytree(REPO / "specs", tmp_path / "specs")
    return tmp_path


def _blocks(kind: str) -> list[tuple[str, int]]:
    return [(text, end) for lang, text, end in BLOCKS if lang == kind]


def test_the_readme_is_a_front_page():
    lines = README.splitlines()
    assert len(lines) <= 150
    opening = "\n".join(lines[:40])
    spec = _blocks("prs")[0][0]  # the scene; its task follows below the opening
    assert "make demo" in opening and "make test" in opening and f"```prs\n{spec}```" in opening
    assert "docs/img/table_cube_sheet.png" in opening
    assert {lang for lang, _, _ in BLOCKS} <= KINDS, "a block of a kind this test does not run"


def test_every_relative_link_names_a_file_of_the_repository():
    targets = [t for t in re.findall(r"\]\(([^)\s#]+)", README) if not t.startswith(("http://", "https://"))]
    assert targets
    assert [t for t in targets if not (REPO / t).exists()] == []


def test_the_two_commands_are_make_targets():
    (block,) = [text for text, _ in _blocks("")]
    makefile = (REPO / "Makefile").read_text(encoding="utf-8")
    for line in block.splitlines():
        target = line.removeprefix("make ").strip()
        assert line.startswith("make ") and re.search(rf"^{target}:", makefile, re.M), line


def test_the_spec_is_the_shipped_one_and_compiles(tmp_path):
    from prsc.ir import compile_program

    block = "\n".join(text for text, _ in _blocks("prs"))  # the scene, then its task
    shipped = (REPO / "specs" / "table_cube.prs").read_text(encoding="utf-8")
    assert re.sub(r'^""".*?"""', "", shipped, count=1, flags=re.S).strip() == block.strip()
    spec = tmp_path / "first.prs"
    spec.write_text(block)
    assert len(compile_program(str(spec)).objects) == 7


def test_the_console_commands_print_what_the_readme_shows(clone):
    (block,) = [text for text, _ in _blocks("console")]
    steps: list[tuple[str, list[str]]] = []
    for line in block.splitlines():
        if line.startswith("$ "):
            steps.append((line[2:], []))
        else:
            steps[-1][1].append(line)
    assert [command.split()[1] for command, _ in steps] == ["check", "sample", "compile", "run"]
    for command, shown in steps:
        done = subprocess.run(["bash", "-c", command], cwd=clone, env=_fresh_clone_env(), capture_output=True,
                              text=True, timeout=600)
        assert done.returncode == 0, (command, done.stderr)
        printed = {" ".join(line.split()) for line in (done.stdout + done.stderr).splitlines()}
        assert shown, f"{command}: the README shows none of its output"
        for line in shown:
            assert " ".join(line.split()) in printed, (command, line, done.stdout + done.stderr)


def test_the_python_example_prints_what_the_readme_says(clone):
    (block, end) = _blocks("python")[0]
    assert len(_blocks("python")) == 1
    expected = re.match(r"\s*prints `([^`]*)`", README[end:]).group(1)
    (clone / "example.py").write_text(block)
    done = subprocess.run([sys.executable, "example.py"], cwd=clone, env=_fresh_clone_env(), capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == expected


def test_the_install_block_names_real_extras_and_the_wheel():
    (block,) = [text for text, _ in _blocks("sh")]
    project = tomllib.loads((REPO / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    extras = set(re.findall(r"\.\[(\w+)\]", block))
    assert extras and extras <= set(project["optional-dependencies"])
    wheels = re.findall(r"dist/(prsc-[^\s]+\.whl)", block)
    assert wheels == [f"prsc-{project['version']}-py3-none-any.whl"]
    assert "pip install ." in block
