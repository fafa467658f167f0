"""The `prsc` command line: one subcommand module per verb in prsc/commands/."""

from __future__ import annotations

import argparse
import importlib
import importlib.util
import io
import os
import signal
import sys
from typing import Any, Callable, TextIO

from prsc.errors import PrscError, format_error

# Each module in prsc.commands exposes `add_parser(subparsers)` and `run(args) -> int`.
# Imported lazily so `prsc check` does not pay for mujoco, pxr or pybullet.
COMMANDS = ("check", "explain", "sample", "compile", "run", "replay", "falsify", "bench", "preview", "reach")
# The last line of each command's --help: a command to run from a clone (reach: the arm pybullet ships,
# PYBULLET_DATA being pybullet_data.getDataPath()). tests/cli/test_help_examples.py parses each.
EXAMPLES = {
    "check": "prsc check specs/table_cube.prs",
    "explain": "prsc explain specs/table_cube.prs --stage constraints",
    "sample": "prsc sample specs/table_cube.prs -n 10 --seed 0 -o scenes.jsonl",
    "compile": "prsc compile specs/table_cube.prs --target mjcf,usd -n 100 -o out",
    "run": "prsc run specs/table_cube.prs -n 20 --seed 0 --jobs 2 -o out/run",
    "replay": "prsc replay out/demos --episode 0 --frames frames",
    "falsify": "prsc falsify specs/table_cube.prs --budget 200 -o out/falsify",
    "bench": "prsc bench specs/table_cube.prs specs/table_cube_naive.prs",
    "preview": "prsc preview specs/table_cube.prs -n 8 -o sheet.png",
    "reach": "prsc reach xarm/xarm6_robot.urdf -I \"$PYBULLET_DATA\" --plot r.png",
}
DESCRIPTION = (
    "prsc: a compiler for probabilistic 3D scene specifications (.prs). It samples scenes that "
    "satisfy a spec's constraints exactly and writes them for simulators (MJCF, URDF, SDF, USD). "
    "Run `prsc COMMAND --help` for a command's options."
)


def _available_commands() -> list[str]:
    """Commands whose module exists (the stages land one at a time)."""
    found = []
    for name in COMMANDS:
        if importlib.util.find_spec(f"prsc.commands.{name}") is not None:
            found.append(name)
    return found


def build_parser(only: str | None = None) -> argparse.ArgumentParser:
    """The argument parser with every available subcommand (or just `only`, to import less)."""
    parser = argparse.ArgumentParser(prog="prsc", description=DESCRIPTION)
    sub = parser.add_subparsers(dest="command", required=True)
    for name in _available_commands():
        if only is not None and name != only:
            continue
        module = importlib.import_module(f"prsc.commands.{name}")
        module.add_parser(sub)
        if name in EXAMPLES:
            sub.choices[name].epilog = f"example: {EXAMPLES[name]}"
    return parser


def _requested_command(argv: list[str]) -> str | None:
    """The subcommand named first on the command line, when it is an available one."""
    for word in argv:
        if word.startswith("-"):
            return None  # a global option (e.g. --help): build the full parser
        return word if word in _available_commands() else None
    return None


def _discard_stdout() -> None:
    """Point standard output at /dev/null, so what is still buffered cannot fail again at exit."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError, io.UnsupportedOperation):
        pass  # not a real file (e.g. captured by a test): nothing is flushed at exit


class _GuardedStdout:
    """sys.stdout whose write failures (a full disk, an I/O error) are user errors, not prsc bugs."""

    def __init__(self, stream: TextIO | None) -> None:
        # Python sets sys.stdout to None when file descriptor 1 is closed (`prsc ... >&-`).
        self._closed = stream is None
        self._stream = open(os.devnull, "w", encoding="utf-8") if stream is None else stream

    def _guard(self, method: Callable[..., Any], *args: Any) -> Any:
        try:
            return method(*args)
        except BrokenPipeError:
            raise  # the reader went away: main() stops quietly
        except OSError as error:
            _discard_stdout()
            raise PrscError(f"cannot write to standard output: {error.strerror or error}") from None

    def write(self, text: str) -> int:
        """Write text, as sys.stdout does."""
        if self._closed and text:
            raise PrscError("cannot write to standard output: it is closed")
        return self._guard(self._stream.write, text)

    def writelines(self, lines: Any) -> None:
        """Write each line, as sys.stdout does."""
        if self._closed:
            lines = list(lines)
            if any(lines):
                raise PrscError("cannot write to standard output: it is closed")
        self._guard(self._stream.writelines, lines)

    def flush(self) -> None:
        """Flush, as sys.stdout does."""
        self._guard(self._stream.flush)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._stream, name)


class Terminated(BaseException):
    """SIGTERM, raised in the main thread so that cleanup (temporaries, the manifest) runs."""


def _raise_terminated(signum: int, frame: Any) -> None:
    raise Terminated


def _on_sigterm(handler: Any) -> Any:
    """Set the SIGTERM handler; returns the previous one (None off the main thread, where it cannot be set)."""
    try:
        return signal.signal(signal.SIGTERM, handler)
    except ValueError:  # not the main thread (e.g. main() called from a test's thread)
        return None


def main(argv: list[str] | None = None) -> int:
    """Entry point: run a subcommand, turning user errors into exit code 2."""
    words = sys.argv[1:] if argv is None else list(argv)
    # Import only the requested command's module: `prsc check` must not pay for numpy.
    parser = build_parser(_requested_command(words))
    args = parser.parse_args(words)
    module = importlib.import_module(f"prsc.commands.{args.command}")
    stdout = sys.stdout
    sys.stdout = _GuardedStdout(stdout)  # type: ignore[assignment]
    previous = _on_sigterm(_raise_terminated)
    try:
        code = int(module.run(args) or 0)
        sys.stdout.flush()  # here, not at exit, so that a failure is reported like any other
        return code
    except PrscError as error:
        sys.stderr.write(format_error(error))
        return 2
    except KeyboardInterrupt:
        sys.stderr.write("prsc: interrupted\n")
        return 130
    except Terminated:
        sys.stderr.write("prsc: terminated\n")
        return 143
    except BrokenPipeError:
        # The reader went away (`prsc sample … | head`): stop quietly, as Unix tools do.
        _discard_stdout()
        return 141
    except Exception as error:  # a bug in prsc, not in the user's input
        if isinstance(error, OSError):  # but a build folder prsc cannot write is the user's to mend
            from prsc.user_assets.asset_files import build_folder_error

            known = build_folder_error(error)
            if known is not None:
                sys.stderr.write(format_error(known))
                return 2
        if os.environ.get("PRSC_DEBUG"):
            raise
        sys.stderr.write(
            f"prsc: internal error: {type(error).__name__}: {error}\n"
            "  (this is a bug in prsc; rerun with PRSC_DEBUG=1 for the traceback)\n"
        )
        return 3
    finally:
        sys.stdout = stdout
        if previous is not None:
            _on_sigterm(previous)


if __name__ == "__main__":
    sys.exit(main())
