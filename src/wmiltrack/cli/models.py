"""``wmiltrack models``: the networks' model files: which there are and where (``list``), fetching
and checking them (``fetch``), and the paths a tracker would use (``path``)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .options import EXIT_CODES_EPILOG, EXIT_ERROR, EXIT_OK, EXIT_USAGE, Subparsers, UsageError


def _cmd_list(args: argparse.Namespace) -> int:
    from ..networks.files import MODELS, locate, models_dir, models_dir_origin

    print(f"models folder: {models_dir()} ({models_dir_origin()})")
    for s in MODELS.values():
        print(f"\n{s.name}  {s.title}: {s.repository} at {s.commit[:12]} ({s.license})")
        for found in locate(s.name):
            f = s.files[found.role]
            print(f"  {found.role:<9} {f.name:<28} sha1 {f.sha1}")
            if found.problem is None:
                print(f"  {'':<9} present: {found.path} ({found.origin})")
            else:
                state = "not usable" if found.path.exists() else "missing"
                print(f"  {'':<9} {state}: {found.problem}")
    return EXIT_OK


def _cmd_fetch(args: argparse.Namespace) -> int:
    from ..networks.files import fetch, models_dir

    if args.source is not None and not args.source.is_dir():
        raise UsageError(f"--from {args.source} is not a folder")
    if args.dest is not None and args.dest.exists() and not args.dest.is_dir():
        raise UsageError(f"--dest {args.dest} is not a folder")
    try:
        paths = fetch(args.name, source=args.source, dest=args.dest, quiet=args.quiet)
    except OSError as exc:  # a target with other bytes, an unreadable source, a full disk
        print(f"wmiltrack: error: {exc}", file=sys.stderr)
        return EXIT_ERROR
    for path in paths:
        print(path)
    if args.dest is not None and args.dest.expanduser().absolute() != models_dir() and not args.quiet:
        print(f"wmiltrack looks for model files in {models_dir()}: set WMILTRACK_MODELS="
              f"{args.dest.expanduser().absolute()} to use these, or give their paths",
              file=sys.stderr)
    return EXIT_OK


def _cmd_path(args: argparse.Namespace) -> int:
    from ..networks.files import find_files

    for path in find_files(args.name):
        print(path)
    return EXIT_OK


def _cmd_models_help(args: argparse.Namespace) -> int:
    args.models_parser.print_help(sys.stderr)
    return EXIT_USAGE


def add_models(sub: Subparsers) -> None:
    """Add the ``models`` subcommand (``list``, ``fetch``, ``path``) to ``sub``."""
    from ..networks.files import DEFAULT_BASE_URL, MODELS, MODELS_ENV, MODELS_URL_ENV

    names = list(MODELS)
    p = sub.add_parser(
        "models", help="list, fetch and find the networks' model files (NanoTrack)",
        description="The model files of the networks wmiltrack runs (NanoTrack v2 and v3: a "
        "backbone and a head, ONNX), which no wheel ships. A tracker takes them from the paths it "
        "is given, else from WMILTRACK_NANO_BACKBONE and WMILTRACK_NANO_HEAD, else from the "
        f"models folder: {MODELS_ENV}, else wmiltrack/models in the user's cache folder "
        "($XDG_CACHE_HOME or ~/.cache).",
        epilog=EXIT_CODES_EPILOG)
    p.set_defaults(func=_cmd_models_help, models_parser=p)
    actions = p.add_subparsers(dest="action", metavar="ACTION",
                               help="list, fetch or path (each has its own --help)")

    q = actions.add_parser(
        "list", help="the model sets, their files, where they are looked for and whether present",
        description="For each model set: its files, their SHA-1, where a tracker would take each "
        "from and whether it is there and right.", epilog=EXIT_CODES_EPILOG)
    q.set_defaults(func=_cmd_list)

    q = actions.add_parser(
        "fetch", help="download a set's files (or copy them from a folder) and check their SHA-1",
        description="Download a set's files from its public repository at the pinned commit "
        f"({DEFAULT_BASE_URL}, or the mirror in {MODELS_URL_ENV}) or copy them from a local "
        "folder (--from), check each file's SHA-1 and size, and only then give it its name in "
        "DEST/SET (DEST: the models folder). A file already there with the right bytes is kept; "
        "one with other bytes is never overwritten. Prints the files' paths.",
        epilog=EXIT_CODES_EPILOG)
    q.add_argument("name", choices=names, metavar="SET", help=f"the set: {', '.join(names)}")
    q.add_argument("--from", dest="source", type=Path, default=None, metavar="DIR",
                   help="copy from this folder instead of downloading: the files in it directly, "
                   "in a v3/ (version), nanotrack-v3/ (set) or nanotrackv3/ subfolder, or a "
                   "checkout of the repository")
    q.add_argument("--dest", type=Path, default=None, metavar="DIR",
                   help="the models folder to fetch into (files go to DIR/SET; default: "
                   f"{MODELS_ENV}, else the user's cache folder)")
    q.add_argument("-q", "--quiet", action="store_true",
                   help="no progress bar and no report on standard error")
    q.set_defaults(func=_cmd_fetch)

    q = actions.add_parser(
        "path", help="print the backbone's and the head's paths a tracker would use",
        description="Print the paths a tracker would take the set's backbone and head from (one "
        "a line, backbone first), or the error that says which file is missing and how to get it.",
        epilog=EXIT_CODES_EPILOG)
    q.add_argument("name", choices=names, metavar="SET", help=f"the set: {', '.join(names)}")
    q.set_defaults(func=_cmd_path)
