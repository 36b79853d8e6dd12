"""Once a tracker has lost its target, could its own models find it again?

Runs a tracker with a lost state and a correlation-filter template (``rcwmil-cf`` by default)
over the development set and looks at every frame it flags lost (``ok`` False) while the target
is in view and its box misses it (IoU below 0.1). On each such frame it asks the two target
models a re-detection could use:

* the grey template of the lost state (:class:`~wmiltrack.engine.recovery.Redetector`): its
  correlation with a box of the re-detection's size centred on the true target, against the
  best place it finds over the whole frame, and whether that place is on the target (IoU with
  the true box at least 0.3);
* the correlation filter (frozen while the target is lost, as the tracker keeps it): its
  response peak searched around the true target, and around random places of the frame at
  least a target away from it, each divided by the filter's running mean peak over the frames
  flagged tracked.

It also prints how far the target is from the box, in box sides. A re-detector built on a model
can work only where the model scores the true target above every other place.

With ``--nano`` it asks a learned model the same question for comparison: NanoTrack v2's siamese
network (its two ONNX files, read from ``WMILTRACK_NANO_BACKBONE`` and ``WMILTRACK_NANO_HEAD``
and run by ``cv2.dnn``; never shipped with the project), its template taken from the first frame
as TrackerNano takes it. Its score at a place is the largest target log-odds of its 16 x 16
map over a search window (twice the target's context) centred there (log-odds, since the
probabilities are within 1e-3 of 1 at most places), at the true target and at three random
places whose window does not reach the target.

    python benchmarks/lost_study.py --roots ../shared/data/otb,$POOL_DIR [--tracker rcwmil-cf]
        [--seeds 0] [--sequences a,b] [-j 2] [--json out.json] [--nano]

``WMILTRACK_DEVSET`` (a comma-separated list of roots) replaces ``--roots``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np

import wmiltrack
from wmiltrack.data.sequences import load_dataset
from wmiltrack.eval.metrics import iou, valid_mask
from wmiltrack.progress import progress
from wmiltrack.trackers import parse_spec

#: Random places of the frame each studied frame asks the filter about (NanoTrack: fewer,
#: each costs a network's pass).
RANDOM_PLACES = 6
NANO_RANDOM_PLACES = 3
#: The running mean of the filter's peak: weight of the old value.
MEMORY = 0.9


def _iou(a: np.ndarray, b: np.ndarray) -> float:
    return float(iou(a[None], b[None])[0])


def _centred(cx: float, cy: float, w: int, h: int) -> tuple[int, int, int, int]:
    return int(round(cx - w / 2.0)), int(round(cy - h / 2.0)), w, h


class NanoScore:
    """NanoTrack v2's target log-odds over a search window (see the module's docstring):
    TrackerNano's crops (the box plus half its perimeter as context, the exemplar resized to
    127 px and the search window, twice as wide, to 255 px; the frame's mean colour beyond its
    edges) and its two networks, without its motion and size penalties."""

    EXEMPLAR, INSTANCE, CONTEXT = 127, 255, 0.5

    def __init__(self, backbone: str, head: str, frame: np.ndarray, box: Any) -> None:
        import cv2

        self.backbone = cv2.dnn.readNet(backbone)
        self.head = cv2.dnn.readNet(head)
        x, y, w, h = (float(v) for v in box)
        self.backbone.setInput(self._blob(frame, x + w / 2, y + h / 2, self._side(w, h),
                                          self.EXEMPLAR))
        self.head.setInput(self.backbone.forward(), "input1")

    def _side(self, w: float, h: float) -> float:
        extra = self.CONTEXT * (w + h)
        return math.sqrt((w + extra) * (h + extra))

    @staticmethod
    def _blob(frame: np.ndarray, cx: float, cy: float, side: float, out: int) -> np.ndarray:
        import cv2

        n = max(1, int(side))
        x0, y0 = int(cx) - (n + 1) // 2, int(cy) - (n + 1) // 2
        fh, fw = frame.shape[:2]
        pads = (max(0, -y0), max(0, y0 + n - fh), max(0, -x0), max(0, x0 + n - fw))
        if any(pads):
            mean = tuple(float(v) for v in cv2.mean(frame)[:3])
            frame = cv2.copyMakeBorder(frame, *pads, cv2.BORDER_CONSTANT, value=mean)
            x0, y0 = x0 + pads[2], y0 + pads[0]
        crop = cv2.resize(frame[y0:y0 + n, x0:x0 + n], (out, out))
        return cv2.dnn.blobFromImage(crop, 1.0, swapRB=True)

    def at(self, frame: np.ndarray, cx: float, cy: float, w: float, h: float) -> float:
        """The largest target log-odds over the search window centred at ``(cx, cy)`` for a
        target of ``w x h``."""
        self.backbone.setInput(self._blob(frame, cx, cy, self.window(w, h), self.INSTANCE))
        self.head.setInput(self.backbone.forward(), "input2")
        logits = self.head.forward("output1").reshape(2, -1).astype(np.float64)
        return float((logits[1] - logits[0]).max())  # the log-odds of the two classes' softmax

    def window(self, w: float, h: float) -> float:
        """The search window's side for a target of ``w x h``."""
        return self._side(w, h) * self.INSTANCE / self.EXEMPLAR


def _ask_grey(recovery: Any, frame: np.ndarray, box: np.ndarray, g: np.ndarray
              ) -> dict[str, Any]:
    """The target's distance from the box, and the lost state's grey template at the target
    and at its best place over the frame."""
    gx, gy = g[0] + g[2] / 2.0, g[1] + g[3] / 2.0
    side = math.sqrt(box[2] * box[3])
    distance = math.hypot(gx - box[0] - box[2] / 2.0, gy - box[1] - box[3] / 2.0) / side
    size = recovery.size or (int(box[2]), int(box[3]))
    place = recovery.best_place(frame)
    best, found = (math.nan, None) if place is None else place
    return {"distance": distance,
            "grey_at_target": recovery.similarity(frame, _centred(gx, gy, *size)),
            "grey_best": best,
            "grey_best_on_target": found is not None
            and _iou(np.asarray(found, dtype=np.float64), g) >= 0.3}


def _ask_filter(cf: Any, usual: float, frame: np.ndarray, box: np.ndarray, g: np.ndarray,
                rng: np.random.Generator) -> dict[str, Any]:
    """The correlation filter's peak (over its running mean ``usual``), at the box's size,
    around the target and around random places at least a target away."""
    gx, gy = g[0] + g[2] / 2.0, g[1] + g[3] / 2.0
    w, h = int(box[2]), int(box[3])
    fh, fw = frame.shape[:2]
    at_random = []
    for _ in range(RANDOM_PLACES):
        cx = rng.uniform(w / 2.0, max(w / 2.0 + 1, fw - w / 2.0))
        cy = rng.uniform(h / 2.0, max(h / 2.0 + 1, fh - h / 2.0))
        if abs(cx - gx) < g[2] and abs(cy - gy) < g[3]:
            continue
        at_random.append(cf.locate(frame, (cx, cy), (w, h)).peak / usual)
    return {"filter_at_target": cf.locate(frame, (gx, gy), (w, h)).peak / usual,
            "filter_random": at_random}


def _ask_nano(nano: NanoScore, frame: np.ndarray, g: np.ndarray, rng: np.random.Generator
              ) -> dict[str, Any]:
    """NanoTrack's log-odds at the target and at random places whose window misses it."""
    gx, gy = g[0] + g[2] / 2.0, g[1] + g[3] / 2.0
    fh, fw = frame.shape[:2]
    reach = nano.window(g[2], g[3]) / 2.0 + max(g[2], g[3])
    at_random: list[float] = []
    for _ in range(NANO_RANDOM_PLACES * 4):
        cx, cy = rng.uniform(0, fw), rng.uniform(0, fh)
        if max(abs(cx - gx), abs(cy - gy)) > reach:
            at_random.append(nano.at(frame, cx, cy, g[2], g[3]))
        if len(at_random) == NANO_RANDOM_PLACES:
            break
    return {"nano_at_target": nano.at(frame, gx, gy, g[2], g[3]), "nano_random": at_random}


def study(job: tuple[str, int, str, str, tuple[str, str] | None]) -> dict[str, Any]:
    """One tracker spec, seed, root and sequence (and NanoTrack's model files, or None): a
    row per studied frame (see the module's docstring)."""
    spec, seed, root, name, nano_files = job
    import cv2

    cv2.setNumThreads(1)
    seq = load_dataset(root, [name])[0]
    frames = seq.load()
    gt = np.asarray(seq.groundtruth, dtype=np.float64)
    variant, overrides = parse_spec(spec)
    tracker = wmiltrack.Tracker(variant, seed=seed, **overrides)
    tracker.init(frames[0], seq.init_box)
    nano = None if nano_files is None else NanoScore(*nano_files, frames[0], seq.init_box)
    recovery, template = tracker.parts.recovery, tracker.parts.template
    if recovery is None or template is None:
        raise SystemExit(f"{spec} has no lost state or no correlation-filter template")
    visible = valid_mask(gt)
    rng = np.random.default_rng(seed)
    usual = math.nan
    rows = []
    for i in range(1, len(frames)):
        frame = frames[i]
        r = tracker.update(frame)
        if r.ok:
            peak = template.confidence
            if math.isfinite(peak):
                usual = peak if not math.isfinite(usual) else MEMORY * usual + (1 - MEMORY) * peak
            continue
        box = np.asarray(r.box, dtype=np.float64)
        if not visible[i] or not math.isfinite(usual) or _iou(box, gt[i]) >= 0.1:
            continue
        row = {"frame": i, **_ask_grey(recovery, frame, box, gt[i]),
               **_ask_filter(template.filter, usual, frame, box, gt[i], rng)}
        if nano is not None:
            row.update(_ask_nano(nano, frame, gt[i], rng))
        rows.append(row)
    return {"spec": spec, "seed": seed, "name": name, "frames": len(frames), "rows": rows}


def summary(rows: list[dict[str, Any]]) -> dict[str, float]:
    """Medians and shares over studied frames (see the module's docstring)."""
    if not rows:
        return {"frames": 0}

    def col(key: str) -> np.ndarray:
        return np.array([r[key] for r in rows], dtype=np.float64)

    rand = np.array([v for r in rows for v in r["filter_random"]], dtype=np.float64)
    at_cf = col("filter_at_target")
    nano: dict[str, float] = {}
    if "nano_at_target" in rows[0]:
        at_nano = col("nano_at_target")
        nano_rand = np.array([v for r in rows for v in r["nano_random"]], dtype=np.float64)
        q95 = float(np.percentile(nano_rand, 95)) if nano_rand.size else math.nan
        nano = {"nano_at_target_median": float(np.median(at_nano)), "nano_random_q95": q95,
                "nano_target_above_random_q95": float(np.mean(at_nano > q95))}
    return {
        "frames": len(rows),
        "distance_median": float(np.median(col("distance"))),
        "within_3_sides": float(np.mean(col("distance") < 3)),
        "grey_at_target_median": float(np.nanmedian(col("grey_at_target"))),
        "grey_best_median": float(np.nanmedian(col("grey_best"))),
        "grey_best_on_target": float(np.mean(col("grey_best_on_target"))),
        "filter_at_target_median": float(np.median(at_cf)),
        "filter_random_q95": float(np.percentile(rand, 95)) if rand.size else math.nan,
        "filter_target_above_random_q95": (float(np.mean(at_cf > np.percentile(rand, 95)))
                                           if rand.size else math.nan),
        **nano,
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--roots", default=os.environ.get("WMILTRACK_DEVSET"),
                    help="comma-separated OTB-layout folders (default: $WMILTRACK_DEVSET)")
    ap.add_argument("--tracker", default="rcwmil-cf")
    ap.add_argument("--seeds", default="0")
    ap.add_argument("--sequences", default=None, help="comma-separated names (default all)")
    ap.add_argument("-j", "--jobs", type=int, default=1)
    ap.add_argument("--json", type=Path, default=None, help="write every row here")
    ap.add_argument("--nano", action="store_true",
                    help="also ask NanoTrack v2 (WMILTRACK_NANO_BACKBONE, WMILTRACK_NANO_HEAD)")
    args = ap.parse_args(argv)
    if not args.roots:
        ap.error("give --roots or set WMILTRACK_DEVSET")
    nano_files = None
    if args.nano:
        nano_files = (os.environ.get("WMILTRACK_NANO_BACKBONE", ""),
                      os.environ.get("WMILTRACK_NANO_HEAD", ""))
        if not all(Path(f).is_file() for f in nano_files):
            ap.error("--nano needs NanoTrack's two ONNX files in WMILTRACK_NANO_BACKBONE and "
                     "WMILTRACK_NANO_HEAD")
    where: dict[str, str] = {}
    for root in args.roots.split(","):
        for seq in load_dataset(root, None):
            where.setdefault(seq.name, root)
    names = sorted(where) if args.sequences is None else sorted(args.sequences.split(","))
    missing = [n for n in names if n not in where]
    if missing:
        ap.error(f"no such sequence under the roots: {', '.join(missing)}")
    jobs = [(args.tracker, int(s), where[n], n, nano_files) for s in args.seeds.split(",")
            for n in names]
    with ProcessPoolExecutor(args.jobs) as pool:
        results = list(progress(pool.map(study, jobs), total=len(jobs), desc="runs"))
    print(f"{args.tracker}, seeds {args.seeds}: frames flagged lost with the target in view and "
          "missed (IoU < 0.1)")
    print("sequence | frames | distance (sides) | grey at target | grey best | best on target | "
          "filter at target | filter random q95" + (" | nano at target | nano random q95"
                                                    if args.nano else ""))
    per: dict[str, list[dict[str, Any]]] = {}
    for res in results:
        per.setdefault(res["name"], []).extend(res["rows"])
    for name in names:
        s = summary(per[name])
        if s["frames"]:
            print(f"{name} | {s['frames']} | {s['distance_median']:.1f} | "
                  f"{s['grey_at_target_median']:.2f} | {s['grey_best_median']:.2f} | "
                  f"{100 * s['grey_best_on_target']:.0f} % | {s['filter_at_target_median']:.2f} | "
                  f"{s['filter_random_q95']:.2f}" + (
                      f" | {s['nano_at_target_median']:.2f} | {s['nano_random_q95']:.2f}"
                      if args.nano else ""))
    pooled = summary([r for rows in per.values() for r in rows])
    print(f"all: {pooled}")
    if args.json is not None:
        args.json.write_text(json.dumps({"tracker": args.tracker, "summary": pooled,
                                         "runs": results}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
