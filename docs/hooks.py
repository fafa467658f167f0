"""MkDocs hooks of prsc's site (mkdocs.yml): what the pages need beyond the files in docs/.

- the front page is README.md and the changelog page CHANGELOG.md, their links rewritten
  to the site's pages (one text each, for the repository and for the site);
- a link from a page to a repository file outside docs/ (a spec, an example script) points at
  a copy of that file in the site (`repo/...`); a link to a folder becomes its name in code;
  one to nothing is a warning, so the strict build fails;
- cli.md's `<!-- cli-help -->` becomes every command's `--help`, from prsc/cli.py's parsers;
- `\\|` in a table cell's code (GitHub's escape) is shown as `|`;
- every name in `prsc.__all__` must have a `::: identifier` entry in docs/api/*.md, and
  everything those entries document must have a docstring, or the build fails.
"""

from __future__ import annotations

import argparse
import importlib
import inspect
import logging
import os
import posixpath
import re
from pathlib import Path
from typing import Any

from mkdocs.exceptions import PluginError
from mkdocs.structure.files import File, Files

log = logging.getLogger("mkdocs.hooks.prsc")

REPO = Path(__file__).resolve().parents[1]
DOCS = REPO / "docs"
GENERATED = {"index.md": "README.md", "changelog.md": "CHANGELOG.md"}  # site page -> repository file
PAGE_OF = {repo: page for page, repo in GENERATED.items()}
COPIES = "repo"  # where linked repository files are copied in the site
LINK = re.compile(r"(!?\[[^\]]*\]\()([^)\s]+)(\))")  # [text](target) and ![alt](target)
CLI_MARKER = "<!-- cli-help -->"


def _repo_path(src_uri: str) -> str:
    """The repository path of a page's source."""
    return GENERATED.get(src_uri, f"docs/{src_uri}")


def _links(markdown: str) -> list[str]:
    """Relative link targets of a page, without their anchors."""
    targets = []
    for match in LINK.finditer(markdown):
        target = match.group(2)
        if not target.startswith(("http://", "https://", "mailto:", "#", "/")):
            targets.append(target)
    return targets


def _resolve(src_uri: str, target: str) -> tuple[str, str]:
    """(repository path the target names, anchor)."""
    path, _, anchor = target.partition("#")
    base = posixpath.dirname(_repo_path(src_uri))
    return posixpath.normpath(posixpath.join(base, path)), anchor


def _site_uri(repo_path: str) -> str | None:
    """Where a repository path lives in the site: a page, a copied file, or None (a folder)."""
    if repo_path in PAGE_OF:
        return PAGE_OF[repo_path]
    if repo_path.startswith("docs/"):
        return repo_path[len("docs/"):]
    if (REPO / repo_path).is_file():
        return f"{COPIES}/{repo_path}"
    return None


def _markdown_of(file: File) -> str:
    return file.content_string


def on_files(files: Files, config: Any) -> Files:
    """Add the front page, the changelog page and copies of the repository files pages link to."""
    for page, source in GENERATED.items():
        if files.get_file_from_path(page) is not None:
            raise PluginError(f"docs/{page} would hide the page made from {source}: remove it")
        files.append(File.generated(config, page, content=(REPO / source).read_text(encoding="utf-8")))
    copied: set[str] = set()
    for file in list(files):
        if not file.src_uri.endswith(".md"):
            continue
        for target in _links(_markdown_of(file)):
            repo_path, _ = _resolve(file.src_uri, target)
            if repo_path.startswith(("docs/", "..")) or repo_path in PAGE_OF or repo_path in copied:
                continue
            if (REPO / repo_path).is_file():
                copied.add(repo_path)
                files.append(File.generated(config, f"{COPIES}/{repo_path}", abs_src_path=str(REPO / repo_path)))
    return files


def _rewrite_links(markdown: str, src_uri: str) -> str:
    page_dir = posixpath.dirname(src_uri) or "."

    def replace(match: re.Match[str]) -> str:
        opening, target, closing = match.groups()
        if target.startswith(("http://", "https://", "mailto:", "#", "/")):
            return match.group(0)
        repo_path, anchor = _resolve(src_uri, target)
        uri = None if repo_path.startswith("..") else _site_uri(repo_path)
        if uri is not None:
            return f"{opening}{posixpath.relpath(uri, page_dir)}{'#' + anchor if anchor else ''}{closing}"
        if (REPO / repo_path).is_dir() and not repo_path.startswith(".."):
            # The site holds no folder listings: a link to a folder becomes its name, in code.
            text = opening[opening.index("[") + 1:-2]
            name = f"`{repo_path.rstrip('/')}/`"
            return name if text.strip("`/") in ("", repo_path.strip("/"), posixpath.basename(repo_path)) \
                else f"{text} ({name})"
        log.warning(f"{_repo_path(src_uri)}: the link '{target}' names no file of the repository")
        return match.group(0)

    return LINK.sub(replace, markdown)


def _help_texts() -> str:
    """Every command's --help, as an 80-column terminal shows it."""
    os.environ["COLUMNS"] = "80"  # argparse wraps to the terminal's width
    from prsc import cli

    parser = cli.build_parser()
    (commands,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    sections = []
    for name in cli.COMMANDS:
        if name not in commands.choices:
            raise PluginError(f"prsc {name} has no parser")
        text = commands.choices[name].format_help().rstrip()
        sections.append(f"## `prsc {name}`\n\n```text\n{text}\n```\n")
    return "\n".join(sections)


def on_page_markdown(markdown: str, page: Any, config: Any, files: Files) -> str:
    """Rewrite links for the site; render the command line's help into cli.md."""
    src_uri = page.file.src_uri
    if src_uri == "cli.md":
        if CLI_MARKER not in markdown:
            raise PluginError(f"docs/cli.md lost its {CLI_MARKER} marker")
        markdown = markdown.replace(CLI_MARKER, _help_texts())
    return _rewrite_links(_unescape_table_code(markdown), src_uri)


def _unescape_table_code(markdown: str) -> str:
    """`a\\|b` in a table cell's code: GitHub needs the backslash, Python-Markdown shows it."""
    def unescape(line: str) -> str:
        return re.sub(r"`[^`]*`", lambda m: m.group(0).replace("\\|", "|"), line) if line.startswith("|") else line

    return "\n".join(unescape(line) for line in markdown.split("\n"))


def _resolve_identifier(identifier: str) -> Any:
    """The object a `::: a.b.C` entry documents, imported."""
    parts = identifier.split(".")
    for cut in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:cut]))
        except ImportError:
            continue
        for name in parts[cut:]:
            obj = getattr(obj, name)
        return obj
    raise PluginError(f"docs/api: '::: {identifier}' names nothing importable")


def _own_doc(obj: Any) -> str:
    """The object's own docstring (not one inherited from a base class)."""
    doc = obj.__doc__ if (inspect.isclass(obj) or inspect.isroutine(obj) or inspect.ismodule(obj)) else None
    if inspect.isclass(obj) and "__doc__" not in vars(obj):
        doc = None
    return inspect.cleandoc(doc) if doc else ""


def undocumented(identifier: str, obj: Any) -> list[str]:
    """What an API entry shows without a docstring: the object, a class's public methods and
    properties, a module's public functions and classes."""
    missing = [identifier] if not _own_doc(obj) else []
    if inspect.isclass(obj):
        for name, member in vars(obj).items():
            if name.startswith("_"):
                continue
            target = member.fget if isinstance(member, property) else getattr(member, "__func__", member)
            if inspect.isroutine(target) and not (target.__doc__ or "").strip():
                missing.append(f"{identifier}.{name}")
    elif inspect.ismodule(obj):
        for name, member in vars(obj).items():
            if name.startswith("_") or getattr(member, "__module__", None) != obj.__name__:
                continue
            if inspect.isclass(member) or inspect.isroutine(member):
                missing += undocumented(f"{identifier}.{name}", member)
    return missing


def api_problems(docs_dir: Path = DOCS) -> list[str]:
    """Public names of prsc without an API entry, and API entries without docstrings."""
    import prsc

    identifiers = []
    for page in sorted((docs_dir / "api").glob("*.md")):
        identifiers += re.findall(r"^:::\s*([\w.]+)", page.read_text(encoding="utf-8"), re.M)
    documented = {identifier: _resolve_identifier(identifier) for identifier in identifiers}
    problems = []
    for name in prsc.__all__:
        public = getattr(prsc, name)
        if not any(obj is public for obj in documented.values()):
            problems.append(f"prsc.{name} is public (prsc.__all__) but no docs/api page has a '::: ' entry for it")
    for identifier, obj in documented.items():
        problems += [f"{what} has no docstring" for what in undocumented(identifier, obj)]
    return problems


def on_config(config: Any) -> Any:
    """Fail before building when the API reference misses a public name or a docstring."""
    problems = api_problems(Path(config["docs_dir"]))
    if problems:
        raise PluginError("the API reference is incomplete:\n  " + "\n  ".join(problems))
    return config
