"""``wmiltrack inspect``: draw what one tracker step looks at (bags and search grids)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from .options import (
    EXIT_CODES_EPILOG,
    UsageError,
    add_model_options,
    add_tracker_options,
    open_frames,
    parse_box,
    tracker_from_args,
)
from .outputs import check_outputs


def _cmd_inspect(args: argparse.Namespace) -> int:
    import cv2

    from ..visualize import draw_samples

    if args.frame < 2:
        raise UsageError("--frame must be >= 2 (frames count from 1; the first one has no update)")
    check_outputs([("-o", args.output)], [args.input])
    if not cv2.haveImageWriter(str(args.output)):
        raise UsageError(f"-o {args.output}: OpenCV cannot write a {args.output.suffix or 'extension-less'} "
                         "image; name it .png (or .jpg)")
    t = tracker_from_args(args, ours=True)
    seq = open_frames(args.input, has_box=args.box is not None)
    if args.box is not None:
        box: Any = args.box
    elif seq.groundtruth is not None:
        box = seq.init_box
    else:
        raise UsageError(f"{args.input} has no ground truth; give the first box with --box")
    frame = None
    for i, frame in enumerate(seq):
        if i == 0:
            t.init(frame, box)
        else:
            t.update(frame)
        if i + 1 == args.frame:
            break
    else:
        raise ValueError(f"{args.input} has fewer than {args.frame} frames")
    img = draw_samples(frame, t.samples(), scale=args.scale)
    if not cv2.imwrite(str(args.output), img, [cv2.IMWRITE_PNG_COMPRESSION, 9]):
        raise RuntimeError(f"cannot write {args.output}")
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
        "the other scales searched (magenta; the presets with a scale search).",
        epilog=EXIT_CODES_EPILOG)
    p.add_argument("input", type=Path, help="video file, image folder or OTB sequence folder")
    p.add_argument("-o", "--output", type=Path, default=Path("samples.png"), help="PNG to write")
    p.add_argument("--frame", type=int, default=2,
                   help="frame to draw, counted from 1 (default 2: the first update)")
    p.add_argument("--box", type=parse_box, help="first box as x,y,w,h (default: ground truth)")
    p.add_argument("--scale", type=int, default=3, help="enlargement of the crop (default 3)")
    add_tracker_options(p, opencv=False)
    add_model_options(p)
    p.set_defaults(func=_cmd_inspect)
