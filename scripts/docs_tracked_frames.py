"""Make docs/images/tracked_frames.jpg: four frames of the demo's generated sequence, tracked.

    python scripts/docs_tracked_frames.py [-o docs/images/tracked_frames.jpg]

The sequence is the one ``wmiltrack demo`` tracks (``make_preset("all", seed=0)``: occlusion,
illumination change, clutter). Green: rcwmil-plus; red: rcwmil; thin white: the ground truth.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import cv2
import numpy as np

import wmiltrack
from wmiltrack.data.synthetic import make_preset
from wmiltrack.visualize import draw_result

SHOWN = (1, 100, 200, 300)  # frame numbers, counted from 1


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-o", "--out", type=Path, default=Path("docs/images/tracked_frames.jpg"))
    args = parser.parse_args()

    seq = make_preset("all", seed=0, n_frames=max(SHOWN))
    frames = seq.load()
    gt = seq.groundtruth
    assert gt is not None
    boxes: dict[str, list[tuple[float, float, float, float]]] = {}
    for name in ("rcwmil", "rcwmil-plus"):
        t = wmiltrack.Tracker(name, seed=0)
        t.init(frames[0], tuple(gt[0]))
        boxes[name] = [t.box] + [t.update(f).box for f in frames[1:]]

    tiles = []
    for n in SHOWN:
        img = draw_result(frames[n - 1], boxes["rcwmil"][n - 1], color=(0, 0, 255))
        img = draw_result(img, boxes["rcwmil-plus"][n - 1], index=n, color=(0, 255, 0))
        x, y, w, h = (round(v) for v in gt[n - 1])
        cv2.rectangle(img, (x, y), (x + w - 1, y + h - 1), (255, 255, 255), 1)
        tiles.append(img)
    pad = np.full((tiles[0].shape[0], 4, 3), 255, np.uint8)
    row = [tiles[0]]
    for t in tiles[1:]:
        row += [pad, t]
    if not cv2.imwrite(str(args.out), cv2.hconcat(row), [cv2.IMWRITE_JPEG_QUALITY, 85]):
        raise SystemExit(f"cannot write {args.out}")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
