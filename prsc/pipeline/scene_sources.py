"""Where `prsc compile` reads its scenes: a .prs spec's sampler, or scene JSON files.

Scene files are read whole and validated before any output is written, so an error points
into the file (the line of a .jsonl, the position in a list).
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any, Callable, Sequence

from prsc.errors import PrscError, Span

MAX_JSON_DEPTH = 100  # reported when a scene file is nested too deeply for Python's JSON reader


def read_input(path: Path) -> bytes:
    """The bytes of an input file, or a PrscError saying why it cannot be read."""
    try:
        return path.read_bytes()
    except IsADirectoryError:
        raise PrscError(f"{path} is a directory, not a spec or scene file") from None
    except OSError as error:
        raise PrscError(f"cannot read {path}: {os.strerror(error.errno) if error.errno else error}") from None


def read_scene_file(path: Path, data: bytes | None = None) -> list[dict]:
    """Scenes of a .json (one scene or a list) or .jsonl file, each validated.

    Validated here, before any output is written, so that an error points into the file
    (line of a .jsonl, position in a list) rather than surfacing halfway through a run."""
    from prsc.backends.scene import parse_scene
    from prsc.syntax import decode_text

    text = decode_text(read_input(path) if data is None else data, str(path))

    def invalid(error: json.JSONDecodeError, line: int) -> PrscError:
        return PrscError(f"invalid JSON: {error.msg}", Span(str(path), line, error.colno, line, error.colno + 1))

    def too_deep(document: str, first_line: int) -> PrscError:
        line, column = _nesting_place(document, MAX_JSON_DEPTH)
        return PrscError(f"JSON nested more than {MAX_JSON_DEPTH} levels deep",
                         Span(str(path), first_line + line - 1, column, first_line + line - 1, column + 1))

    # (line number, scene): split on "\n" only, as the error renderer counts lines.
    found: list[tuple[int | None, object]] = []
    listed = True  # several scenes: name the one at fault
    if path.suffix == ".jsonl":
        for number, line in enumerate(text.split("\n"), start=1):
            if line.strip():
                try:
                    found.append((number, json.loads(line)))
                except json.JSONDecodeError as error:
                    raise invalid(error, number) from None
                except RecursionError:
                    raise too_deep(line, number) from None
    else:
        try:
            loaded = json.loads(text)
        except json.JSONDecodeError as error:
            raise invalid(error, error.lineno) from None
        except RecursionError:
            raise too_deep(text, 1) from None
        listed = isinstance(loaded, list)
        found = [(None, s) for s in loaded] if listed else [(None, loaded)]
    if not found:
        raise PrscError(f"{path}: no scenes in the file")
    for k, (line, scene) in enumerate(found):
        try:
            parse_scene(scene)  # type: ignore[arg-type]
        except PrscError as error:
            message = error.message.removeprefix("scene JSON: ")  # the file name says as much
            if line is not None:
                raise PrscError(message, Span(str(path), line, 1, line, 2)) from None
            raise PrscError(f"{path}: {f'scene {k}: ' if listed else ''}{message}") from None
    return [scene for _, scene in found]  # type: ignore[misc]


def _nesting_place(text: str, limit: int) -> tuple[int, int]:
    """(line, column) of the bracket that opens level `limit + 1` of a JSON text (strings skipped)."""
    depth, line, column, in_string, escaped = 0, 1, 0, False, False
    for char in text:
        column += 1
        if char == "\n":
            line, column = line + 1, 0
        elif in_string:
            escaped, in_string = (False, True) if escaped else (char == "\\", char != '"')
        elif char == '"':
            in_string = True
        elif char in "[{":
            depth += 1
            if depth > limit:
                return line, column
        elif char in "]}":
            depth -= 1
    return 1, 1


def add_law_argument(parser: Any) -> None:
    """The --law option of the commands that sample a spec (docs/sampling.md)."""
    parser.add_argument("--law", choices=("joint", "sequential", "rejection"), default=None,
                        help="joint (default: the paper's law, by candidate rounds or Gibbs sweeps), sequential (objects one at a time, "
                             "faster; the default with --proposal or --sampler hit-and-run), or rejection (the joint "
                             "law by whole-scene rejection: the exact reference)")


def spec_sampler(spec: str, seed: int, include_dirs: Sequence[str] = (), law: str | None = None,
                 proposal: dict | None = None) -> Callable[[int], dict]:
    """Scene k of a .prs spec as scene JSON (the sampler is imported only when needed)."""
    from prsc.sampling import compile_sampler

    sampler = compile_sampler(spec, include_dirs=include_dirs, law=law, proposal=proposal_from_json(proposal))
    return sampler.drawer(seed)


def add_proposal_argument(parser: Any) -> None:
    """`--proposal DIR/proposal.json` (sample, compile, run)."""
    parser.add_argument("--proposal", metavar="JSON", default=None,
                        help="draw scenes from a proposal `prsc falsify` learnt (DIR/proposal.json): "
                             "the hard cases, still satisfying the spec")


def read_proposal(path: str | None, source: str) -> dict | None:
    """The JSON of --proposal (validated), or None; an error when the input is scene JSON, not a spec."""
    if path is None:
        return None
    if Path(source).suffix in (".json", ".jsonl"):
        raise PrscError("--proposal draws new scenes from a .prs spec; it does not apply to scene JSON")
    from prsc.sampling.proposal import load_proposal

    return load_proposal(path).to_json()


def proposal_key(data: dict | None) -> bytes:
    """The bytes that identify a proposal in a folder's source digest (none without one)."""
    return b"" if data is None else json.dumps(data, sort_keys=True).encode("utf-8")


def proposal_from_json(data: dict | None) -> Any:
    """A Proposal from its JSON, or None."""
    if data is None:
        return None
    from prsc.sampling.proposal import Proposal

    return Proposal.from_json(data)
