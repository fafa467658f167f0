"""Import resolution: find, parse and order every file a spec imports (before any naming).

`import NAME` / `from NAME import *` load NAME.prs, searched next to the importing file,
then in the --include dirs, then in prsc's own model library (the repo's specs/).
`import math` is the one Python module a spec may name.
"""

from __future__ import annotations

import os
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Sequence

from prsc.errors import PrscError
from prsc.ir.builtins import PYTHON_MODULES
from prsc.syntax import nodes, parse_file

MATH = "math"


def library_dir() -> Path:
    """prsc's own model library: the package data in prsc/library (tabletop.prs), installed with prsc."""
    return Path(__file__).resolve().parents[1] / "library"


@dataclass
class ModuleGraph:
    """Every parsed file, and for each import statement the file (or "math") it names."""

    main: str
    modules: dict[str, nodes.Module] = field(default_factory=dict)  # real path -> module
    targets: dict[int, str] = field(default_factory=dict)  # id(import statement) -> real path or "math"
    order: list[str] = field(default_factory=list)  # real paths, main first, then as discovered


def _search_path(importer: str, include_dirs: Sequence[str]) -> list[Path]:
    """Directories searched for an import made in importer, in order."""
    return [Path(importer).resolve().parent, *(Path(d) for d in include_dirs), library_dir()]


def _find(name: str, statement: nodes.Statement, importer: str, include_dirs: Sequence[str]) -> str:
    """The real path of NAME.prs for an import statement, or a PrscError saying why not."""
    span = statement.module_span  # type: ignore[attr-defined]
    dirs = _search_path(importer, include_dirs)
    for directory in dirs:
        candidate = directory / f"{name}.prs"
        if candidate.is_file():
            return os.path.realpath(candidate)
    if name in PYTHON_MODULES or name in getattr(sys, "stdlib_module_names", ()):
        raise PrscError(f"cannot import Python module '{name}': a spec is data, not code "
                        f"(the only Python import allowed is `import math`)", span)
    searched = ", ".join(str(d) for d in dirs)
    raise PrscError(f"import not found: no file {name}.prs (searched {searched}; add a directory with --include)",
                    span)


def load_module_graph(path: str, include_dirs: Sequence[str] = ()) -> ModuleGraph:
    """Parse the spec and, depth first, every file it imports; import cycles are errors."""
    for directory in include_dirs:
        # A mistyped --include would otherwise only show as "import not found" (or not at all).
        if not Path(directory).is_dir():
            what = "is not a folder" if Path(directory).exists() else "no such folder"
            raise PrscError(f"--include {directory}: {what}")
    main = os.path.realpath(path)
    graph = ModuleGraph(main=main)
    chain: list[tuple[str, str]] = []  # (real path, display path) of files being loaded

    def visit(real: str, display: str) -> None:
        module = parse_file(display)
        graph.modules[real] = module
        graph.order.append(real)
        chain.append((real, display))
        for statement in module.statements:
            if not isinstance(statement, (nodes.ImportFrom, nodes.ImportModule)):
                continue
            if statement.module == MATH:
                graph.targets[id(statement)] = MATH
                continue
            target = _find(statement.module, statement, display, include_dirs)
            graph.targets[id(statement)] = target
            on_chain = [r for r, _ in chain]
            if target in on_chain:
                start = on_chain.index(target)
                names = [Path(d).name for _, d in chain[start:]] + [Path(target).name]
                raise PrscError("import cycle: " + " -> ".join(names), statement.module_span)
            if target not in graph.modules:
                visit(target, _display_path(target))
        chain.pop()

    visit(main, str(path))
    return graph


def _display_path(real: str) -> str:
    """A path for messages: relative to the working directory when that is shorter."""
    try:
        rel = os.path.relpath(real)
    except ValueError:
        return real
    return rel if len(rel) < len(real) else real
