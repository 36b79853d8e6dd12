"""Probe: track with the correlation filters alone (translation + DSST scale), no MIL.

An experiment, not a preset: it measures what the correlation-filter parts of
:mod:`wmiltrack.engine.correlation` do on their own, Staple's loop without its colour
model. Each frame: the translation filter searches around the last centre at the last
size, the scale filter estimates the size change at the new centre, then both learn there
(rates 0.01 and 0.025). Deterministic, so one run per sequence.

Usage::

    python benchmarks/cf_probe.py                     # the 17 shared sequences
    python benchmarks/cf_probe.py --names Car4,David --no-scale

AUC: OTB success AUC with a box on every frame (``ope_metrics(..., missing="hold")``, as
``wmiltrack eval`` scores); frames/s: the tracking loop (init + updates) on frames decoded
beforehand, in this process. ``--confidence`` also prints how well each of the translation
filter's confidences (peak, PSR, APCE, and each divided by its running mean over the
earlier frames, "rel") tells tracked frames (IoU > 0) from lost ones (IoU == 0), as ROC AUC
over all frames pooled (``scripts/score_study.py``'s ``roc_auc``).
"""

from __future__ import annotations

import argparse
import importlib.util
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np

try:
    import wmiltrack  # noqa: F401
except ImportError:  # a checkout that was not installed
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))

from wmiltrack.data.sequences import default_otb_root, load_dataset
from wmiltrack.engine.correlation import (
    CorrelationFilter,
    CorrelationSettings,
    ScaleFilter,
    ScaleFilterSettings,
)
from wmiltrack.eval.metrics import iou, ope_metrics
from wmiltrack.progress import progress
from wmiltrack.timing import gc_paused, timed

CONFIDENCES = ("peak", "psr", "apce")
RELATIVE_RATE = 0.05  # running mean of a confidence over earlier frames, for the "rel" rows


def relative(values: np.ndarray) -> np.ndarray:
    """Each value divided by the running mean (rate RELATIVE_RATE) of the values before it;
    NaN on the first."""
    out = np.full(values.shape, np.nan)
    mean = math.nan
    for i, v in enumerate(values):
        if math.isfinite(v):
            if math.isfinite(mean):
                out[i] = v / mean if mean > 0 else np.nan
                mean = (1 - RELATIVE_RATE) * mean + RELATIVE_RATE * v
            else:
                mean = v
    return out


def track(frames: list[np.ndarray], box: np.ndarray, settings: CorrelationSettings,
          scale_settings: ScaleFilterSettings, use_scale: bool,
          learn_every: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """Boxes (n, 4) of the CF-only tracker on ``frames`` from ``box`` on the first, and the
    translation filter's confidences (n, 3: peak, PSR, APCE; NaN on the first frame).

    ``learn_every`` = k > 1: both filters learn on every k-th frame only, at the rate that
    forgets as fast per frame (1 - (1 - rate)**k), as ECO's sparse updates."""
    x, y, w, h = (float(v) for v in box)
    cf = CorrelationFilter(settings)
    cf.init(frames[0], (x, y, w, h))
    se = ScaleFilter(scale_settings)
    if use_scale:
        se.init(frames[0], (x, y, w, h))
    cx, cy = x + w / 2, y + h / 2
    fh, fw = frames[0].shape[:2]
    min_side = 4.0
    out = [np.array([x, y, w, h])]
    conf = [np.full(len(CONFIDENCES), np.nan)]
    cf_rate = 1.0 - (1.0 - settings.learning_rate) ** learn_every
    scale_rate = 1.0 - (1.0 - scale_settings.learning_rate) ** learn_every
    for i, frame in enumerate(frames[1:], start=1):
        learn = i % learn_every == 0
        loc = cf.locate(frame, (cx, cy), (w, h))
        conf.append(np.array([loc.peak, loc.psr, loc.apce]))
        cx = min(max(cx + loc.dx, 0.0), fw - 1.0)
        cy = min(max(cy + loc.dy, 0.0), fh - 1.0)
        if use_scale:
            f = se.estimate(frame, (cx, cy), (w, h)).factor
            f = min(f, fw / w, fh / h)  # never larger than the frame
            f = max(f, min_side / w, min_side / h)
            w, h = w * f, h * f
            if learn:
                se.learn(frame, (cx, cy), (w, h), scale_rate)
        if learn:
            cf.learn(frame, (cx - w / 2, cy - h / 2, w, h), cf_rate)
        out.append(np.array([cx - w / 2, cy - h / 2, w, h]))
    return np.array(out), np.array(conf)


def _median(values: np.ndarray) -> float:
    finite = values[np.isfinite(values)]
    return float(np.median(finite)) if finite.size else math.nan


def _roc_auc() -> Any:
    """``roc_auc`` of scripts/score_study.py (the project's tracked-vs-lost measure)."""
    path = Path(__file__).resolve().parents[1] / "scripts" / "score_study.py"
    spec = importlib.util.spec_from_file_location("score_study", path)
    if spec is None or spec.loader is None:
        raise ImportError(f"cannot load {path}")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.roc_auc


def main(argv: list[str] | None = None) -> int:
    """Run the probe and print per-sequence AUC, the mean and frames/s."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--otb", type=Path, default=None, help="OTB folder (default: the project's)")
    ap.add_argument("--names", default=None, help="comma-separated sequence names (default: all)")
    ap.add_argument("--no-scale", action="store_true", help="translation only (fixed size)")
    ap.add_argument("--padding", type=float, default=CorrelationSettings.padding)
    ap.add_argument("--cell", type=int, default=CorrelationSettings.cell)
    ap.add_argument("--rate", type=float, default=CorrelationSettings.learning_rate)
    ap.add_argument("--scales", type=int, default=ScaleFilterSettings.num_scales,
                    help="scale samples (odd; default 33)")
    ap.add_argument("--learn-every", type=int, default=1, metavar="K",
                    help="learn on every K-th frame only (at the equivalent rate)")
    ap.add_argument("--confidence", action="store_true",
                    help="also the ROC AUC of each confidence for tracked vs lost frames")
    ap.add_argument("--area", type=float, default=CorrelationSettings.template_area,
                    help="template pixels (default 150**2)")
    args = ap.parse_args(argv)
    if args.learn_every < 1:
        ap.error("--learn-every must be >= 1")
    settings = CorrelationSettings(cell=args.cell, padding=args.padding, learning_rate=args.rate,
                                   template_area=args.area)
    scale_settings = ScaleFilterSettings(num_scales=args.scales)
    root = args.otb if args.otb is not None else default_otb_root()
    names = args.names.split(",") if args.names else None
    seqs = load_dataset(root, names)
    rows = []
    ious, confs = [], []
    total_frames, total_time = 0, 0.0
    for seq in progress(seqs, desc="sequences"):
        frames = seq.load()
        gt = seq.groundtruth
        if gt is None:
            ap.error(f"{seq.name} has no ground truth")
        with gc_paused():
            (boxes, conf), dt = timed(track, frames, np.asarray(seq.init_box), settings,
                                      scale_settings, not args.no_scale, args.learn_every)
        ious.append(iou(boxes[1:], gt[1:]))
        rel = np.stack([relative(conf[:, k]) for k in range(conf.shape[1])], axis=1)
        confs.append(np.concatenate([conf, rel], axis=1)[1:])
        auc = ope_metrics(boxes, gt, missing="hold").auc
        rows.append((seq.name, len(frames), auc, len(frames) / dt))
        total_frames += len(frames)
        total_time += dt
    print(f"{'sequence':<16} {'frames':>6} {'AUC':>6} {'fps':>7}")
    for name, n, auc, fps in rows:
        print(f"{name:<16} {n:>6} {auc:6.3f} {fps:7.1f}")
    mean = float(np.mean([r[2] for r in rows]))
    print(f"{'mean':<16} {total_frames:>6} {mean:6.3f} {total_frames / total_time:7.1f}")
    if args.confidence:
        ov, cf = np.concatenate(ious), np.concatenate(confs)
        scored = np.isfinite(ov)
        tracked, lost = scored & (ov > 0), scored & (ov == 0)
        roc_auc = _roc_auc()
        print(f"confidence: tracked (IoU > 0) {int(tracked.sum())} frames, lost {int(lost.sum())}")
        names = [*CONFIDENCES, *(f"{n} rel" for n in CONFIDENCES)]
        for k, name in enumerate(names):
            print(f"  {name:<9} ROC AUC {roc_auc(cf[tracked, k], cf[lost, k]):.3f}  "
                  f"median tracked {_median(cf[tracked, k]):.3g}, lost {_median(cf[lost, k]):.3g}")
    return 0 if math.isfinite(mean) else 1


if __name__ == "__main__":
    raise SystemExit(main())
