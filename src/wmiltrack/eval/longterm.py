"""Long-term tracking figures: tracking precision, recall and F-score over confidence thresholds.

OTB's one-pass AUC scores every frame's box and ignores whether the tracker said it had the
target, so a tracker that never says "lost" loses nothing by it. The long-term measures of
Lukežič et al. ("Now you see me: evaluating performance in long-term visual tracking") and of
the VOT long-term challenges score the tracker's claim too. On one sequence, with ``IoU_t``
the overlap of frame ``t``'s box with the ground truth (0 where the target is absent, i.e. the
ground truth is NaN or empty) and ``c_t`` the tracker's confidence:

* tracking precision ``Pr(tau)`` = mean of ``IoU_t`` over the frames with ``c_t >= tau`` (the
  frames where the tracker reports the target); 1 when it reports none;
* tracking recall ``Re(tau)`` = sum of ``IoU_t`` over the frames with ``c_t >= tau``, divided by
  the number of frames where the target is present (a frame not reported counts 0);
* ``F(tau) = 2 Pr Re / (Pr + Re)``.

Over a dataset this module does what the VOT toolkit does (``vot/analysis/longterm.py``: the
``pr_curves``, ``pr_curve``, ``f_curve`` and ``average_tpr`` analyses): the thresholds are up to
100 values taken from the tracker's confidences pooled over every sequence (plus +inf and
-inf), ``Pr`` and ``Re`` are computed per sequence (averaged over repeats) at every threshold,
averaged over the sequences threshold by threshold, and ``F`` is computed on that averaged
curve; the tracker's F-score is its maximum, with ``Pr`` and ``Re`` reported at the threshold
that gives it. Besides, each tracker is scored at its own lost flag: ``c_t`` = 1 where
``ok`` is true, else 0, at ``tau`` = 1.

The confidence of a frame is the tracker's ``TrackResult.score`` when the run has scores
(wmiltrack's presets; OpenCV's TrackerNano through ``getTrackingScore``), else its ``ok`` flag
as 1 or 0 (OpenCV's other trackers give no score). A frame without a box, or without a score in
a run that has scores (a frame that could not be decoded), is never reported. The first frame
(the one the tracker is started on) is left out of every figure. Boxes are not clipped to the
frame (the toolkit clips them; OTB's figures do not).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from .metrics import iou, valid_mask

__all__ = [
    "LongTermCurve",
    "confidences",
    "f_score",
    "longterm_scores",
    "sequence_curve",
    "thresholds_from",
]

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]

#: Thresholds per tracker (the VOT toolkit's default resolution), +inf and -inf included.
RESOLUTION = 100


def confidences(scores: npt.ArrayLike, oks: npt.ArrayLike, boxes: npt.ArrayLike) -> FloatArray:
    """Each frame's confidence: the score where the run has scores, else ``ok`` as 1 or 0.

    Parameters
    ----------
    scores:
        ``(n,)`` the tracker's scores (NaN where it gave none), or an empty array.
    oks:
        ``(n,)`` its lost flags (``True``: found).
    boxes:
        ``(n, 4)`` its boxes; a frame with a NaN box is never reported.

    Returns
    -------
    numpy.ndarray
        ``(n,)`` confidences; ``-inf`` for a frame that is never reported.
    """
    ok = np.asarray(oks, dtype=bool)
    s = np.asarray(scores, dtype=np.float64).reshape(-1)
    b = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
    if s.shape == ok.shape and np.any(np.isfinite(s[1:])):
        conf = np.where(np.isfinite(s), s, -np.inf)
    else:
        conf = ok.astype(np.float64)
        conf[~ok] = -np.inf
    conf[~np.all(np.isfinite(b), axis=1)] = -np.inf
    return conf


def thresholds_from(values: Iterable[float], resolution: int = RESOLUTION) -> FloatArray:
    """The thresholds of one tracker: its finite confidences in decreasing order, or, when there
    are more than ``resolution - 2``, ``resolution - 2`` of them evenly spaced through that
    order, then +inf first and -inf last (as the VOT toolkit chooses them).

    Parameters
    ----------
    values:
        Every confidence the tracker gave (all sequences and repeats).
    resolution:
        Thresholds in all (at least 3).
    """
    if resolution < 3:
        raise ValueError(f"resolution must be at least 3, got {resolution}")
    v = np.sort(np.asarray([x for x in values if math.isfinite(x)], dtype=np.float64))[::-1]
    if v.size > resolution - 2:
        step = v.size // (resolution - 2)
        idx = np.round(np.linspace(step, v.size - step, num=resolution - 2)).astype(int)
        v = v[np.clip(idx, 0, v.size - 1)]
    return np.concatenate([[np.inf], v, [-np.inf]])


def sequence_curve(boxes: npt.ArrayLike, conf: npt.ArrayLike, gt: npt.ArrayLike,
                   thresholds: npt.ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Tracking precision and recall of one run at every threshold (frame 0 left out).

    Parameters
    ----------
    boxes:
        ``(n, 4)`` the run's boxes.
    conf:
        ``(n,)`` :func:`confidences`.
    gt:
        ``(n, 4)`` ground truth; NaN or empty rows: the target is absent.
    thresholds:
        ``(k,)`` thresholds.

    Returns
    -------
    (precision, recall)
        Two ``(k,)`` arrays. Precision is 1 at a threshold where no frame is reported.

    Raises
    ------
    ValueError
        Shapes that do not match, or no frame after the first where the target is present.
    """
    b = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)[1:]
    g = np.asarray(gt, dtype=np.float64).reshape(-1, 4)[1:]
    c = np.asarray(conf, dtype=np.float64).reshape(-1)[1:]
    if b.shape != g.shape or c.shape[0] != b.shape[0]:
        raise ValueError(f"boxes {b.shape}, ground truth {g.shape} and confidences {c.shape} "
                         "must have one row per frame")
    present = valid_mask(g)
    n_present = int(np.sum(present))
    if n_present == 0:
        raise ValueError("the target is present on no frame after the first")
    overlap = np.where(present, iou(b, g), 0.0)
    t = np.asarray(thresholds, dtype=np.float64).reshape(-1)
    reported = (c[None, :] >= t[:, None]) & np.isfinite(c)[None, :]  # (k, n); -inf: never
    n_rep = reported.sum(axis=1)
    total = (reported * overlap[None, :]).sum(axis=1)
    precision = np.where(n_rep > 0, total / np.maximum(n_rep, 1), 1.0)
    recall = total / n_present
    return precision.astype(np.float64), recall.astype(np.float64)


def f_score(precision: npt.ArrayLike, recall: npt.ArrayLike) -> FloatArray:
    """``2 Pr Re / (Pr + Re)``, 0 where both are 0."""
    p = np.asarray(precision, dtype=np.float64)
    r = np.asarray(recall, dtype=np.float64)
    s = p + r
    return np.where(s > 0, 2.0 * p * r / np.where(s > 0, s, 1.0), 0.0)


@dataclass(frozen=True)
class LongTermCurve:
    """One tracker's long-term figures over a dataset.

    Attributes
    ----------
    thresholds, precision, recall, f:
        The averaged curve, one value per threshold (decreasing thresholds).
    best:
        Index of the maximum F-score.
    """

    thresholds: FloatArray
    precision: FloatArray
    recall: FloatArray
    f: FloatArray
    best: int

    @classmethod
    def of(cls, thresholds: FloatArray, precision: FloatArray, recall: FloatArray
           ) -> LongTermCurve:
        """The curve with its F-scores and the index of their maximum (the first, on ties)."""
        f = f_score(precision, recall)
        return cls(thresholds, precision, recall, f, int(np.argmax(f)))

    def summary(self) -> dict[str, float]:
        """``f_score``, ``precision``, ``recall`` and ``threshold`` at the best F-score."""
        return {
            "f_score": float(self.f[self.best]),
            "precision": float(self.precision[self.best]),
            "recall": float(self.recall[self.best]),
            "threshold": float(self.thresholds[self.best]),
        }


def _mean_over_repeats(curves: Sequence[tuple[FloatArray, FloatArray]]
                       ) -> tuple[FloatArray, FloatArray]:
    return (np.mean([c[0] for c in curves], axis=0), np.mean([c[1] for c in curves], axis=0))


def _tracker_figures(runs: Sequence[Any], gts: Mapping[str, FloatArray]) -> dict[str, Any]:
    """Long-term figures of one tracker's runs (every sequence and repeat)."""
    conf = {id(r): confidences(r.scores, r.oks, r.boxes) for r in runs}
    ok_conf = {id(r): confidences(np.zeros(0), r.oks, r.boxes) for r in runs}
    thr = thresholds_from(v for c in conf.values() for v in c[1:])
    at_ok = np.array([1.0])
    by_seq: dict[str, list[Any]] = {}
    for r in runs:
        by_seq.setdefault(r.sequence, []).append(r)
    per_seq: dict[str, tuple[FloatArray, FloatArray]] = {}
    per_seq_ok: dict[str, tuple[FloatArray, FloatArray]] = {}
    for seq, seq_runs in by_seq.items():
        gt = gts[seq]
        per_seq[seq] = _mean_over_repeats(
            [sequence_curve(r.boxes, conf[id(r)], gt, thr) for r in seq_runs])
        per_seq_ok[seq] = _mean_over_repeats(
            [sequence_curve(r.boxes, ok_conf[id(r)], gt, at_ok) for r in seq_runs])
    curve = LongTermCurve.of(thr, np.mean([p for p, _ in per_seq.values()], axis=0),
                             np.mean([r for _, r in per_seq.values()], axis=0))
    ok_pr = float(np.mean([p[0] for p, _ in per_seq_ok.values()]))
    ok_re = float(np.mean([r[0] for _, r in per_seq_ok.values()]))
    sequences = {}
    for seq, (p, r) in per_seq.items():
        f = f_score(p, r)
        okp, okr = per_seq_ok[seq]
        sequences[seq] = {
            "precision": float(p[curve.best]), "recall": float(r[curve.best]),
            "f_score": float(f[curve.best]), "f_score_max": float(np.max(f)),
            "ok_precision": float(okp[0]), "ok_recall": float(okr[0]),
            "ok_f_score": float(f_score(okp, okr)[0]),
            "absent_frames": int(np.sum(~valid_mask(gts[seq])[1:])),
            "repeats": len(by_seq[seq]),
        }
    return {
        **curve.summary(),
        "ok_precision": ok_pr,
        "ok_recall": ok_re,
        "ok_f_score": float(f_score(np.array([ok_pr]), np.array([ok_re]))[0]),
        "confidence": "score" if any(
            np.any(np.isfinite(np.asarray(r.scores, dtype=np.float64)[1:])) for r in runs
        ) else "ok",
        "curve": {"thresholds": curve.thresholds.tolist(),
                  "precision": curve.precision.tolist(),
                  "recall": curve.recall.tolist(), "f_score": curve.f.tolist()},
        "sequences": sequences,
    }


def longterm_scores(runs: Sequence[Any], gts: Mapping[str, FloatArray]) -> dict[str, Any]:
    """Every tracker's long-term figures.

    Parameters
    ----------
    runs:
        :class:`wmiltrack.eval.runner.RunOutcome` objects (anything with ``tracker``,
        ``sequence``, ``boxes``, ``oks``, ``scores`` and ``error``). A failed run is scored
        as it stands (no frame reported from where it failed: its target is missed there, as
        OPE's figures miss it) and counted in ``errors``.
    gts:
        ``{sequence: (n, 4) ground truth}``.

    Returns
    -------
    dict
        ``{"summary": {tracker: figures}, "results": {tracker: {sequence: figures}},
        "errors": {tracker: failed runs}, "left_out": [sequences]}``; ``left_out``: the
        sequences where the target is present on no frame after the first (no recall).
        A tracker's summary: ``errors`` (its failed runs), ``f_score``, ``precision``,
        ``recall``, ``threshold`` (at the maximum F-score of the averaged curve),
        ``ok_precision``, ``ok_recall``, ``ok_f_score`` (at its own lost flag),
        ``confidence`` (``"score"`` or ``"ok"``) and ``curve`` (lists per threshold).
        A sequence's figures: ``precision``, ``recall``, ``f_score`` at the tracker's best
        threshold, the sequence's own maximum ``f_score_max``, ``ok_*`` at the lost flag,
        ``absent_frames`` and ``repeats``.
    """
    # recall is not defined without a frame where the target is present (after the first)
    left_out = sorted(n for n, g in gts.items() if not np.any(valid_mask(g)[1:]))
    gts = {n: g for n, g in gts.items() if n not in left_out}
    by_tracker: dict[str, list[Any]] = {}
    errors: dict[str, int] = {}
    for r in runs:
        if r.sequence not in gts:
            continue
        if r.error is not None:
            errors[r.tracker] = errors.get(r.tracker, 0) + 1
        by_tracker.setdefault(r.tracker, []).append(r)
    summary: dict[str, Any] = {}
    results: dict[str, Any] = {}
    for t, rs in by_tracker.items():
        figures = _tracker_figures(rs, gts)
        results[t] = figures.pop("sequences")
        summary[t] = {**figures, "errors": errors.get(t, 0)}
    return {"summary": summary, "results": results, "errors": errors, "left_out": left_out}
