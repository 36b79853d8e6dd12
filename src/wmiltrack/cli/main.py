"""The ``wmiltrack`` command line: one module per subcommand, registered in :data:`SUBCOMMANDS`.

Each subcommand module has a function ``add_<name>(subparsers)`` that defines its arguments
and sets ``func``, so a new command is one module and one line here.
"""

from __future__ import annotations

import argparse
import os
import signal
import sys
from collections.abc import Callable, Sequence
from importlib import import_module
from typing import NoReturn

from .options import Subparsers, UsageError, join_negative_values

#: FFmpeg's and OpenCV's own log lines (``moov atom not found``, ``[ WARN:0@...]``) would reach
#: the user ahead of the command's own message; both libraries read these when first used.
QUIET_OPENCV = {"OPENCV_FFMPEG_LOGLEVEL": "-8", "OPENCV_LOG_LEVEL": "ERROR"}  # -8: AV_LOG_QUIET
EXIT_USAGE = 2
EXIT_SIGPIPE = 128 + int(getattr(signal, "SIGPIPE", 13))


class _Parser(argparse.ArgumentParser):
    """argparse with the command line's one error prefix, ``wmiltrack: error:``."""

    def error(self, message: str) -> NoReturn:
        self.print_usage(sys.stderr)
        self.exit(EXIT_USAGE, f"wmiltrack: error: {message}\n")

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

    parser = _Parser(
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

    Every error is one ``wmiltrack: error: ...`` line, not a traceback: exit status 2 for a
    command line that cannot run as given (argparse's errors, :class:`UsageError`), 1 for
    errors of the input or the run (bad files, unavailable trackers, OpenCV errors). Output cut
    short by a closed pipe (``wmiltrack variants | head -5``) ends quietly with status 141.
    """
    for key, value in QUIET_OPENCV.items():
        os.environ.setdefault(key, value)
    parser = build_parser()
    args = parser.parse_args(join_negative_values(sys.argv[1:] if argv is None else argv))
    if not hasattr(args, "func"):
        parser.print_help()
        return EXIT_USAGE
    try:
        return int(args.func(args))
    except UsageError as exc:
        print(f"wmiltrack: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except BrokenPipeError:
        _silence_stdout()
        return EXIT_SIGPIPE
    except (ValueError, TypeError, FileNotFoundError, RuntimeError) as exc:
        print(f"wmiltrack: error: {exc}", file=sys.stderr)
        return 1
    except Exception as exc:
        if type(exc).__module__.split(".")[0] != "cv2":  # cv2.error: OpenCV refused the input
            raise
        print(f"wmiltrack: error: OpenCV: {str(exc).strip().splitlines()[-1]}", file=sys.stderr)
        return 1


def _silence_stdout() -> None:
    """Point standard output at /dev/null, so that flushing it at exit after the reader went
    away (a closed pipe) raises nothing more."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError):  # no real file descriptor (captured output)
        pass


if __name__ == "__main__":
    sys.exit(main())
