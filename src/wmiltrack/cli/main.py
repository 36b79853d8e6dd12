"""The ``wmiltrack`` command line: one module per subcommand, registered in :data:`SUBCOMMANDS`.

Each subcommand module has a function ``add_<name>(subparsers)`` that defines its arguments
and sets ``func``, so a new command is one module and one line here.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Sequence
from importlib import import_module

from .options import Subparsers

# -- registry ------------------------------------------------------------------------------
#: (module, function) pairs; a module's function adds its subcommand.
SUBCOMMANDS: list[tuple[str, str]] = [
    (".track", "add_track"),
    (".demo", "add_demo"),
    (".variants", "add_variants"),
    (".eval", "add_eval"),
    (".inspect", "add_inspect"),
]


def build_parser() -> argparse.ArgumentParser:
    """The ``wmiltrack`` argument parser with every registered subcommand."""
    from .. import __version__

    parser = argparse.ArgumentParser(
        prog="wmiltrack",
        description="Fast single-object visual tracking (RCWMIL and its family) and tracker benchmarks.",
    )
    parser.add_argument("--version", action="version", version=f"wmiltrack {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for module, func in SUBCOMMANDS:
        adder: Callable[[Subparsers], None] = getattr(import_module(module, __package__), func)
        adder(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line on ``argv`` (default: ``sys.argv[1:]``); returns the exit status.

    Errors a user can fix (bad input, missing files, unavailable trackers) are printed as
    one ``wmiltrack: error: ...`` line with exit status 1, not as a traceback.
    """
    parser = build_parser()
    args = parser.parse_args(argv)
    if not hasattr(args, "func"):
        parser.print_help()
        return 2
    try:
        return int(args.func(args))
    except (ValueError, TypeError, FileNotFoundError, RuntimeError) as exc:
        print(f"wmiltrack: error: {exc}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
