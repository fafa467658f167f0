"""The `prsc` command line: one subcommand module per verb in prsc/commands/."""

from __future__ import annotations

import argparse
import importlib
import os
import importlib.util
import sys

from prsc.errors import PrscError, format_error

# Each module in prsc.commands exposes `add_parser(subparsers)` and `run(args) -> int`.
# Imported lazily so `prsc check` does not pay for mujoco, pxr or pybullet.
COMMANDS = ("check", "explain", "sample", "compile", "run", "bench", "preview")


def _available_commands() -> list[str]:
    """Commands whose module exists (the stages land one at a time)."""
    found = []
    for name in COMMANDS:
        if importlib.util.find_spec(f"prsc.commands.{name}") is not None:
            found.append(name)
    return found


def build_parser(only: str | None = None) -> argparse.ArgumentParser:
    """The argument parser with every available subcommand (or just `only`, to import less)."""
    parser = argparse.ArgumentParser(prog="prsc", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    for name in _available_commands():
        if only is not None and name != only:
            continue
        module = importlib.import_module(f"prsc.commands.{name}")
        module.add_parser(sub)
    return parser


def _requested_command(argv: list[str]) -> str | None:
    """The subcommand named first on the command line, when it is an available one."""
    for word in argv:
        if word.startswith("-"):
            return None  # a global option (e.g. --help): build the full parser
        return word if word in _available_commands() else None
    return None


def main(argv: list[str] | None = None) -> int:
    """Entry point: run a subcommand, turning user errors into exit code 2."""
    words = sys.argv[1:] if argv is None else list(argv)
    # Import only the requested command's module: `prsc check` must not pay for numpy.
    parser = build_parser(_requested_command(words))
    args = parser.parse_args(words)
    module = importlib.import_module(f"prsc.commands.{args.command}")
    try:
        return int(module.run(args) or 0)
    except PrscError as error:
        sys.stderr.write(format_error(error))
        return 2
    except KeyboardInterrupt:
        sys.stderr.write("prsc: interrupted\n")
        return 130
    except BrokenPipeError:
        # The reader went away (`prsc sample … | head`): stop quietly, as Unix tools do.
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 141
    except Exception as error:  # a bug in prsc, not in the user's input
        if os.environ.get("PRSC_DEBUG"):
            raise
        sys.stderr.write(
            f"prsc: internal error: {type(error).__name__}: {error}\n"
            "  (this is a bug in prsc; rerun with PRSC_DEBUG=1 for the traceback)\n"
        )
        return 3


if __name__ == "__main__":
    sys.exit(main())
