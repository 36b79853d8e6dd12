"""Many targets in one video: MultiTracker against a loop of single trackers and OpenCV's.

    python benchmarks/multi.py [--frames 40] [--targets 1,4,16,64] [--sizes 640x480,1280x720]
                               [--variant rcwmil] [--opencv MIL] [--opencv-max-targets 16]

For each frame size a generated sequence is decoded into memory and ``N`` boxes (40x40) are laid
on a regular grid over the frame (targets on the textured background and on the moving target;
what matters here is the cost, which does not depend on what a box holds). Every tracker starts
on frame 0 and is timed over the remaining frames, updates only; the table gives frames per
second (all N targets updated per frame, median of ``--repeats`` runs) for

* ``MultiTracker`` (``threads=None``: one worker per core),
* the same preset as N single ``wmiltrack.Tracker`` objects updated one after the other,
* N OpenCV trackers (``cv2.TrackerMIL`` by default) updated one after the other, with
  ``cv2.setNumThreads(1)`` (skipped above ``--opencv-max-targets``: at ~50 fps per target it
  would take minutes).

The MultiTracker's boxes are checked against the single trackers' (they must be identical).
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
from collections.abc import Callable, Sequence

import cv2
import numpy as np

import wmiltrack
from wmiltrack.data.synthetic import make_sequence
from wmiltrack.timing import gc_paused, timed

Box = tuple[float, float, float, float]


def grid_boxes(n: int, width: int, height: int, side: int = 40) -> list[Box]:
    """``n`` side x side boxes spread on a regular grid, away from the frame's edges."""
    cols = int(np.ceil(np.sqrt(n * width / height)))
    rows = int(np.ceil(n / cols))
    xs = np.linspace(side, width - 2 * side, cols)
    ys = np.linspace(side, height - 2 * side, rows)
    boxes = [(float(x), float(y), float(side), float(side)) for y in ys for x in xs]
    return boxes[:n]


def run_multi(variant: str, frames: Sequence[np.ndarray], boxes: Sequence[Box],
              threads: int | None) -> tuple[float, list[list[Box]]]:
    mt = wmiltrack.MultiTracker(variant, seed=0, threads=threads)
    for b in boxes:
        mt.add(frames[0], b)

    def loop() -> list[list[Box]]:
        out: list[list[Box]] = []
        for f in frames[1:]:
            res = mt.update(f)
            out.append([res[i].box for i in range(len(boxes))])
        return out

    with gc_paused():
        out, dt = timed(loop)
    mt.close()
    return dt, out


def run_singles(variant: str, frames: Sequence[np.ndarray],
                boxes: Sequence[Box]) -> tuple[float, list[list[Box]]]:
    trackers = []
    for i, b in enumerate(boxes):
        t = wmiltrack.Tracker(variant, seed=i)
        t.init(frames[0], b)
        trackers.append(t)
    with gc_paused():
        out, dt = timed(lambda: [[t.update(f).box for t in trackers] for f in frames[1:]])
    return dt, out


def run_opencv(name: str, frames: Sequence[np.ndarray], boxes: Sequence[Box]) -> float:
    factory: Callable[[], object] = getattr(cv2, f"Tracker{name}_create")
    trackers = []
    for b in boxes:
        t = factory()
        t.init(frames[0], tuple(int(round(v)) for v in b))  # type: ignore[attr-defined]
        trackers.append(t)

    def loop() -> None:
        for f in frames[1:]:
            for t in trackers:
                t.update(f)  # type: ignore[attr-defined]

    with gc_paused():
        _, dt = timed(loop)
    return dt


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=40, help="frames per run (default 40)")
    ap.add_argument("--targets", default="1,4,16,64")
    ap.add_argument("--sizes", default="640x480,1280x720", help="frame WxH list")
    ap.add_argument("--variant", default="rcwmil")
    ap.add_argument("--opencv", default="MIL", help="OpenCV tracker for the loop ('' = none)")
    ap.add_argument("--opencv-max-targets", type=int, default=16)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args(argv)
    cv2.setNumThreads(1)
    counts = [int(v) for v in args.targets.split(",")]
    print(f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, Python "
          f"{platform.python_version()}, OpenCV {cv2.__version__}, wmiltrack {wmiltrack.__version__}")
    print(f"{args.variant}: {args.frames} frames, update-only frames/s (all targets per frame), "
          f"median of {args.repeats}; OpenCV {args.opencv} with cv2.setNumThreads(1)")
    head = (f"| frame | targets | MultiTracker fps | {args.variant} loop fps | speed-up | "
            f"opencv:{args.opencv} loop fps |")
    print(head)
    print("|---|---|---|---|---|---|")
    for size in args.sizes.split(","):
        w, h = (int(v) for v in size.split("x"))
        seq = make_sequence(args.frames, size=(h, w), target_size=(40, 40), seed=0)
        frames = seq.load()
        for n in counts:
            boxes = grid_boxes(n, w, h)
            multi_t, loop_t, cv_t = [], [], []
            for _ in range(args.repeats):
                dt, got = run_multi(args.variant, frames, boxes, None)
                multi_t.append(dt)
                dt, want = run_singles(args.variant, frames, boxes)
                loop_t.append(dt)
                if got != want:
                    raise SystemExit(f"MultiTracker boxes differ from single trackers ({n} targets)")
                if args.opencv and n <= args.opencv_max_targets:
                    cv_t.append(run_opencv(args.opencv, frames, boxes))
            nf = len(frames) - 1
            fm = nf / statistics.median(multi_t)
            fl = nf / statistics.median(loop_t)
            fc = f"{nf / statistics.median(cv_t):.1f}" if cv_t else "-"
            print(f"| {w}x{h} | {n} | {fm:.1f} | {fl:.1f} | {fm / fl:.2f}x | {fc} |", flush=True)


if __name__ == "__main__":
    main()
