"""Options shared by the subcommands: boxes, parameter overrides, the tracker to run."""

from __future__ import annotations

import argparse
import math
import re
import signal
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

Subparsers = Any  # argparse's _SubParsersAction is private

# -- exit status: one table for every subcommand ----------------------------------------------
EXIT_OK = 0
"""The command did what was asked."""
EXIT_ERROR = 1
"""The run failed: an input that cannot be read, a tracker that is not installed or fails, an
output that cannot be written."""
EXIT_USAGE = 2
"""The command line cannot run as given, found before anything ran or was written: a bad
option, an unknown tracker or parameter, a bad box, an output that would overwrite an input."""
EXIT_SIGINT = 128 + int(signal.SIGINT)
"""Interrupted by Ctrl-C (SIGINT): 130."""
EXIT_SIGPIPE = 128 + int(getattr(signal, "SIGPIPE", 13))
"""Standard output was closed by its reader (``wmiltrack variants | head -1``): 141, quietly,
as a shell command killed by SIGPIPE."""

EXIT_CODES = {
    EXIT_OK: "done",
    EXIT_ERROR: "the run failed (an input that cannot be read, a tracker that is not installed "
                "or fails, an output that cannot be written)",
    EXIT_USAGE: "bad command line or input, refused before anything ran or was written (an "
                "unknown tracker or parameter, a bad box, an output that is an input)",
    EXIT_SIGINT: "interrupted by Ctrl-C (SIGINT)",
    EXIT_SIGPIPE: "standard output closed by its reader (| head), quietly",
}
"""The exit statuses of every ``wmiltrack`` subcommand, as each ``--help`` lists them."""

EXIT_CODES_EPILOG = "Exit status: " + "; ".join(f"{k} {v}" for k, v in EXIT_CODES.items()) + "."

#: Options whose value may start with a minus sign (``--box -10,-10,40,40``).
BOX_OPTIONS = ("--box",)
_NEGATIVE_VALUE = re.compile(r"^-[0-9.]")


class UsageError(ValueError):
    """The command line cannot run as given (a bad option value, a missing option, an unknown
    tracker or parameter): ``wmiltrack: error: ...`` and exit status 2, as argparse's own."""


def join_negative_values(argv: Sequence[str]) -> list[str]:
    """``--box -10,-10,40,40`` as ``--box=-10,-10,40,40``: argparse takes a value that starts
    with ``-`` and is not a plain number for an option, so a box left of or above the frame
    could only be given with ``=``."""
    out: list[str] = []
    args = list(argv)
    i = 0
    while i < len(args):
        if args[i] in BOX_OPTIONS and i + 1 < len(args) and _NEGATIVE_VALUE.match(args[i + 1]):
            out.append(f"{args[i]}={args[i + 1]}")
            i += 2
            continue
        if args[i] == "--":  # everything after is positional
            out += args[i:]
            break
        out.append(args[i])
        i += 1
    return out


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
    if not all(math.isfinite(v) for v in values):
        raise argparse.ArgumentTypeError(f"--box needs finite numbers; got {text!r}")
    if values[2] <= 0 or values[3] <= 0:
        raise argparse.ArgumentTypeError(f"--box needs a positive width and height; got {text!r}")
    return values[0], values[1], values[2], values[3]


def parse_overrides(items: Sequence[str]) -> dict[str, Any]:
    """``--set name=value`` pairs; values are read as Python literals where possible."""
    import ast

    out: dict[str, Any] = {}
    for item in items:
        if "=" not in item:
            raise UsageError(f"--set expects name=value, got {item!r}")
        key, raw = item.split("=", 1)
        try:
            out[key.strip()] = ast.literal_eval(raw)
        except (ValueError, SyntaxError):
            out[key.strip()] = raw
    return out


def preset_names() -> list[str]:
    """wmiltrack's presets, from the registry (:data:`wmiltrack.engine.params.VARIANTS`): every
    list of presets the command line shows is made from it."""
    from ..engine.params import VARIANTS

    return list(VARIANTS)


def trackers_help(default: str | None = "rcwmil", *, opencv: bool = True) -> str:
    """The help text of a tracker option: the presets, from the registry, and OpenCV's."""
    from ..integrations.opencv_wheels import OPENCV_TRACKERS

    text = f"a preset: {', '.join(preset_names())}"
    if opencv:
        from ..networks.files import nanotrack_versions

        nano = " or ".join(f"nanotrack:{v}" for v in nanotrack_versions())
        text += (f"; {nano} (NanoTrack alone); or opencv:NAME, NAME one of "
                 f"{', '.join(OPENCV_TRACKERS)}")
    text += " (`wmiltrack variants` lists the presets and their parameters)"
    if default is not None:
        text += f"; default {default}"
    return text


def check_tracker_spec(spec: str) -> None:
    """A :class:`UsageError` (exit status 2) for a tracker spec that names no tracker or sets
    a parameter the tracker does not have; an OpenCV tracker that is valid but missing from the
    installed ``cv2`` passes (running it is a runtime failure, exit status 1)."""
    from ..engine.params import Params
    from ..integrations.opencv_wheels import parse_opencv_name
    from ..trackers import is_opencv_spec, parse_spec

    try:
        name, overrides = parse_spec(spec)
        if is_opencv_spec(name):
            parse_opencv_name(name)
            return
        if name.lower() in preset_names():
            Params.for_variant(name, **overrides)  # an unknown parameter or a bad value
            return
        from ..trackers import NANOTRACK_PREFIX, make_tracker

        if name.lower().startswith(NANOTRACK_PREFIX):  # checked without loading the network
            _check_nanotrack_spec(name[len(NANOTRACK_PREFIX):].lower(), overrides)
            return

        make_tracker(spec)  # not a preset: the registry's own answer ("did you mean ...")
    except (ValueError, TypeError) as exc:
        raise UsageError(str(exc)) from None


def _check_nanotrack_spec(version: str, overrides: dict[str, Any]) -> None:
    """``nanotrack:VERSION[:key=value...]``: a known version and only the keywords
    :class:`~wmiltrack.integrations.nanotrack_peer.NanoTracker` takes."""
    from ..networks.files import nanotrack_versions

    if version not in nanotrack_versions():
        raise ValueError(f"unknown NanoTrack version {version!r} in nanotrack:{version}; choose "
                         f"{' or '.join('nanotrack:' + v for v in nanotrack_versions())}")
    unknown = sorted(set(overrides) - {"backbone", "head", "runtime", "threads"})
    if unknown:
        raise ValueError(f"nanotrack:{version} has no parameter {', '.join(map(repr, unknown))}; "
                         "it takes backbone, head, runtime and threads")


def add_model_options(p: argparse.ArgumentParser) -> None:
    """``--nano-backbone``, ``--nano-head`` and ``--vit-model``: the model files of the network
    trackers (``opencv:Nano``, ``opencv:Vit``, ``nanotrack:VERSION`` and rcwmil-nano), which no
    wheel ships; each goes to the trackers that run its network (:func:`model_keywords`)."""
    from ..networks.files import MODEL_ENV, MODELS

    v2, v3 = MODELS["nanotrack-v2"].files, MODELS["nanotrack-v3"].files
    p.add_argument("--nano-backbone", type=Path, default=None, metavar="FILE",
                   help="NanoTrack's backbone, for the trackers of its version: v2's "
                   f"({v2['backbone'].name}) for opencv:Nano, nanotrack:v2 and rcwmil-nano "
                   f"with network=nanotrack-v2, v3's ({v3['backbone'].name}) for nanotrack:v3 "
                   f"and rcwmil-nano (default: {MODEL_ENV['Nano']['backbone']}, then the models "
                   "folder, see `wmiltrack models list`; in eval, TRACKER:backbone=FILE gives one "
                   "tracker its own)")
    p.add_argument("--nano-head", type=Path, default=None, metavar="FILE",
                   help=f"NanoTrack's head, as --nano-backbone: v2's ({v2['head'].name}) or "
                   f"v3's ({v3['head'].name}); opencv:Nano calls it neckhead")
    p.add_argument("--vit-model", type=Path, default=None, metavar="FILE",
                   help="for opencv:Vit: " + _vit_file() + " (default: the environment "
                   "variable WMILTRACK_VIT_MODEL)")


def _vit_file() -> str:
    from ..integrations.opencv_peers import MODEL_FILES

    return MODEL_FILES[("Vit", "net")]


#: Each model option's tracker keyword, by the kind of tracker that takes it.
_KEYWORDS = {
    "opencv:Nano": {"--nano-backbone": "backbone", "--nano-head": "neckhead"},
    "opencv:Vit": {"--vit-model": "net"},
    "nanotrack": {"--nano-backbone": "backbone", "--nano-head": "head"},
}
_ROLES = {"--nano-backbone": "backbone", "--nano-head": "head"}


def given_model_files(args: argparse.Namespace) -> dict[str, Path]:
    """The model files given by option (:func:`add_model_options`), by option, as absolute
    paths; a path that is not a file is a :class:`UsageError`."""
    out: dict[str, Path] = {}
    for option in ("--nano-backbone", "--nano-head", "--vit-model"):
        path = getattr(args, option.lstrip("-").replace("-", "_"), None)
        if path is None:
            continue
        if not Path(path).expanduser().is_file():
            raise UsageError(f"{option} {path} is not a file")
        if ":" in str(path):
            raise UsageError(f"{option} {path}: a path with ':' cannot be given to a tracker")
        out[option] = Path(path).expanduser().resolve()
    return out


def _network_of(spec: str, extra: dict[str, Any]) -> tuple[str, str, dict[str, str]] | None:
    """What the tracker of ``spec`` (with the overrides ``extra``) runs: (its name, the model
    set, {option: its keyword}), or None for a tracker without model files."""
    from ..engine.params import Params
    from ..integrations.opencv_peers import NANO_MODELS
    from ..integrations.opencv_wheels import parse_opencv_name
    from ..trackers import NANOTRACK_PREFIX, is_opencv_spec, parse_spec

    name, overrides = parse_spec(spec)
    overrides = {**overrides, **extra}
    if is_opencv_spec(name):
        kind = f"opencv:{parse_opencv_name(name)}"
        return (kind, NANO_MODELS, _KEYWORDS[kind]) if kind in _KEYWORDS else None
    if name.lower().startswith(NANOTRACK_PREFIX):
        version = name[len(NANOTRACK_PREFIX):].lower() or "v3"
        return name, f"nanotrack-{version}", _KEYWORDS["nanotrack"]
    if name.lower() in preset_names():
        network = Params.for_variant(name, **overrides).network
        return (name, network, _KEYWORDS["nanotrack"]) if network else None
    return None


def model_keywords(spec: str, given: dict[str, Path], extra: dict[str, Any] | None = None, *,
                   alone: bool = True) -> dict[str, str]:
    """The keywords that give the tracker of ``spec`` the files ``given`` by option: each file
    whose content is the model set and role the tracker runs (or a file wmiltrack does not
    know), unless the tracker is given its own (in ``spec`` or ``extra``). A file of another
    set is left out; ``alone`` (one tracker in the run) makes that a :class:`UsageError`
    naming the fix."""
    from ..networks.files import identify

    extra = extra or {}
    found = _network_of(spec, extra)
    if found is None:
        return {}
    name, model_set, keywords = found
    own = set(extra) | set(_spec_keys(spec))
    out: dict[str, str] = {}
    for option, path in given.items():
        keyword = keywords.get(option)
        if keyword is None or keyword in own:
            continue
        known = identify(path)
        if known is None or known == (model_set, _ROLES[option]):
            out[keyword] = str(path)
        elif alone:
            raise UsageError(_wrong_file(option, path, known, name, model_set))
    return out


def _spec_keys(spec: str) -> list[str]:
    from ..trackers import parse_spec

    return list(parse_spec(spec)[1])


def _wrong_file(option: str, path: Path, known: tuple[str, str], name: str, model_set: str) -> str:
    """The message for a file of another set or role given to the tracker ``name``."""
    from ..networks.files import MODELS

    theirs, mine = MODELS[known[0]], MODELS[model_set]
    role = _ROLES[option]
    what = f"{option} {path} is {theirs.title}'s {known[1]}"
    if known[0] == model_set:
        other = next(o for o, r in _ROLES.items() if r == known[1])
        return f"{what}, not its {role}: give it with {other}"
    fix = ""
    if name.lower().startswith("nanotrack:"):
        fix = f"to run {theirs.title} use -t nanotrack:{theirs.version}, or "
    elif not name.startswith("opencv:"):
        fix = f"to run {name} on {theirs.title} add --set network={theirs.name}, or "
    return (f"{what}, but {name} runs {mine.title}: {fix}give {mine.title}'s {role} "
            f"({mine.files[role].name})")


def specs_with_model_files(specs: list[str], args: argparse.Namespace) -> list[str]:
    """``specs`` (eval's ``--trackers``), each given the files of ``--nano-backbone``,
    ``--nano-head`` and ``--vit-model`` that are its network's (:func:`model_keywords`: a
    file of NanoTrack v2 goes to the trackers of v2 only). A file that no tracker takes is a
    :class:`UsageError`."""
    from ..networks.files import MODELS, identify

    given = given_model_files(args)
    out, taken = [], set()
    for spec in specs:
        keywords = model_keywords(spec, given, alone=len(specs) == 1)
        taken |= {o for o, p in given.items() if str(p) in keywords.values()}
        out.append(spec + "".join(f":{k}={v}" for k, v in keywords.items()))
    for option in given.keys() - taken:
        known = identify(given[option])
        what = (f"{MODELS[known[0]].title}'s {known[1]}, and no tracker of --trackers runs "
                f"{MODELS[known[0]].title}" if known else "for no tracker of --trackers")
        raise UsageError(f"{option} {given[option]} is {what}; give each tracker its own files "
                         "as TRACKER:backbone=FILE:head=FILE (opencv:Nano: backbone, neckhead)")
    return out


def tracker_overrides(args: argparse.Namespace) -> dict[str, Any]:
    """The parameters ``--set`` gives the tracker of ``-t``, with the model files given by
    option that are its (:func:`model_keywords`)."""
    overrides = parse_overrides(args.set)
    given = given_model_files(args)
    try:
        keywords = model_keywords(args.tracker, given, overrides)
    except UsageError:
        raise
    except (ValueError, TypeError):  # a bad -t or --set: said when the tracker is made
        return overrides
    return {**overrides, **keywords}


def add_tracker_options(p: argparse.ArgumentParser, *, opencv: bool = True) -> None:
    """``-t/--tracker``, ``--seed`` and ``--set NAME=VALUE``, shared by the commands that run one
    tracker; ``opencv``: whether OpenCV's trackers may be asked for."""
    p.add_argument("-t", "--tracker", default="rcwmil", help=trackers_help(opencv=opencv))
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="override a parameter, e.g. --set num_selected=30 (repeatable)")


def tracker_from_args(args: argparse.Namespace, *, several: bool = False, ours: bool = False) -> Any:
    """The tracker that ``-t``, ``--seed`` and ``--set`` ask for.

    ``several``: a :class:`wmiltrack.MultiTracker` (wmiltrack's presets only); ``ours``: a
    :class:`wmiltrack.Tracker` (not an OpenCV tracker). An unknown tracker or parameter, or a
    bad value, is a :class:`UsageError`; an OpenCV tracker missing from the installed ``cv2``
    stays a :class:`wmiltrack.integrations.opencv_wheels.TrackerUnavailable` (exit status 1).
    """
    from ..trackers import make_tracker

    overrides = tracker_overrides(args)
    if (several or ours) and args.tracker.lower().startswith("opencv:"):
        what = "--boxes tracks several targets" if several else "this command runs"
        raise UsageError(f"{what} with wmiltrack's presets only; {args.tracker} is an OpenCV tracker")
    try:
        if several:
            from ..engine.multi import MultiTracker

            return MultiTracker(args.tracker, seed=args.seed, **overrides)
        return make_tracker(args.tracker, seed=args.seed, **overrides)
    except (ValueError, TypeError) as exc:
        raise UsageError(str(exc)) from None


def open_frames(path: Any, *, has_box: bool) -> Any:
    """:func:`wmiltrack.data.sequences.open_input`, where a ground-truth file that cannot be read
    does not stop a run that has its first box (``--box``/``--boxes``): the frames are then
    opened without it, and a warning says why."""
    from ..data.sequences import open_input

    try:
        return open_input(path)
    except ValueError as exc:
        if not has_box:
            raise
        seq = open_input(path, groundtruth=False)
        print(f"wmiltrack: warning: ground truth not used: {exc}", file=sys.stderr)
        return seq


def add_executor_options(p: argparse.ArgumentParser, inputs: str) -> None:
    """``-j/--jobs``, ``--executor`` and ``--scheduler`` (:func:`wmiltrack.parallel.executors.make_executor`),
    shared by ``eval`` and ``track --list``; ``inputs`` names what the workers must see."""
    from ..parallel.executors import EXECUTORS

    p.add_argument("-j", "--jobs", type=int, default=1,
                   help="parallel processes or Dask workers (default 1)")
    p.add_argument("--executor", choices=EXECUTORS, default=None,
                   help="where tasks run: serial (this process), process (-j worker processes) or "
                   "dask (a LocalCluster of -j workers, or the cluster at --scheduler; needs "
                   "pip install \"wmiltrack[cluster]\"); default serial for -j 1, else process")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="with --executor dask: an existing Dask scheduler (tcp://host:8786) whose "
                   f"workers see {inputs} at the same path")
