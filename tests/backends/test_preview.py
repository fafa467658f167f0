"""`prsc preview`: a contact sheet of rendered scenes."""

from __future__ import annotations

import json

import numpy as np
import pytest

from prsc.cli import main
from tests.backends.scenes import cube_in_air, tray_with_cube


def test_contact_sheet_shows_every_scene(tmp_path):
    import matplotlib.image

    scenes = []
    for k in range(4):
        s = tray_with_cube() if k % 2 else cube_in_air()
        s["index"] = k
        scenes.append(s)
    source = tmp_path / "scenes.jsonl"
    source.write_text("".join(json.dumps(s) + "\n" for s in scenes))
    out = tmp_path / "sheet.png"
    assert main(["preview", str(source), "-n", "4", "-o", str(out)]) == 0
    image = matplotlib.image.imread(out)
    assert image.shape[0] > 400 and image.shape[1] > 600  # a 2 x 2 grid of 320 x 240 tiles
    # The scenes differ, so the tiles differ: compare the top-left and top-right quarters.
    h, w = image.shape[0] // 2, image.shape[1] // 2
    assert np.abs(image[:h, :w, :3] - image[:h, w : 2 * w, :3]).mean() > 0.01


def test_preview_errors_are_clear(tmp_path, capsys):
    assert main(["preview", str(tmp_path / "missing.prs"), "-o", str(tmp_path / "s.png")]) == 2
    assert "cannot read" in capsys.readouterr().err
    source = tmp_path / "one.json"
    source.write_text(json.dumps(cube_in_air()))
    assert main(["preview", str(source), "-o", str(tmp_path / "nowhere" / "s.png")]) == 2
    assert "does not exist" in capsys.readouterr().err


def test_preview_refuses_bad_paths_before_rendering(tmp_path, capsys, monkeypatch):
    """A folder at -o, a folder as input, a file without scenes: exit 2, nothing rendered."""
    from prsc.commands import preview

    monkeypatch.setattr(preview, "render_scene", lambda *a: pytest.fail("rendered before the check"))
    source = tmp_path / "one.json"
    source.write_text(json.dumps(cube_in_air()))
    (tmp_path / "sheet.png").mkdir()
    assert main(["preview", str(source), "-o", str(tmp_path / "sheet.png")]) == 2
    assert capsys.readouterr().err == f"prsc: error: cannot write {tmp_path / 'sheet.png'}: it is a folder\n"
    assert main(["preview", str(tmp_path), "-o", str(tmp_path / "s.png")]) == 2
    assert capsys.readouterr().err == f"prsc: error: {tmp_path} is a directory, not a spec file\n"
    (tmp_path / "none.json").write_text("[]")
    assert main(["preview", str(tmp_path / "none.json"), "-o", str(tmp_path / "s.png")]) == 2
    assert capsys.readouterr().err == f"prsc: error: {tmp_path / 'none.json'}: no scenes in the file\n"
    assert not (tmp_path / "s.png").exists()
