"""``wmiltrack inspect``: draw what one tracker step looks at (bags and search grids)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from .options import add_tracker_options, parse_box, parse_overrides


def _cmd_inspect(args: argparse.Namespace) -> int:
    import cv2

    from ..data.sequences import open_input
    from ..engine.tracker import Tracker
    from ..visualize import draw_samples

    seq = open_input(args.input)
    if args.box is not None:
        box: Any = args.box
    elif seq.groundtruth is not None:
        box = seq.init_box
    else:
        raise SystemExit(f"wmiltrack: {args.input} has no ground truth; give the first box with --box")
    if args.frame < 1:
        raise SystemExit("wmiltrack: --frame must be >= 1 (the frame after the first)")
    t = Tracker(args.tracker, seed=args.seed, **parse_overrides(args.set))
    frame = None
    for i, frame in enumerate(seq):
        if i == 0:
            t.init(frame, box)
        else:
            t.update(frame)
        if i == args.frame:
            break
    else:
        raise SystemExit(f"wmiltrack: {args.input} has fewer than {args.frame + 1} frames")
    img = draw_samples(frame, t.samples(), scale=args.scale)
    if not cv2.imwrite(str(args.output), img, [cv2.IMWRITE_PNG_COMPRESSION, 9]):
        raise SystemExit(f"wmiltrack: cannot write {args.output}")
    s = t.samples()
    scales = f", {len(s['scales'])} other scales" if s["scales"] else ""
    print(f"frame {args.frame}: {len(s['positive'])} positives, {len(s['negative'])} negatives, "
          f"search stages {[(r, st) for _, r, st in s['search']]}{scales} -> {args.output}")
    return 0


def add_inspect(sub: Any) -> None:
    """Register ``wmiltrack inspect`` on the CLI's subparsers.

    Parameters
    ----------
    sub : argparse subparsers action
        What ``ArgumentParser.add_subparsers`` returned.
    """
    p = sub.add_parser(
        "inspect", help="draw the positive/negative bags and the search grid of one frame as a PNG",
        description="Track INPUT up to --frame and draw, on a crop around the target, the positive "
        "bag (green), the negative bag (red), the coarse search grid around the previous box (blue) "
        "and the fine grid around the coarse winner (yellow) of that frame's update, and the boxes of "
        "the other scales searched (magenta; rcwmil-plus).")
    p.add_argument("input", type=Path, help="video file, image folder or OTB sequence folder")
    p.add_argument("-o", "--output", type=Path, default=Path("samples.png"), help="PNG to write")
    p.add_argument("--frame", type=int, default=1, help="frame index to draw (default 1)")
    p.add_argument("--box", type=parse_box, help="first box as x,y,w,h (default: ground truth)")
    p.add_argument("--scale", type=int, default=3, help="enlargement of the crop (default 3)")
    add_tracker_options(p)
    p.set_defaults(func=_cmd_inspect)
