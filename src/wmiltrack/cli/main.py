"""The ``wmiltrack`` command line: one module per subcommand, registered in :data:`SUBCOMMANDS`.

Each subcommand module has a function ``add_<name>(subparsers)`` that defines its arguments
and sets ``func``, so a new command is one module and one line here.
"""

from __future__ import annotations

import argparse
import os
import signal
import sys
import textwrap
from collections.abc import Callable, Sequence
from importlib import import_module
from typing import Any, NoReturn

from .options import (
    EXIT_CODES_EPILOG,
    EXIT_ERROR,
    EXIT_SIGINT,
    EXIT_SIGPIPE,
    EXIT_USAGE,
    Subparsers,
    UsageError,
    join_negative_values,
)

#: FFmpeg's and OpenCV's own log lines (``moov atom not found``, ``[ WARN:0@...]``) would reach
#: the user ahead of the command's own message; both libraries read these when first used.
QUIET_OPENCV = {"OPENCV_FFMPEG_LOGLEVEL": "-8", "OPENCV_LOG_LEVEL": "ERROR"}  # -8: AV_LOG_QUIET


class _HelpFormatter(argparse.HelpFormatter):
    """argparse's help, with lines broken at spaces only: a preset's name (``rcwmil-plus``)
    or an option (``--cv-threads``) is never split over two lines."""

    def _split_lines(self, text: str, width: int) -> list[str]:
        return textwrap.wrap(" ".join(text.split()), width, break_on_hyphens=False)

    def _fill_text(self, text: str, width: int, indent: str) -> str:
        return textwrap.fill(" ".join(text.split()), width, initial_indent=indent,
                             subsequent_indent=indent, break_on_hyphens=False)


class _Parser(argparse.ArgumentParser):
    """argparse with the command line's one error prefix, ``wmiltrack: error:``, and help
    text that keeps names whole (:class:`_HelpFormatter`); subcommands' parsers are made by
    this class too."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        kwargs.setdefault("formatter_class", _HelpFormatter)
        super().__init__(*args, **kwargs)

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
    (".models", "add_models"),
]


def build_parser() -> argparse.ArgumentParser:
    """The ``wmiltrack`` argument parser with every registered subcommand."""
    from .. import __version__

    parser = _Parser(
        prog="wmiltrack",
        description="Fast single-object visual tracking (RCWMIL and its family) and tracker benchmarks.",
        epilog=EXIT_CODES_EPILOG,
    )
    parser.add_argument("--version", action="version", version=f"wmiltrack {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for module, func in SUBCOMMANDS:
        adder: Callable[[Subparsers], None] = getattr(import_module(module, __package__), func)
        adder(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line on ``argv`` (default: ``sys.argv[1:]``); returns the exit status.

    Every error is one ``wmiltrack: error: ...`` line, not a traceback, and every subcommand
    has the exit statuses of :data:`~wmiltrack.cli.options.EXIT_CODES`: 2 for a command line
    that cannot run as given (argparse's errors, :class:`UsageError`), 1 for errors of the
    input or the run (bad files, unavailable trackers, OpenCV errors), 130 for Ctrl-C (one
    line, no traceback); output cut short by a closed pipe (``wmiltrack variants | head -5``)
    ends quietly with status 141.
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
    except KeyboardInterrupt:
        # Ctrl-C: one line, not the traceback of wherever the run was (signals are now
        # ignored, so that a second Ctrl-C cannot cut this line or the exit short)
        _ignore_interrupts()
        print("wmiltrack: interrupted by SIGINT (Ctrl-C); what was finished is written",
              file=sys.stderr)
        return EXIT_SIGINT
    except (ValueError, TypeError, FileNotFoundError, RuntimeError) as exc:
        print(f"wmiltrack: error: {exc}", file=sys.stderr)
        return EXIT_ERROR
    except Exception as exc:
        if type(exc).__module__.split(".")[0] != "cv2":  # cv2.error: OpenCV refused the input
            raise
        print(f"wmiltrack: error: OpenCV: {str(exc).strip().splitlines()[-1]}", file=sys.stderr)
        return EXIT_ERROR


def _ignore_interrupts() -> None:
    """Ignore further SIGINTs while the command line reports an interrupt and exits."""
    try:
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    except ValueError:  # not the main thread
        pass


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
