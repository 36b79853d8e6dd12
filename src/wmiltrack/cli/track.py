"""``wmiltrack track``: one object through a video, an image folder or an OTB sequence."""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from .options import Subparsers, add_tracker_options, parse_box, parse_overrides


def _cmd_track(args: argparse.Namespace) -> int:
    from ..data.boxes import write_boxes
    from ..data.sequences import open_input
    from ..eval.peers import make_tracker
    from ..progress import progress

    seq = open_input(args.input)
    if args.box is not None:
        box = args.box
    elif seq.groundtruth is not None:
        box = seq.init_box
    else:
        raise SystemExit(
            f"wmiltrack: {args.input} has no ground truth; give the first box with --box x,y,w,h"
        )
    tracker = make_tracker(args.tracker, seed=args.seed, **parse_overrides(args.set))
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

    from ..visualize import draw_result

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
    p.add_argument("--box", type=parse_box, help="first box as x,y,w,h (pixels)")
    p.add_argument("-o", "--output", type=Path, help="write boxes here (default: print them)")
    p.add_argument("--video", type=Path, help="write a video with the box, frame number and score drawn")
    add_tracker_options(p)
    p.set_defaults(func=_cmd_track)
