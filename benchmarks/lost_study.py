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

    python benchmarks/lost_study.py --roots ../shared/data/otb,$POOL_DIR [--tracker rcwmil-cf]
        [--seeds 0] [--sequences a,b] [-j 2] [--json out.json]

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

#: Random places of the frame each studied frame asks the filter about.
RANDOM_PLACES = 6
#: The running mean of the filter's peak: weight of the old value.
MEMORY = 0.9


def _iou(a: np.ndarray, b: np.ndarray) -> float:
    return float(iou(a[None], b[None])[0])


def _centred(cx: float, cy: float, w: int, h: int) -> tuple[int, int, int, int]:
    return int(round(cx - w / 2.0)), int(round(cy - h / 2.0)), w, h


def study(job: tuple[str, int, str, str]) -> dict[str, Any]:
    """One tracker spec, seed, root and sequence: a row per studied frame (see the module's
    docstring)."""
    spec, seed, root, name = job
    import cv2

    cv2.setNumThreads(1)
    seq = load_dataset(root, [name])[0]
    frames = seq.load()
    gt = np.asarray(seq.groundtruth, dtype=np.float64)
    variant, overrides = parse_spec(spec)
    tracker = wmiltrack.Tracker(variant, seed=seed, **overrides)
    tracker.init(frames[0], seq.init_box)
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
        g = gt[i]
        gx, gy = g[0] + g[2] / 2.0, g[1] + g[3] / 2.0
        side = math.sqrt(box[2] * box[3])
        distance = math.hypot(gx - box[0] - box[2] / 2.0, gy - box[1] - box[3] / 2.0) / side
        # the grey template
        size = recovery.size or (int(box[2]), int(box[3]))
        at_target = recovery.similarity(frame, _centred(gx, gy, *size))
        place = recovery.best_place(frame)
        best, found = (math.nan, None) if place is None else place
        hit = found is not None and _iou(np.asarray(found, dtype=np.float64), g) >= 0.3
        # the correlation filter, at the box's size
        w, h = int(box[2]), int(box[3])
        cf_target = template.filter.locate(frame, (gx, gy), (w, h)).peak / usual
        fh, fw = frame.shape[:2]
        cf_random = []
        for _ in range(RANDOM_PLACES):
            cx, cy = rng.uniform(w / 2.0, max(w / 2.0 + 1, fw - w / 2.0)), rng.uniform(
                h / 2.0, max(h / 2.0 + 1, fh - h / 2.0))
            if abs(cx - gx) < g[2] and abs(cy - gy) < g[3]:
                continue
            cf_random.append(template.filter.locate(frame, (cx, cy), (w, h)).peak / usual)
        rows.append({"frame": i, "distance": distance, "grey_at_target": at_target,
                     "grey_best": best, "grey_best_on_target": bool(hit),
                     "filter_at_target": cf_target, "filter_random": cf_random})
    return {"spec": spec, "seed": seed, "name": name, "frames": len(frames), "rows": rows}


def summary(rows: list[dict[str, Any]]) -> dict[str, float]:
    """Medians and shares over studied frames (see the module's docstring)."""
    if not rows:
        return {"frames": 0}

    def col(key: str) -> np.ndarray:
        return np.array([r[key] for r in rows], dtype=np.float64)

    rand = np.array([v for r in rows for v in r["filter_random"]], dtype=np.float64)
    at_cf = col("filter_at_target")
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
    args = ap.parse_args(argv)
    if not args.roots:
        ap.error("give --roots or set WMILTRACK_DEVSET")
    where: dict[str, str] = {}
    for root in args.roots.split(","):
        for seq in load_dataset(root, None):
            where.setdefault(seq.name, root)
    names = sorted(where) if args.sequences is None else sorted(args.sequences.split(","))
    missing = [n for n in names if n not in where]
    if missing:
        ap.error(f"no such sequence under the roots: {', '.join(missing)}")
    jobs = [(args.tracker, int(s), where[n], n) for s in args.seeds.split(",") for n in names]
    with ProcessPoolExecutor(args.jobs) as pool:
        results = list(progress(pool.map(study, jobs), total=len(jobs), desc="runs"))
    print(f"{args.tracker}, seeds {args.seeds}: frames flagged lost with the target in view and "
          "missed (IoU < 0.1)")
    print("sequence | frames | distance (sides) | grey at target | grey best | best on target | "
          "filter at target | filter random q95")
    per: dict[str, list[dict[str, Any]]] = {}
    for res in results:
        per.setdefault(res["name"], []).extend(res["rows"])
    for name in names:
        s = summary(per[name])
        if s["frames"]:
            print(f"{name} | {s['frames']} | {s['distance_median']:.1f} | "
                  f"{s['grey_at_target_median']:.2f} | {s['grey_best_median']:.2f} | "
                  f"{100 * s['grey_best_on_target']:.0f} % | {s['filter_at_target_median']:.2f} | "
                  f"{s['filter_random_q95']:.2f}")
    pooled = summary([r for rows in per.values() for r in rows])
    print(f"all: {pooled}")
    if args.json is not None:
        args.json.write_text(json.dumps({"tracker": args.tracker, "summary": pooled,
                                         "runs": results}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
