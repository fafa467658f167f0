"""Hostile input across commands: every one is a clear error (exit 2), never a traceback (exit 3)."""

from __future__ import annotations

import errno
import io
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from prsc.cli import main
from tests.original import original_params

REPO = Path(__file__).resolve().parents[2]
TABLE_CUBE = str(REPO / "specs" / "table_cube.prs")
PRSC = [sys.executable, "-m", "prsc.cli"]


def test_a_failing_standard_output_is_a_user_error(monkeypatch, capsys):
    """A full disk behind stdout is exit 2 with the reason; a closed stdout likewise."""

    class Full(io.StringIO):
        def write(self, text: str) -> int:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(sys, "stdout", Full())
    assert main(["sample", TABLE_CUBE, "-n", "2"]) == 2
    assert capsys.readouterr().err == "prsc: error: cannot write to standard output: No space left on device\n"
    monkeypatch.setattr(sys, "stdout", None)  # what Python makes of `prsc check ... >&-`
    assert main(["check", TABLE_CUBE]) == 2
    assert capsys.readouterr().err == "prsc: error: cannot write to standard output: it is closed\n"
    assert main(["check", "--quiet", TABLE_CUBE]) == 0  # nothing to write, nothing wrong


def test_real_full_device_and_closed_pipe():
    """Through the real interpreter: /dev/full, and `prsc sample | head -1` (quiet exit 141)."""
    for command in (["check", TABLE_CUBE], ["sample", TABLE_CUBE, "-n", "2000"]):  # sample: batched lines
        with open("/dev/full", "w") as full:
            done = subprocess.run([*PRSC, *command], stdout=full, stderr=subprocess.PIPE, text=True, cwd=REPO)
        assert done.returncode == 2
        assert done.stderr == "prsc: error: cannot write to standard output: No space left on device\n"
    sample = subprocess.Popen([*PRSC, "sample", TABLE_CUBE, "-n", "500"], stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, cwd=REPO)
    first = sample.stdout.readline()
    sample.stdout.close()  # the reader goes away, as `head -1` does
    assert json.loads(first)["index"] == 0
    assert sample.wait() == 141 and sample.stderr.read() == b""


@pytest.mark.parametrize("command", [["check"], ["sample"], ["compile"]])
def test_an_endless_file_is_refused_after_the_size_limit(tmp_path, capsys, command):
    """`prsc check /dev/zero` must not read forever (or until memory runs out)."""
    assert main([*command, "/dev/zero", *(["-o", str(tmp_path / "o")] if command == ["compile"] else [])]) == 2
    assert capsys.readouterr().err.startswith(
        "/dev/zero:1:1: error: file too large (over 256 KiB; a spec may be at most 256 KiB)\n")
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("command", [["check"], ["explain"], ["sample"], ["bench", "-n", "1"]])
def test_an_include_folder_that_does_not_exist(tmp_path, capsys, command):
    missing = tmp_path / "nowhere"
    assert main([*command, TABLE_CUBE, "--include", str(missing)]) == 2
    assert f"prsc: error: --include {missing}: no such folder\n" in capsys.readouterr().err


@pytest.mark.parametrize("command", [["compile"], ["preview"], ["run"]])
def test_binary_scene_json(tmp_path, capsys, command):
    garbage = tmp_path / "garbage.json"
    garbage.write_bytes(bytes(range(0xc0, 0x100)) * 4)
    assert main([*command, str(garbage), "-o", str(tmp_path / ("out.png" if command == ["preview"] else "out"))]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"{garbage}:1:1: error: the file is not valid UTF-8 text (byte 0xc0)\n")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["garbage.json"]


@pytest.mark.parametrize("spec", sorted(str(p) for p in (REPO / "specs").glob("*.prs")) + original_params(as_text=True),
                         ids=lambda s: Path(s).name)
def test_explain_every_shipped_and_original_spec(capsys, spec):
    assert main(["explain", spec]) == 0
    assert capsys.readouterr().out.startswith(f"spec: {spec}\n")


def test_unicode_in_paths_and_strings(tmp_path, capsys):
    folder = tmp_path / "ünï cödé"
    folder.mkdir()
    spec = folder / "spéc.prs"
    spec.write_text('from tabletop import *\nparam task = "pïck ✓ 日本"\nclass Thing(Cube):\n    label: "ünï <&\\"\'>"\n'
                    'table = Table on Vector3D(0, 0, 0)\nc = Thing completely on table\n', encoding="utf-8")
    out = folder / "öut"
    assert main(["compile", str(spec), "--target", "json,mjcf", "-o", str(out)]) == 0
    scene = json.loads((out / "spéc" / "json" / "00000.json").read_text(encoding="utf-8"))
    assert scene["params"]["task"] == "pïck ✓ 日本" and scene["objects"][1]["properties"]["label"] == "ünï <&\"'>"
    import mujoco

    assert mujoco.MjModel.from_xml_path(str(out / "spéc" / "mjcf" / "00000.xml")).nbody >= 3


def test_help_of_every_command_is_for_users(capsys):
    with pytest.raises(SystemExit) as done:
        main(["--help"])
    assert done.value.code == 0
    text = capsys.readouterr().out
    assert "prsc/commands" not in text and "COMMAND --help" in text
    for command in ("check", "explain", "sample", "compile", "run", "bench", "preview"):
        with pytest.raises(SystemExit) as done:
            main([command, "--help"])
        assert done.value.code == 0
        assert f"usage: prsc {command}" in capsys.readouterr().out
