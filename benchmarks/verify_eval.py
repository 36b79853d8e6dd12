"""Recompute ``wmiltrack eval``'s OPE figures from its box files, independently.

Usage::

    python benchmarks/verify_eval.py OUT_DIR [--dataset ../shared/data/otb] [--tol 1e-6]

Reads ``OUT_DIR/eval_ope.json`` (for the list of trackers, sequences and the dataset path),
then for every (tracker, sequence, repeat) reads the box file
``OUT_DIR/boxes/<tracker>/<seq>[.r<k>].txt`` and the sequence's ``groundtruth_rect.txt``
(first as many lines as there are boxes: the loader cuts sequences such as Football1 to their
annotated frames, and with ``start.txt`` the ground truth's first line is the first frame
tracked, so the lines stay paired), and recomputes AUC, success rate at 0.5, precision at
20 px and mean centre error with a few lines of numpy written here (it imports nothing from
wmiltrack).  Prints the largest absolute difference per figure and exits 1 if any exceeds
``--tol``.

The box files hold the boxes that were scored, after ``--missing`` (hold the last box, or
none on frames a tracker reports lost), so any convention is checked the same way.
(Tiger1, whose ground-truth lines start 5 frames before OTB-100's first frame, is not paired
right by "the first lines"; it is not among the shared sequences.)

Conventions (OTB toolkit): boxes ``x, y, w, h`` cover ``[x, x + w) x [y, y + h)``; frames whose
ground truth has a NaN or a non-positive width/height are not scored; a predicted row with NaN
has IoU 0 and infinite centre error (so the mean centre error is infinite when there is one);
success(t) = mean(IoU > t) for t = 0, 0.05, ..., 1 and AUC is the mean of those 21 values;
precision(20) = mean(error <= 20).
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

F = npt.NDArray[np.float64]


def read_rows(path: Path) -> F:
    """``x, y, w, h`` rows of a text file (comma, tab, space or semicolon separated)."""
    rows = []
    for line in path.read_text(encoding="utf-8-sig").splitlines():
        parts = [p for p in re.split(r"[,\t ;]+", line.strip()) if p]
        if parts:
            rows.append([float(p) for p in parts])
    return np.asarray(rows, dtype=np.float64).reshape(-1, 4)


def figures(pred: F, gt: F) -> dict[str, float]:
    """AUC, SR@0.5, P@20 and mean centre error, computed from scratch."""
    ok = np.isfinite(gt).all(axis=1) & (gt[:, 2] > 0) & (gt[:, 3] > 0)
    p, g = pred[ok], gt[ok]
    has = np.isfinite(p).all(axis=1)
    x1 = np.maximum(p[:, 0], g[:, 0])
    y1 = np.maximum(p[:, 1], g[:, 1])
    x2 = np.minimum(p[:, 0] + np.maximum(p[:, 2], 0), g[:, 0] + g[:, 2])
    y2 = np.minimum(p[:, 1] + np.maximum(p[:, 3], 0), g[:, 1] + g[:, 3])
    inter = np.clip(x2 - x1, 0, None) * np.clip(y2 - y1, 0, None)
    union = np.maximum(p[:, 2], 0) * np.maximum(p[:, 3], 0) + g[:, 2] * g[:, 3] - inter
    with np.errstate(invalid="ignore", divide="ignore"):
        ov = np.where(has & (union > 0), inter / union, 0.0)
    ov = np.nan_to_num(ov, nan=0.0)
    cp = p[:, :2] + p[:, 2:] / 2
    cg = g[:, :2] + g[:, 2:] / 2
    err = np.where(has, np.sqrt(((cp - cg) ** 2).sum(axis=1)), np.inf)
    err = np.nan_to_num(err, nan=np.inf)
    thr = np.arange(21) / 20.0
    success = np.array([(ov > t).mean() for t in thr])
    return {
        "auc": float(success.mean()),
        "success_50": float((ov > 0.5).mean()),
        "precision_20": float((err <= 20).mean()),
        "mean_center_error": float(err.mean()) if err.size else float("nan"),
    }


def main(argv: list[str] | None = None) -> int:
    """Compare; return the exit status."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0] if __doc__ else None)
    ap.add_argument("out", type=Path, help="the --out folder of `wmiltrack eval`")
    ap.add_argument(
        "--dataset",
        type=Path,
        default=None,
        help="dataset folder (default: the one recorded in eval_ope.json)",
    )
    ap.add_argument(
        "--boxes",
        type=Path,
        default=None,
        help="box folder (default OUT/boxes, or the --results folder recorded)",
    )
    ap.add_argument("--tol", type=float, default=1e-6)
    args = ap.parse_args(argv)

    doc: dict[str, Any] = json.loads((args.out / "eval_ope.json").read_text())
    dataset = args.dataset or Path(doc["dataset"])
    source = str(doc.get("source", "run"))
    boxes_root = args.boxes or (
        Path(source.split(":", 1)[1]) if source.startswith("results:") else args.out / "boxes"
    )
    single = (dataset / "groundtruth_rect.txt").is_file()
    worst: dict[str, float] = {}
    count = 0
    for tracker in doc["trackers"]:
        folder = boxes_root / doc["box_folders"][tracker]
        for seq, entry in doc["results"][tracker].items():
            gt_file = (dataset if single else dataset / seq) / "groundtruth_rect.txt"
            gt_all = read_rows(gt_file)
            for rep, run in enumerate(entry["runs"]):
                name = f"{seq}.txt" if rep == 0 else f"{seq}.r{rep}.txt"
                pred = read_rows(folder / name)[: len(gt_all)]
                mine = figures(pred, gt_all[: len(pred)])
                for key, value in mine.items():
                    theirs = run[key]
                    if theirs is None or np.isnan(value):
                        d = 0.0 if theirs is None and np.isnan(value) else float("inf")
                    elif np.isinf(value) or theirs in ("inf", "-inf"):
                        d = 0.0 if float(theirs) == value else float("inf")
                    else:
                        d = abs(float(theirs) - value)
                    worst[key] = max(worst.get(key, 0.0), d)
                count += 1
    print(
        f"{count} box files ({len(doc['trackers'])} trackers x {len(doc['sequences'])} "
        f"sequences x {doc['repeats']} repeats) recomputed independently"
    )
    for key, d in worst.items():
        print(f"  max |difference| {key:<18} {d:.3g}")
    total = max(worst.values()) if worst else 0.0
    print(
        f"max abs difference overall: {total:.3g} ({'OK' if total <= args.tol else 'FAIL'}"
        f", tolerance {args.tol:g})"
    )
    return 0 if total <= args.tol else 1


if __name__ == "__main__":
    sys.exit(main())
