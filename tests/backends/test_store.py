"""The output folder's asset store (backends/store.py): a robot's mesh folder is copied and
named by its files alone, whatever another process is writing into it at the time."""

from __future__ import annotations

from prsc.backends.store import AssetStore, _folder_key


def test_a_folder_key_and_copy_ignore_the_temporaries_of_a_write_under_way(tmp_path):
    source = tmp_path / "build" / "meshes"
    source.mkdir(parents=True)
    (source / "finger.obj").write_text("v 0 0 0\n")
    (source / "hand.obj").write_text("v 1 0 0\n")
    before = _folder_key(str(source))
    _folder_key.cache_clear()
    # What atomic_write leaves for a moment while another process rewrites a file.
    (source / ".finger.obj.prsc-a1b2c3d4.tmp").write_text("v 0 0")
    assert _folder_key(str(source)) == before
    copied = AssetStore(tmp_path / "out").robot_file("panda", source / "finger.obj")
    assert sorted(p.name for p in copied.parent.iterdir()) == [".complete", "finger.obj", "hand.obj"]
    assert copied.parent.name == before
    _folder_key.cache_clear()
    (source / "hand.obj").write_text("v 2 0 0\n")  # a real change still changes the key
    assert _folder_key(str(source)) != before
