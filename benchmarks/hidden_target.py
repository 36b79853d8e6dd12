"""Does a tracker notice a hidden target and take it back? Generated sequences with a full
occlusion of 20 frames and a target out of view for 30 (``data/synthetic.py``), seeds 0, 1, 2.

For each tracker spec and seed it prints: the share of hidden frames reported lost
(``ok`` False; asked: at least 80 %), and how many frames after the target's return the box is
back on it (IoU > 0.5; asked: within 10), for the occlusion and for the return into view.

Usage::

    python benchmarks/hidden_target.py
    python benchmarks/hidden_target.py --trackers rcwmil,rcwmil-plus:template_weight=0.2:colour_weight=0.65

The default runs rcwmil, rcwmil-plus and rcwmil-plus with the lost state and re-detection
(``redetect=True``).

``--export DIR`` writes the three sequences instead, as OTB-layout folders (``hidden_s0`` ...,
``img/0001.jpg`` and ``groundtruth_rect.txt`` with ``NaN`` on the frames where the target is
hidden or out of view), for ``wmiltrack eval DIR --protocol longterm``; an existing folder of
that name is an error, never overwritten.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import numpy as np

from wmiltrack.data.synthetic import make_sequence
from wmiltrack.eval.metrics import iou
from wmiltrack.trackers import make_tracker, split_specs

OCCLUDED = (60, 20)  # frames 60..79 hidden behind a block
OUT = (110, 30)  # frames 110..139 out of view


def back_after(boxes: np.ndarray, gt: np.ndarray, start: int, limit: int = 30) -> int | None:
    """Frames from ``start`` until the box first overlaps the target by IoU > 0.5 (None: not
    within ``limit``)."""
    end = min(start + limit, len(gt))
    ov = iou(boxes[start:end], gt[start:end])
    hits = np.flatnonzero(ov > 0.5)
    return int(hits[0]) if hits.size else None


def generated(seed: int) -> Any:
    """The generated sequence of ``seed``: a full occlusion and a spell out of view."""
    return make_sequence(170, seed=seed, occlusion=False, full_occlusion=OCCLUDED, out_of_view=OUT)


def export(root: Path, seeds: list[int]) -> None:
    """The sequences of ``seeds`` as OTB-layout folders under ``root`` (absent: NaN)."""
    import cv2

    for seed in seeds:
        seq = generated(seed)
        folder = root / f"hidden_s{seed}"
        if folder.exists():
            raise SystemExit(f"{folder} exists: choose another --export folder")
        (folder / "img").mkdir(parents=True)
        for i, frame in enumerate(seq.load()):
            cv2.imwrite(str(folder / "img" / f"{i + 1:04d}.jpg"), frame,
                        [cv2.IMWRITE_JPEG_QUALITY, 95])
        gt = np.asarray(seq.groundtruth, dtype=np.float64)
        gt[~seq.meta["visible"]] = np.nan
        (folder / "groundtruth_rect.txt").write_text(
            "\n".join(",".join(f"{v:.3f}" for v in row) for row in gt) + "\n")
        print(f"wrote {folder}")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--trackers", default="rcwmil,rcwmil-plus,rcwmil-plus:redetect=True")
    ap.add_argument("--seeds", default="0,1,2")
    ap.add_argument("--export", type=Path, default=None,
                    help="write the sequences as OTB-layout folders here instead of tracking")
    args = ap.parse_args(argv)
    if args.export is not None:
        export(args.export, [int(s) for s in args.seeds.split(",")])
        return 0
    print(f"{'tracker':<40} {'seed':>4} {'lost while hidden':>17} {'back after occl.':>16} "
          f"{'back after out':>14}")
    for spec in split_specs(args.trackers):
        for seed in (int(s) for s in args.seeds.split(",")):
            seq = generated(seed)
            frames, gt = seq.load(), np.asarray(seq.groundtruth, dtype=np.float64)
            tracker = make_tracker(spec, seed=seed)
            tracker.init(frames[0], tuple(gt[0]))
            boxes, oks = [gt[0]], [True]
            for f in frames[1:]:
                r = tracker.update(f)
                boxes.append(np.asarray(r.box, dtype=np.float64))
                oks.append(bool(r.ok))
            b, ok = np.array(boxes), np.array(oks)
            hidden = ~seq.meta["visible"]
            lost = float(np.mean(~ok[hidden]))
            occ = back_after(b, gt, OCCLUDED[0] + OCCLUDED[1])
            out = back_after(b, gt, OUT[0] + OUT[1])
            print(f"{spec:<40} {seed:>4} {lost:>16.0%} {str(occ):>16} {str(out):>14}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
