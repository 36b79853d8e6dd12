"""Track one object through a video and write a copy with the box drawn on every frame.

    python examples/track_video.py                          # a generated clip, no download
    python examples/track_video.py clip.mp4 --box 120,80,40,60 -o tracked.mp4

Without a video the script writes a generated 150-frame clip (a textured target moving over
clutter, with an occlusion and an illumination change; wmiltrack.data.synthetic) to an MP4
first, then tracks it as it would any file, and prints the mean overlap with the known
ground truth.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import cv2
import numpy as np

import wmiltrack
from wmiltrack.data.synthetic import make_preset
from wmiltrack.eval.metrics import iou


def write_generated_clip(path: Path) -> tuple[tuple[float, float, float, float], np.ndarray]:
    """Write the generated clip to ``path``; return its first box and its ground truth."""
    seq = make_preset("all", seed=0, n_frames=150)
    frames = seq.load()
    h, w = frames[0].shape[:2]
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter.fourcc(*"mp4v"), 30.0, (w, h))
    if not writer.isOpened():
        raise SystemExit(f"OpenCV cannot write {path}")
    for frame in frames:
        writer.write(frame)
    writer.release()
    assert seq.groundtruth is not None
    x, y, bw, bh = (float(v) for v in seq.groundtruth[0])
    return (x, y, bw, bh), seq.groundtruth


def track(video: Path, box: tuple[float, float, float, float], out: Path,
          tracker: str) -> list[tuple[float, float, float, float]]:
    """Track ``box`` through ``video``, write the drawn frames to ``out``, return the boxes."""
    cap = cv2.VideoCapture(str(video))
    ok, frame = cap.read()
    if not ok:
        raise SystemExit(f"cannot read a frame from {video}")
    fps = cap.get(cv2.CAP_PROP_FPS) or 30.0
    h, w = frame.shape[:2]

    t = wmiltrack.Tracker(tracker, seed=0)  # a preset that cannot start (no model files) stops here
    t.init(frame, box)
    # the output is opened once the tracker has started: a run that cannot start leaves it as it was
    writer = cv2.VideoWriter(str(out), cv2.VideoWriter.fourcc(*"mp4v"), fps, (w, h))
    boxes = [t.box]
    while True:
        writer.write(draw(frame, boxes[-1], len(boxes)))
        ok, frame = cap.read()
        if not ok:
            break
        result = t.update(frame)         # result.box, result.score, result.ok
        boxes.append(result.box)
    cap.release()
    writer.release()
    return boxes


def draw(frame: np.ndarray, box: tuple[float, float, float, float], number: int) -> np.ndarray:
    """A copy of ``frame`` with ``box`` in green and the frame number (from 1) in the corner."""
    out = frame.copy()
    x, y, w, h = (round(v) for v in box)
    cv2.rectangle(out, (x, y), (x + w - 1, y + h - 1), (0, 255, 0), 2)
    cv2.putText(out, f"#{number}", (6, 18), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (255, 255, 255), 1)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("video", nargs="?", type=Path, help="video file (default: a generated clip)")
    parser.add_argument("--box", help="x,y,w,h of the target on the first frame (needed with VIDEO)")
    parser.add_argument("-o", "--out", type=Path, default=Path("tracked.mp4"), help="output video")
    parser.add_argument("-t", "--tracker", default="rcwmil-plus", help="preset (default rcwmil-plus)")
    args = parser.parse_args()

    with tempfile.TemporaryDirectory() as tmp:
        gt = None
        if args.video is None:
            args.video = Path(tmp) / "generated.mp4"
            box, gt = write_generated_clip(args.video)
        elif args.box is None:
            parser.error("--box x,y,w,h is needed with a video")
        else:
            x, y, w, h = (float(v) for v in args.box.split(","))
            box = (x, y, w, h)
        try:
            boxes = track(args.video, box, args.out, args.tracker)
        except (ValueError, TypeError, FileNotFoundError) as exc:  # a bad preset, box or model file
            raise SystemExit(f"track_video.py: {exc}") from None

    print(f"{len(boxes)} frames tracked with {args.tracker}; drawn boxes in {args.out}")
    if gt is not None:
        overlap = iou(np.array(boxes), gt[: len(boxes)])
        print(f"mean overlap with the ground truth: {overlap.mean():.2f}")


if __name__ == "__main__":
    main()
