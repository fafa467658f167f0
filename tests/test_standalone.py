"""A user's clone stands alone: no doc, example or source points outside the repository."""

from __future__ import annotations

from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def test_docs_and_sources_point_only_inside_the_repository():
    """A user's clone has no ../shared and no other machine's folders: nothing may send them there."""
    # The folder this checkout sits in, read at run time: a path under it written into a file
    # is a path of the machine that wrote it.
    outside = ("LANGUAGE.md", "shared folder", "../shared", "shared/specs", "FIELD-NOTES", f"{REPO.parent}/")
    files = [REPO / "README.md", REPO / "CHANGELOG.md", REPO / "Makefile", REPO / "mkdocs.yml",
             *(REPO / "docs").rglob("*.md"), *(REPO / "docs").rglob("*.py"), *(REPO / "specs").rglob("*.prs"),
             *(REPO / "specs").rglob("*.py"), *(p for d in ("prsc", "backends", "assets") for p in (REPO / d).rglob("*.py"))]
    found = [f"{path.relative_to(REPO)}: {word}" for path in files for word in outside if word in path.read_text()]
    assert found == []
