"""The design card's layering, read off every import in the source (also those inside
functions and under TYPE_CHECKING: a type named across a layer is a dependency too).

- A stage imports only earlier stages: syntax -> ir -> constraints -> sampling -> commands,
  with geometry/ (pure math: numpy, highspy and the standard library) below them all and
  user_assets/ (the user's URDF, MJCF and mesh files) just above it.
- The parser (syntax/) knows no semantics: lark, the standard library and prsc.errors.
- Backends (and the asset recipes they read) never import spec text's stages, the IR or
  prsc.commands: they read scene JSON and asset descriptions.
- The MuJoCo runner (runner/) steps what the backends wrote; it reads scene JSON, never spec text.
- The library API (prsc/scenario.py, prsc/scene_env.py, prsc/scene_cameras.py) joins sampling, the backends and the
  runner; pipeline/ (executors, campaigns, output folders) serves the subcommands (commands/).
- No import cycles between modules. Three were broken and stay forbidden by name:
  ir/constructors <-> ir/expressions, the engine <-> Gibbs object cycle, and `commands`
  reading its own manifest through runner/settle_check.
"""

from __future__ import annotations

import ast
import sys
from functools import lru_cache
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
ROOTS = {"prsc": REPO / "prsc", "prsc.backends": REPO / "backends", "prsc.assets": REPO / "assets"}
FOUNDATION = {"prsc.errors", "prsc.files", "prsc.limits"}  # what every layer may use: errors, atomic files, size limits
ALLOWED = {  # layer -> the layers it may import, besides itself and FOUNDATION
    "syntax": set(),
    "geometry": set(),
    "user_assets": {"geometry"},
    "task": {"geometry"},  # the task's terms and its one evaluator (LANGUAGE.md section 8): no simulator
    "ir": {"syntax", "user_assets", "task"},
    "constraints": {"ir", "geometry", "user_assets", "task"},
    "sampling": {"ir", "geometry", "constraints", "user_assets", "task"},
    "assets": {"geometry", "user_assets"},
    "backends": {"geometry", "user_assets", "assets"},
    "runner": {"geometry", "user_assets", "assets", "backends", "task"},
    "library": set(),
    "api": {"syntax", "ir", "geometry", "constraints", "sampling", "user_assets", "assets", "backends", "runner", "task"},
    "pipeline": {"syntax", "ir", "geometry", "constraints", "sampling", "user_assets", "assets", "backends", "runner", "api",
                 "task"},
    "commands": {"syntax", "ir", "geometry", "constraints", "sampling", "user_assets", "assets", "backends", "runner", "api",
                 "pipeline", "task"},
    "foundation": set(),
}
PURE_MATH = {"numpy", "highspy", "__future__"} | set(sys.stdlib_module_names)
FORBIDDEN_EDGES = [
    ("prsc.ir.constructors", "prsc.ir.expressions"),
    ("prsc.sampling.gibbs", "prsc.sampling.engine"),
]


def _module(path: Path) -> str:
    for package, folder in sorted(ROOTS.items(), key=lambda item: -len(item[0])):
        if path.is_relative_to(folder):
            parts = list(path.relative_to(folder).with_suffix("").parts)
            return ".".join([package, *parts[:-1]] + ([] if parts[-1] == "__init__" else [parts[-1]]))
    raise ValueError(path)


@lru_cache(maxsize=1)
def _graph() -> dict[str, tuple[set[str], set[str]]]:
    """Module -> (prsc modules it imports, top-level third-party/stdlib names it imports)."""
    files = {_module(p): p for folder in ROOTS.values() for p in folder.rglob("*.py")}
    graph = {}
    for name, path in files.items():
        inner, outer = set(), set()
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                # `from prsc.ir import expressions` names the module prsc.ir.expressions
                targets = [f"{node.module}.{a.name}" if f"{node.module}.{a.name}" in files else node.module
                           for a in node.names]
            else:
                continue
            for target in targets:
                (inner if target.split(".")[0] == "prsc" else outer).add(target if target.startswith("prsc")
                                                                          else target.split(".")[0])
        graph[name] = (inner, outer)
    return graph


API = {"prsc.scenario", "prsc.scene_env", "prsc.scene_cameras", "prsc.record_episodes"}  # the library API (prsc.load, SceneEnv and its camera views, RecordEpisodes)


def _layer(module: str) -> str:
    if module in FOUNDATION:
        return "foundation"
    if module in API:
        return "api"
    parts = module.split(".")
    if parts[:2] == ["prsc", "backends"] or parts[:2] == ["prsc", "assets"]:
        return parts[1]
    return parts[1] if len(parts) > 1 and parts[1] in ALLOWED else module


def test_each_layer_imports_only_the_layers_below_it():
    wrong = []
    for module, (inner, _) in _graph().items():
        layer = _layer(module)
        if layer not in ALLOWED:
            continue  # prsc itself (the library API) and prsc.cli sit on top
        for target in inner:
            other = _layer(target)
            if other != layer and other != "foundation" and other not in ALLOWED[layer]:
                wrong.append(f"{module} -> {target}")
    assert wrong == []


def test_geometry_is_pure_math_and_the_parser_knows_no_semantics():
    graph = _graph()
    geometry = {m: sorted(outer - PURE_MATH) for m, (_, outer) in graph.items() if _layer(m) == "geometry"}
    assert {m: o for m, o in geometry.items() if o} == {}
    syntax = {m: sorted(t for t in inner if _layer(t) not in ("syntax", "foundation")) + sorted(outer - PURE_MATH - {"lark"})
              for m, (inner, outer) in graph.items() if _layer(m) == "syntax"}
    assert {m: o for m, o in syntax.items() if o} == {}


@pytest.mark.parametrize("edge", FORBIDDEN_EDGES, ids=lambda e: f"{e[0]}->{e[1]}")
def test_the_broken_cycles_stay_broken(edge):
    module, target = edge
    assert target not in _graph()[module][0]


def test_backends_never_read_a_commands_manifest():
    """Which scenes an output folder holds is prsc.commands' business (output_folder.compiled_scenes)."""
    readers = [p.name for folder in (REPO / "backends", REPO / "prsc" / "runner")
               for p in folder.rglob("*.py") if "manifest.json" in p.read_text()]
    assert readers == []


def test_no_import_cycles():
    graph = {m: {t for t in inner if t in _graph()} for m, (inner, _) in _graph().items()}
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    cycles = []

    def visit(v: str) -> None:  # Tarjan's strongly connected components
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                cycles.append(sorted(component))

    sys.setrecursionlimit(max(sys.getrecursionlimit(), 10_000))
    for v in graph:
        if v not in index:
            visit(v)
    assert cycles == []


def test_module_names_are_unique():
    """A module's name says which one it is: no two modules of the tree share a file name."""
    names: dict[str, list[str]] = {}
    for folder in ROOTS.values():
        for path in folder.rglob("*.py"):
            if path.name != "__init__.py":
                names.setdefault(path.name, []).append(str(path.relative_to(REPO)))
    assert {name: paths for name, paths in names.items() if len(paths) > 1} == {}
