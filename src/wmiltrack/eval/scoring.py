"""Score stage of the evaluation: turn :class:`~wmiltrack.eval.runner.RunOutcome` s into figures.

Conventions
-----------
*Frames without a box* (``missing``), the same rule for every tracker:

``"hold"`` (default, as the OTB toolkit's ``calcSeqErrRobust.m`` and the got10k toolkit
    give every tracker a box on every frame)
    A frame where the tracker gave no box (an OpenCV tracker saying "not found") gets the
    last box it gave.  Frames after a tracker raised stay without a box.
``"miss"``
    Every frame the tracker reports lost (its ``ok`` flag False, whatever box it returned)
    has no box.

Whatever the convention, a frame left without a box is a miss in every figure: IoU 0 and an
infinite centre error, so it fails every success and precision threshold and makes the mean
centre error infinite (it is not left out of that mean).  Frames whose ground truth is absent
are left out of every figure (:func:`wmiltrack.eval.metrics.ope_metrics`).

Repeats are runs with different seeds; per-sequence figures are means over the repeats with
the population standard deviation beside them, and a tracker's summary is the mean over
sequences computed per repeat, then mean and standard deviation over the repeats.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Collection, Iterable, Mapping, Sequence
from typing import Any, Literal

import numpy as np
import numpy.typing as npt

from .benchmark_scores import count_absent_as_failures
from .metrics import hold_missing, ope_metrics
from .runner import RunOutcome

__all__ = [
    "OPE_SCALARS",
    "SPEED_SCALARS",
    "VOT_SCALARS",
    "Missing",
    "run_boxes",
    "score_ope",
    "score_vot",
    "scored_boxes",
]

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]
Missing = Literal["hold", "miss"]

OPE_SCALARS = (
    "auc",
    "success_50",
    "precision_20",
    "norm_precision_20",
    "mean_iou",
    "mean_center_error",
)
VOT_SCALARS = ("accuracy", "failures", "robustness", "failures_per_100")
SPEED_SCALARS = ("fps", "init_time", "median_update_time")


def scored_boxes(
    boxes: npt.ArrayLike,
    oks: npt.ArrayLike,
    frames_run: int | None = None,
    missing: Missing = "hold",
) -> FloatArray:
    """The boxes that are scored, under the convention for frames without a box.

    Parameters
    ----------
    boxes:
        ``(n, 4)`` boxes as the tracker gave them (NaN rows: no box).
    oks:
        ``(n,)`` the tracker's "found" flags.
    frames_run:
        Frames before the one where the tracker raised (``None``: all of them); later
        frames stay without a box under either convention.
    missing:
        ``"hold"``: a frame without a box gets the last box given before it.  ``"miss"``: a
        frame the tracker reports lost has no box, whatever it returned.

    Returns
    -------
    numpy.ndarray
        A new ``(n, 4)`` array; NaN rows are misses.

    Raises
    ------
    ValueError
        For an unknown convention or mismatched lengths.
    """
    b = np.array(boxes, dtype=np.float64, copy=True)
    ok = np.asarray(oks, dtype=bool)
    if b.ndim != 2 or b.shape[1] != 4 or ok.shape != (b.shape[0],):
        raise ValueError(f"boxes {b.shape} and oks {ok.shape} do not match")
    end = b.shape[0] if frames_run is None else int(frames_run)
    if missing == "hold":
        if end > 0:
            b[:end] = hold_missing(b[:end])
    elif missing == "miss":
        b[~ok] = np.nan
    else:
        raise ValueError(f"missing must be 'hold' or 'miss', not {missing!r}")
    b[end:] = np.nan
    return b


def run_boxes(run: RunOutcome, missing: Missing) -> FloatArray:
    """:func:`scored_boxes` of one run."""
    return scored_boxes(run.boxes, run.oks, run.frames_run, missing)


def _stats(values: Iterable[float]) -> tuple[float, float]:
    arr = np.asarray(list(values), dtype=np.float64)
    arr = arr[~np.isnan(arr)]  # an infinite centre error (a frame without a box) stays
    if arr.size == 0:
        return math.nan, math.nan
    if not np.all(np.isfinite(arr)):
        return float(arr.mean()), math.nan
    return float(arr.mean()), float(arr.std())


def _mean_curve(curves: Sequence[Sequence[float]]) -> list[float]:
    stack = np.asarray(curves, dtype=np.float64)
    keep = ~np.any(np.isnan(stack), axis=1)
    if not keep.any():
        return [math.nan] * stack.shape[1]
    return [float(v) for v in stack[keep].mean(axis=0)]


def _speed(run: RunOutcome) -> dict[str, Any]:
    return {
        "fps": run.fps,
        "init_time": run.init_time,
        "median_update_time": run.median_update_time,
        "n_updates": run.n_updates,
        "n_lost": run.n_lost,
        "error": run.error,
        "seed": run.seed,
    }


def _group(
    runs: Iterable[RunOutcome],
) -> dict[str, dict[str, list[RunOutcome]]]:
    out: dict[str, dict[str, list[RunOutcome]]] = {}
    for r in runs:
        out.setdefault(r.tracker, {}).setdefault(r.sequence, []).append(r)
    for seqs in out.values():
        for lst in seqs.values():
            lst.sort(key=lambda r: r.repeat)
    return out


def _seq_summary(per_run: Sequence[Mapping[str, Any]], keys: Sequence[str]) -> dict[str, Any]:
    d: dict[str, Any] = {}
    for k in keys:
        m, s = _stats(float(r[k]) if r[k] is not None else math.nan for r in per_run)
        d[k] = m
        d[k + "_std"] = s
    return d


def _collect(
    seqs: Mapping[str, Sequence[RunOutcome]],
    figures: Callable[[RunOutcome, str], dict[str, Any]],
    seq_mean: Callable[[list[dict[str, Any]]], dict[str, Any]],
) -> tuple[dict[str, Any], dict[int, list[dict[str, Any]]], dict[str, float]]:
    """One tracker's runs: per-run figures (``figures``) with speed, per-sequence means
    (``seq_mean`` plus an error count), the runs of each repeat, and the overall speed
    (``fps``: all timed updates over all their time; ``init_time``: mean)."""
    results: dict[str, Any] = {}
    per_repeat: dict[int, list[dict[str, Any]]] = {}
    updates = 0
    seconds = 0.0
    init_times: list[float] = []
    for seq_name, seq_runs in seqs.items():
        per_run: list[dict[str, Any]] = []
        for run in seq_runs:
            fig = figures(run, seq_name)
            fig.update(_speed(run))
            per_run.append(fig)
            per_repeat.setdefault(run.repeat, []).append(fig)
            if run.n_updates and run.fps > 0:
                updates += run.n_updates
                seconds += run.n_updates / run.fps
            init_times.append(run.init_time)
        mean = seq_mean(per_run)
        mean["errors"] = sum(r["error"] is not None for r in per_run)
        results[seq_name] = {"runs": per_run, "mean": mean}
    speed = {
        "fps": updates / seconds if seconds > 0 else math.nan,
        "init_time": _stats(init_times)[0],
    }
    return results, per_repeat, speed


def score_ope(
    runs: Sequence[RunOutcome],
    gts: Mapping[str, FloatArray],
    *,
    missing: Missing = "hold",
    reference: str = "opencv:MIL",
    absent_fail: Collection[str] = (),
) -> dict[str, Any]:
    """Score OPE runs: figures per run, per (tracker, sequence) and per tracker.

    Sequences named in ``absent_fail`` (LaSOT's) count their frames without ground truth as
    failures (:func:`wmiltrack.eval.benchmark_scores.count_absent_as_failures`); elsewhere
    those frames are left out.

    Parameters
    ----------
    runs:
        Runs of any trackers on any sequences (repeats marked by ``RunOutcome.repeat``).
    gts:
        ``{sequence: (n, 4) ground truth}``.
    missing:
        Convention for frames without a box (:func:`scored_boxes`).
    reference:
        Tracker whose speed ``fps_ratio`` divides by (NaN if it was not run).

    Returns
    -------
    dict
        ``{"results": {tracker: {sequence: {"runs": [...], "mean": {...}}}},
        "summary": {tracker: {...}}}``.  Per-sequence ``mean`` holds the mean over repeats of
        every figure with ``<figure>_std`` (population standard deviation) beside it, and the
        mean curves.  The tracker ``summary`` is the mean over sequences (each sequence weighs
        the same, as in OTB's overall plots), computed per repeat and then reported as mean
        and standard deviation over the repeats; ``fps`` is all timed updates over all their
        time, ``fps_ratio`` that over the reference's.
    """
    grouped = _group(runs)
    results: dict[str, Any] = {}
    summary: dict[str, Any] = {}

    def figures(run: RunOutcome, seq_name: str) -> dict[str, Any]:
        res = ope_metrics(run_boxes(run, missing), gts[seq_name])
        if seq_name in absent_fail:
            res = count_absent_as_failures(res)
        fig = res.to_dict()
        fig["n_lost"] = run.n_lost
        return fig

    def seq_mean(per_run: list[dict[str, Any]]) -> dict[str, Any]:
        mean = _seq_summary(per_run, OPE_SCALARS + SPEED_SCALARS)
        for key in ("success_curve", "precision_curve", "norm_precision_curve"):
            mean[key] = _mean_curve([r[key] for r in per_run])
        for key in ("n_frames", "n_scored", "n_missing"):
            mean[key] = per_run[0][key]
        mean["n_no_prediction"] = _stats(r["n_no_prediction"] for r in per_run)[0]
        mean["n_lost"] = _stats(r["n_lost"] for r in per_run)[0]
        return mean

    for tracker, seqs in grouped.items():
        results[tracker], per_repeat, speed = _collect(seqs, figures, seq_mean)
        overall: dict[str, list[float]] = {k: [] for k in OPE_SCALARS}
        for recs in per_repeat.values():
            for k in OPE_SCALARS:
                overall[k].append(
                    _stats(float(r[k]) if r[k] is not None else math.nan for r in recs)[0]
                )
        s: dict[str, Any] = {"n_sequences": len(seqs), "n_repeats": len(per_repeat)}
        for k in OPE_SCALARS:
            s[k], s[k + "_std"] = _stats(overall[k])
        allruns = [r for seq_res in results[tracker].values() for r in seq_res["runs"]]
        for key in ("success_curve", "precision_curve", "norm_precision_curve"):
            s[key] = _mean_curve([r[key] for r in allruns])
        s.update(speed)
        s["n_frames"] = sum(v["mean"]["n_frames"] for v in results[tracker].values())
        s["n_missing"] = sum(v["mean"]["n_missing"] for v in results[tracker].values())
        s["n_no_prediction"] = sum(
            v["mean"]["n_no_prediction"] for v in results[tracker].values()
        )
        s["n_lost"] = sum(v["mean"]["n_lost"] for v in results[tracker].values())
        s["errors"] = sum(v["mean"]["errors"] for v in results[tracker].values())
        summary[tracker] = s
    _add_fps_ratio(summary, reference)
    return {"results": results, "summary": summary}


def _add_fps_ratio(summary: dict[str, Any], reference: str) -> None:
    base = summary.get(reference, {}).get("fps", math.nan)
    for s in summary.values():
        s["fps_ratio"] = s["fps"] / base if base and base > 0 else math.nan


def score_vot(runs: Sequence[RunOutcome], reference: str = "opencv:MIL") -> dict[str, Any]:
    """Gather VOT supervised runs per run, per (tracker, sequence) and per tracker.

    Parameters
    ----------
    runs:
        Runs made with the VOT protocol (``RunOutcome.vot`` set, or ``error`` set).
    reference:
        Tracker whose speed ``fps_ratio`` divides by.

    Returns
    -------
    dict
        Like :func:`score_ope`.  The tracker ``summary`` has ``accuracy`` (mean over sequences
        of the per-sequence accuracy), ``failures`` (total over sequences),
        ``failures_per_sequence``, ``robustness`` ``exp(-100 * failures / frames)`` over all
        frames, each as mean and standard deviation over the repeats, and ``fps``.
    """
    grouped = _group(runs)
    results: dict[str, Any] = {}
    summary: dict[str, Any] = {}

    def figures(run: RunOutcome, seq_name: str) -> dict[str, Any]:
        if run.vot is not None:
            return dict(run.vot)
        return {
            "accuracy": None,
            "failures": None,
            "robustness": None,
            "failures_per_100": None,
            "n_frames": int(run.boxes.shape[0]),
        }

    def seq_mean(per_run: list[dict[str, Any]]) -> dict[str, Any]:
        mean = _seq_summary(per_run, VOT_SCALARS + SPEED_SCALARS)
        mean["n_frames"] = per_run[0]["n_frames"]
        return mean

    for tracker, seqs in grouped.items():
        results[tracker], per_repeat, speed = _collect(seqs, figures, seq_mean)
        acc: list[float] = []
        fails: list[float] = []
        fps_seq: list[float] = []
        rob: list[float] = []
        for recs in per_repeat.values():
            acc.append(
                _stats(
                    float(r["accuracy"]) if r["accuracy"] is not None else math.nan for r in recs
                )[0]
            )
            f = [r["failures"] for r in recs if r["failures"] is not None]
            frames = sum(r["n_frames"] for r in recs if r["failures"] is not None)
            fails.append(float(sum(f)))
            fps_seq.append(float(sum(f)) / len(f) if f else math.nan)
            rob.append(math.exp(-100.0 * sum(f) / frames) if frames else math.nan)
        s: dict[str, Any] = {"n_sequences": len(seqs), "n_repeats": len(per_repeat)}
        s["accuracy"], s["accuracy_std"] = _stats(acc)
        s["failures"], s["failures_std"] = _stats(fails)
        s["failures_per_sequence"], s["failures_per_sequence_std"] = _stats(fps_seq)
        s["robustness"], s["robustness_std"] = _stats(rob)
        s.update(speed)
        s["n_frames"] = sum(v["mean"]["n_frames"] for v in results[tracker].values())
        s["errors"] = sum(v["mean"]["errors"] for v in results[tracker].values())
        summary[tracker] = s
    _add_fps_ratio(summary, reference)
    return {"results": results, "summary": summary}


