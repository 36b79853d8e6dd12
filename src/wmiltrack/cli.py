"""The ``wmiltrack`` command line: ``track``, ``demo`` and the subcommands registered below.

Each subcommand lives in a function ``add_<name>(subparsers)`` that defines its arguments
and sets ``func``; :data:`SUBCOMMANDS` lists them, so a new command is one module and one
line here.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Callable, Sequence
from importlib import import_module
from pathlib import Path
from typing import Any

Subparsers = Any  # argparse's _SubParsersAction is private


def _parse_box(text: str) -> tuple[float, float, float, float]:
    parts = text.replace(";", ",").replace(" ", ",").split(",")
    parts = [p for p in parts if p]
    try:
        values = tuple(float(p) for p in parts)
    except ValueError:
        raise argparse.ArgumentTypeError(f"--box needs four numbers x,y,w,h; got {text!r}") from None
    if len(values) != 4:
        raise argparse.ArgumentTypeError(f"--box needs four numbers x,y,w,h; got {text!r}")
    return values[0], values[1], values[2], values[3]


def _parse_overrides(items: Sequence[str]) -> dict[str, Any]:
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


def _add_tracker_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("-t", "--tracker", default="rcwmil",
                   help="variant: rcwmil (default), ct, fct, mil, wmil, osil, or opencv:NAME")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="override a parameter, e.g. --set num_selected=30 (repeatable)")


# -- track ---------------------------------------------------------------------------------
def _cmd_track(args: argparse.Namespace) -> int:
    from .datasets import open_input, write_boxes
    from .peers import make_tracker
    from .progress import progress

    seq = open_input(args.input)
    if args.box is not None:
        box = args.box
    elif seq.groundtruth is not None:
        box = seq.init_box
    else:
        raise SystemExit(
            f"wmiltrack: {args.input} has no ground truth; give the first box with --box x,y,w,h"
        )
    tracker = make_tracker(args.tracker, seed=args.seed, **_parse_overrides(args.set))
    writer = None
    boxes: list[tuple[float, float, float, float]] = []
    scores: list[float] = []
    times: list[float] = []
    try:
        for i, frame in enumerate(progress(seq, total=len(seq), desc=f"{args.tracker} {seq.name}")):
            if i == 0:
                tracker.init(frame, box)
                r_box, score = tuple(float(v) for v in box), float("nan")
            else:
                t0 = time.perf_counter()
                r = tracker.update(frame)
                times.append(time.perf_counter() - t0)
                r_box, score = r.box, r.score
            boxes.append(r_box)  # type: ignore[arg-type]
            scores.append(score)
            if args.video is not None:
                writer = _write_video_frame(writer, args.video, frame, r_box, i, score, seq.fps)
    finally:
        if writer is not None:
            writer.release()
    if args.output is not None:
        write_boxes(args.output, boxes)
    else:
        for b in boxes:
            print(",".join(f"{v:g}" for v in b))
    if times:
        fps = len(times) / sum(times)
        print(f"{len(boxes)} frames, {fps:.0f} frames/s (update only)", file=sys.stderr)
    return 0


def _write_video_frame(writer: Any, path: Path, frame: Any, box: Sequence[float], index: int,
                       score: float, fps: float | None) -> Any:
    import cv2
    import numpy as np

    from .visualize import draw_result

    if writer is None:
        h, w = frame.shape[:2]
        fourcc = cv2.VideoWriter.fourcc(*("mp4v" if str(path).lower().endswith(".mp4") else "MJPG"))
        writer = cv2.VideoWriter(str(path), fourcc, float(fps or 25.0), (w, h))
        if not writer.isOpened():
            raise SystemExit(f"wmiltrack: cannot write video {path}")
    img = (frame if frame.ndim == 3 and frame.shape[2] == 3
           else cv2.cvtColor(np.ascontiguousarray(frame), cv2.COLOR_GRAY2BGR))
    writer.write(draw_result(img, box, index=index, score=score))
    return writer


def add_track(sub: Subparsers) -> None:
    """Add the ``track`` subcommand to ``sub``."""
    p = sub.add_parser("track", help="track an object through a video, image folder or OTB sequence",
                       description="Track one object. INPUT is a video file, a folder of images, or an "
                       "OTB sequence folder (img/ + groundtruth_rect.txt: the first box comes from its "
                       "ground truth unless --box is given). Prints or writes one x,y,w,h line per frame.")
    p.add_argument("input", type=Path, help="video file, image folder or OTB sequence folder")
    p.add_argument("--box", type=_parse_box, help="first box as x,y,w,h (pixels)")
    p.add_argument("-o", "--output", type=Path, help="write boxes here (default: print them)")
    p.add_argument("--video", type=Path, help="write a video with the box, frame number and score drawn")
    _add_tracker_options(p)
    p.set_defaults(func=_cmd_track)


# -- demo ----------------------------------------------------------------------------------
def _cmd_demo(args: argparse.Namespace) -> int:
    from .evaluation import run_sequence
    from .metrics import ope_metrics
    from .synthetic import make_preset

    seq = make_preset("all", seed=args.seed, n_frames=args.frames)
    frames = seq.load()
    gt = seq.groundtruth
    assert gt is not None
    print(f"built-in sequence: {len(frames)} frames of {frames[0].shape[1]}x{frames[0].shape[0]}, "
          "moving textured target with partial occlusion, illumination change and clutter")
    print(f"{'tracker':<10} {'AUC':>6} {'SR@0.5':>7} {'P@20':>6} {'fps':>8}")
    for name in args.trackers.split(","):
        run = run_sequence(name.strip(), frames, gt[0], seed=args.seed)
        if run.error:
            print(f"{name:<10} failed: {run.error}")
            continue
        m = ope_metrics(run.boxes, gt)
        print(f"{name:<10} {m.auc:6.3f} {m.success_50:7.3f} {m.precision_20:6.3f} {run.fps:8.0f}")
    return 0


def add_demo(sub: Subparsers) -> None:
    """Add the ``demo`` subcommand to ``sub``."""
    p = sub.add_parser("demo", help="run the tracker on a built-in generated sequence",
                       description="Track the target of a generated sequence (moving textured target, "
                       "partial occlusion, illumination change, cluttered background) and print the "
                       "success AUC, success rate, precision and update-only frames per second.")
    p.add_argument("--trackers", default="rcwmil",
                   help="comma-separated trackers (default rcwmil), e.g. rcwmil,ct,opencv:MIL")
    p.add_argument("--frames", type=int, default=300, help="sequence length (default 300)")
    p.add_argument("--seed", type=int, default=0, help="seed of the sequence and trackers")
    p.set_defaults(func=_cmd_demo)


# -- variants ------------------------------------------------------------------------------
#: Parameters shown in the variants table, with their column titles.
VARIANT_COLUMNS = [
    ("features", "features"), ("M", "num_features"), ("K", "num_selected"), ("rects", "rects"),
    ("rect weights", "weights"), ("lambda", "learning_rate"), ("positives", "pos_radius"),
    ("negatives", "negatives"), ("selection", "selection"), ("instance weights", "instance_weights"),
    ("search", "search"),
]


def variant_table() -> str:
    """The defaults of every variant as a markdown table (the README's table)."""
    from .params import VARIANTS

    def cell(p: Any, key: str) -> str:
        if key == "features":
            return "sub-region (2x2)" if p.feature_kind == "subregion" else "random rects"
        if key == "rects":
            return f"{p.rects_min}-{p.rects_max}"
        if key == "weights":
            if p.feature_kind == "subregion":
                w = f"+1/-1 at {p.positive_prob:.2f}/{1 - p.positive_prob:.2f}"
            else:
                w = {"sign": "+-1", "sign_sqrt": "+-1/sqrt(n)", "uniform": "U[-1,1]"}[p.weight_mode]
            return w + (" / area" if p.area_normalize else ", raw sums")
        if key == "pos_radius":
            return f"d < {p.pos_radius:g}"
        if key == "negatives":
            how = "exactly" if p.neg_sampling == "exact" else "Bernoulli, max"
            return f"{p.neg_inner:g} <= d < {p.neg_outer:g}, {how} {p.neg_count}"
        if key == "selection":
            return {"wmil": "WMIL gradient", "milboost": "MILBoost (Noisy-OR)",
                    "none": "all features"}[p.selection]
        if key == "instance_weights":
            return "-" if p.selection != "wmil" else {"exp": "exp(-d)/sum", "exp_sq": "exp(-d^2)",
                                                      "uniform": "equal"}[p.instance_weights]
        if key == "search":
            s = f"{p.coarse_radius}/{p.coarse_step}"
            return s + (f" then {p.fine_radius}/{p.fine_step}" if p.fine_radius > 0 else "")
        return f"{getattr(p, key):g}" if isinstance(getattr(p, key), float) else str(getattr(p, key))

    head = "| variant | " + " | ".join(title for title, _ in VARIANT_COLUMNS) + " |"
    rule = "|" + "---|" * (len(VARIANT_COLUMNS) + 1)
    rows = [f"| **{name}** | " + " | ".join(cell(p, key) for _, key in VARIANT_COLUMNS) + " |"
            for name, p in VARIANTS.items()]
    return "\n".join([head, rule, *rows])


def _cmd_variants(args: argparse.Namespace) -> int:
    from .params import VARIANTS

    if args.name:
        p = VARIANTS.get(args.name.lower())
        if p is None:
            raise ValueError(f"unknown variant {args.name!r}; choose one of {', '.join(VARIANTS)}")
        print(p.description)
        for key, value in p.as_dict().items():
            if key != "description":
                print(f"  {key} = {value!r}")
        return 0
    print(variant_table())
    return 0


def add_variants(sub: Subparsers) -> None:
    """Add the ``variants`` subcommand to ``sub``."""
    p = sub.add_parser("variants", help="list the tracker variants and their default parameters",
                       description="Print the variants' defaults as a markdown table, or every "
                       "parameter of one variant.")
    p.add_argument("name", nargs="?", help="show every parameter of this variant")
    p.set_defaults(func=_cmd_variants)


# -- registry ------------------------------------------------------------------------------
#: (module, function) pairs; a module's function adds its subcommand.
SUBCOMMANDS: list[tuple[str | None, str]] = [
    (None, "add_track"),
    (None, "add_demo"),
    (None, "add_variants"),
    (".eval_cli", "add_eval"),
    (".inspect_cli", "add_inspect"),
]


def build_parser() -> argparse.ArgumentParser:
    """The ``wmiltrack`` argument parser with every registered subcommand."""
    from . import __version__

    parser = argparse.ArgumentParser(
        prog="wmiltrack",
        description="Fast single-object visual tracking (RCWMIL and its family) and tracker benchmarks.",
    )
    parser.add_argument("--version", action="version", version=f"wmiltrack {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for module, func in SUBCOMMANDS:
        adder: Callable[[Subparsers], None]
        if module is None:
            adder = globals()[func]
        else:
            adder = getattr(import_module(module, __package__), func)
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
