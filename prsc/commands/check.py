"""`prsc check FILE... [--include DIR]`: parse and type-check specs, summarise their objects."""

from __future__ import annotations

import argparse
import sys

from prsc.errors import PrscError, format_error


def add_parser(subparsers) -> None:
    """Register `prsc check`."""
    parser = subparsers.add_parser(
        "check", help="parse and type-check specs; list objects and specifiers in evaluation order",
        description="Parse and type-check .prs specs, with every check `compile` makes before it samples "
                    "(containers, meshes, reach, file names). Prints each object, its class and its specifiers "
                    "in evaluation order. Exit status 0 when every file is clean, 2 otherwise.")
    parser.add_argument("files", nargs="+", metavar="FILE", help="spec files (.prs)")
    parser.add_argument("--include", "-I", action="append", default=[], metavar="DIR",
                        help="also search DIR for imported .prs files (after the importing file's directory)")
    parser.add_argument("--quiet", "-q", action="store_true", help="print nothing for clean files")


def summarise(program) -> str:
    """A few lines per spec: objects, classes and specifiers in evaluation order."""
    from prsc.ir.format import format_specifier

    files = len(program.source_files)
    lines = [f"{program.path}: ok, {len(program.objects)} object{'s' * (len(program.objects) != 1)}"
             + (f", {len(program.requires)} require{'s' * (len(program.requires) != 1)}" if program.requires else "")
             + (f" ({files} files)" if files > 1 else "")]
    for obj in program.objects:
        specs = "; ".join(format_specifier(s) for s in obj.specifiers) or "(no specifiers)"
        lines.append(f"  {obj.name}: {obj.class_name} -- {specs}")
    if program.task:
        from prsc.task.describe import describe_statements

        lines.append("  task (docs/tasks.md):")
        lines.extend(f"    {line}" for line in describe_statements(program.task))
    return "\n".join(lines) + "\n"


def run(args: argparse.Namespace) -> int:
    """Check every file as far as `compile` goes before sampling; report each error; 2 if any file has one."""
    from prsc.pipeline.static_checks import compile_checked

    failed = 0
    for path in args.files:
        try:
            program = compile_checked(path, args.include).program
        except PrscError as error:
            sys.stderr.write(format_error(error))
            failed += 1
            continue
        if not args.quiet:
            sys.stdout.write(summarise(program))
    return 2 if failed else 0
