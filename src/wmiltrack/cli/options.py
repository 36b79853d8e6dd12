"""Options shared by the subcommands: boxes, parameter overrides, the tracker to run."""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from typing import Any

Subparsers = Any  # argparse's _SubParsersAction is private


def parse_box(text: str) -> tuple[float, float, float, float]:
    """``x,y,w,h`` (commas, semicolons or spaces) as four floats, for ``--box``."""
    parts = text.replace(";", ",").replace(" ", ",").split(",")
    parts = [p for p in parts if p]
    try:
        values = tuple(float(p) for p in parts)
    except ValueError:
        raise argparse.ArgumentTypeError(f"--box needs four numbers x,y,w,h; got {text!r}") from None
    if len(values) != 4:
        raise argparse.ArgumentTypeError(f"--box needs four numbers x,y,w,h; got {text!r}")
    return values[0], values[1], values[2], values[3]


def parse_overrides(items: Sequence[str]) -> dict[str, Any]:
    """``--set name=value`` pairs; values are read as Python literals where possible."""
    import ast

    out: dict[str, Any] = {}
    for item in items:
        if "=" not in item:
            raise SystemExit(f"wmiltrack: --set expects name=value, got {item!r}")
        key, raw = item.split("=", 1)
        try:
            out[key.strip()] = ast.literal_eval(raw)
        except (ValueError, SyntaxError):
            out[key.strip()] = raw
    return out


def add_tracker_options(p: argparse.ArgumentParser) -> None:
    """``-t/--tracker``, ``--seed`` and ``--set NAME=VALUE``, shared by the commands that run one tracker."""
    p.add_argument("-t", "--tracker", default="rcwmil",
                   help="variant: rcwmil (default), ct, fct, mil, wmil, osil, or opencv:NAME")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="override a parameter, e.g. --set num_selected=30 (repeatable)")
