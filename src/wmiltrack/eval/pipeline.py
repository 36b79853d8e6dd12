"""``wmiltrack eval``: benchmark trackers on an OTB-layout dataset (OPE or VOT protocol).

Usage::

    wmiltrack eval DATASET --trackers rcwmil,fct,opencv:MIL --out DIR [-j N] [--repeats R]
                   [--protocol ope|vot] [--sequences A,B] [--seed S]
    wmiltrack eval DATASET --results BOXDIR --out DIR      # score another tracker's files

``DATASET`` is a folder of OTB sequence folders (``<Seq>/img/`` + ``groundtruth_rect.txt``,
optionally ``start.txt``) or one such sequence folder.

Protocols
---------
``ope`` (one-pass evaluation, OTB)
    Each tracker starts from the first ground-truth box and runs to the end.  Scores from
    :func:`wmiltrack.eval.metrics.ope_metrics`: success curve (IoU > t, t = 0, 0.05, ..., 1), its
    AUC (mean of the 21 points), success rate at 0.5, precision at 20 px (error <= t),
    normalised precision at 0.2, mean centre error.  Frames whose ground truth is missing
    (NaN or non-positive size) are left out of every figure and counted ("GT missing").
``vot`` (supervised, VOT2015)
    :func:`wmiltrack.eval.vot_style.run_supervised`: failure when the overlap drops to 0,
    re-initialisation 5 frames later, accuracy without the 10 frames after each
    (re)initialisation; failures per sequence and robustness ``exp(-100 F / N)``.

Speed
-----
Update-only frames per second on frames decoded before timing (``tracker.update`` alone is
inside the clock) and the time of ``init``.  Sequences run in parallel processes with
``-j N``; on a machine with few cores the processes compete for them (and for memory
bandwidth), so FPS measured with ``-j`` > 1 is lower and noisier than with ``-j 1``, which
gives the most honest speed figures.

Repeats
-------
``--repeats R`` runs every (tracker, sequence) R times with seeds ``seed, seed+1, ...``;
figures are reported as mean ± standard deviation (population, ``ddof=0``) over the repeats.

Outputs in ``--out DIR``
------------------------
``eval_<protocol>.md`` (table), ``eval_<protocol>.json`` (every figure per tracker and
sequence, per repeat), ``success_ope.png`` and ``precision_ope.png`` (OPE), and the boxes:
``boxes/<tracker>/<seq>.txt`` (OPE; repeat ``k`` > 0 in ``<seq>.r<k>.txt``) or
``boxes_vot/...`` (VOT; NaN rows on frames not tracked).  Tracker names are made
filesystem-safe (``opencv:MIL`` -> ``opencv_MIL``).  ``--results DIR`` reads exactly this
layout (``DIR/<tracker>/<seq>.txt``), e.g. ``--results OUT/boxes``.
"""

from __future__ import annotations

import json
import math
import os
import re
import sys
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from concurrent.futures import Future, ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field
from multiprocessing import get_context
from pathlib import Path
from typing import Any, Literal

import numpy as np
import numpy.typing as npt

from ..engine.result import TrackerLike, TrackResult
from .metrics import (
    PRECISION_THRESHOLDS,
    SUCCESS_THRESHOLDS,
    ope_metrics,
    valid_mask,
)
from .peers import TrackerUnavailable
from .runner import environment, json_safe

__all__ = [
    "RunOutcome",
    "run_eval",
    "safe_name",
    "score_ope",
    "score_vot",
]

FloatArray = npt.NDArray[np.float64]
Frame = npt.NDArray[np.uint8]
Subparsers = Any
Protocol = Literal["ope", "vot"]

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

_UNSAFE = re.compile(r"[^A-Za-z0-9._+-]")


def safe_name(name: str) -> str:
    """Make a tracker name usable as a folder name (``opencv:MIL`` -> ``opencv_MIL``).

    Parameters
    ----------
    name:
        Tracker name.

    Returns
    -------
    str
        ``name`` with every character outside ``[A-Za-z0-9._+-]`` replaced by ``_``.
    """
    out = _UNSAFE.sub("_", name.strip())
    return out if out not in ("", ".", "..") else "_" + out


# ----------------------------------------------------------------------------- running
@dataclass(frozen=True)
class RunOutcome:
    """One tracker run on one sequence (one repeat), as returned by a worker.

    Attributes
    ----------
    tracker, sequence:
        Names.
    repeat, seed:
        Repeat index and the tracker seed it used.
    boxes:
        ``(n, 4)`` boxes, one per ground-truth frame (NaN where the tracker gave none or, with
        the VOT protocol, did not run).
    fps:
        Update-only frames per second (NaN when not timed, e.g. ``--results``).
    init_time:
        Seconds in ``init`` (mean over the initialisations for VOT).
    median_update_time:
        Median seconds per ``update``.
    n_updates:
        Number of timed updates.
    error:
        ``"<Exception>: <message>"`` if the tracker raised, else ``None``.
    vot:
        :meth:`wmiltrack.eval.vot_style.SupervisedResult.to_dict` for the VOT protocol.
    """

    tracker: str
    sequence: str
    repeat: int
    seed: int
    boxes: FloatArray = field(repr=False)
    fps: float = math.nan
    init_time: float = math.nan
    median_update_time: float = math.nan
    n_updates: int = 0
    error: str | None = None
    vot: dict[str, Any] | None = field(default=None, repr=False)


@dataclass(frozen=True)
class _Task:
    path: str
    trackers: tuple[str, ...]
    seeds: tuple[int, ...]
    protocol: str
    skip: int
    burnin: int
    cv_threads: int | None


@dataclass(frozen=True)
class _SeqOutcome:
    name: str
    gt: FloatArray
    runs: tuple[RunOutcome, ...]


class _TimedTracker:
    """Wraps a tracker and adds up the time spent in ``init`` and ``update``."""

    def __init__(self, inner: TrackerLike, init_times: list[float], update_times: list[float]):
        self.inner = inner
        self.init_times = init_times
        self.update_times = update_times

    def init(self, frame: Frame, box: tuple[float, float, float, float]) -> object:
        t0 = time.perf_counter()
        out = self.inner.init(frame, box)
        self.init_times.append(time.perf_counter() - t0)
        return out

    def update(self, frame: Frame) -> TrackResult:
        t0 = time.perf_counter()
        r = self.inner.update(frame)
        self.update_times.append(time.perf_counter() - t0)
        return r


def _first_valid(gt: FloatArray) -> int:
    idx = np.flatnonzero(valid_mask(gt))
    if idx.size == 0:
        raise ValueError("no frame has a valid ground-truth box")
    return int(idx[0])


def _run_ope(
    spec: str, seq_name: str, frames: Sequence[Frame], gt: FloatArray, repeat: int, seed: int
) -> RunOutcome:
    import warnings

    from .runner import run_sequence

    start = _first_valid(gt)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # the error is recorded instead
        run = run_sequence(spec, frames[start:], gt[start], seed=seed)
    boxes = np.full((len(frames), 4), np.nan)
    boxes[start:] = run.boxes
    return RunOutcome(
        tracker=spec,
        sequence=seq_name,
        repeat=repeat,
        seed=seed,
        boxes=boxes,
        fps=run.fps,
        init_time=run.init_time,
        median_update_time=run.median_update_time,
        n_updates=run.n_updates,
        error=None
        if run.error is None
        else f"{run.error} (frame {start + (run.error_frame or 0)})",
    )


def _run_vot(
    spec: str,
    seq_name: str,
    frames: Sequence[Frame],
    gt: FloatArray,
    repeat: int,
    seed: int,
    skip: int,
    burnin: int,
) -> RunOutcome:
    import gc

    from .peers import make_tracker
    from .vot_style import run_supervised

    init_times: list[float] = []
    update_times: list[float] = []

    def factory() -> TrackerLike:
        return _TimedTracker(make_tracker(spec, seed=seed), init_times, update_times)

    gc.collect()
    error: str | None = None
    try:
        res = run_supervised(factory, frames, gt, skip=skip, burnin=burnin)
    except Exception as exc:  # noqa: BLE001 - recorded, like evaluation.run_sequence does
        error = f"{type(exc).__name__}: {exc}"
        return RunOutcome(
            spec, seq_name, repeat, seed, np.full((len(frames), 4), np.nan), error=error
        )
    total = float(sum(update_times))
    n = len(update_times)
    return RunOutcome(
        tracker=spec,
        sequence=seq_name,
        repeat=repeat,
        seed=seed,
        boxes=res.boxes,
        fps=n / total if n and total > 0 else math.nan,
        init_time=float(np.mean(init_times)) if init_times else math.nan,
        median_update_time=float(np.median(update_times)) if update_times else math.nan,
        n_updates=n,
        vot=res.to_dict(),
    )


def _worker_init(cv_threads: int | None) -> None:
    if cv_threads is not None:
        import cv2

        cv2.setNumThreads(cv_threads)


def _run_task(task: _Task) -> _SeqOutcome:
    """Run every tracker and repeat on one sequence (in a worker process or in-process)."""
    from ..data.sequences import load_otb_sequence

    seq = load_otb_sequence(task.path)
    if seq.groundtruth is None:  # pragma: no cover - the OTB loader always reads it
        raise ValueError(f"{task.path}: no ground truth")
    gt = np.asarray(seq.groundtruth, dtype=np.float64)
    frames = seq.load()  # decoded before any clock starts
    runs: list[RunOutcome] = []
    # repeats outermost, trackers interleaved within a round: drifts of the machine hit all
    for r, seed in enumerate(task.seeds):
        for spec in task.trackers:
            if task.protocol == "vot":
                runs.append(_run_vot(spec, seq.name, frames, gt, r, seed, task.skip, task.burnin))
            else:
                runs.append(_run_ope(spec, seq.name, frames, gt, r, seed))
    return _SeqOutcome(seq.name, gt, tuple(runs))


def _execute(tasks: Sequence[_Task], jobs: int, show_progress: bool) -> list[_SeqOutcome]:
    from ..progress import progress

    enabled = None if show_progress else False
    if jobs <= 1 or len(tasks) <= 1:
        _worker_init(tasks[0].cv_threads if tasks else None)
        return list(
            progress((_run_task(t) for t in tasks), total=len(tasks), desc="eval", enabled=enabled)
        )
    out: list[_SeqOutcome] = []
    # spawn, not fork: OpenCV's thread pool does not survive a fork reliably
    with ProcessPoolExecutor(
        max_workers=min(jobs, len(tasks)),
        mp_context=get_context("spawn"),
        initializer=_worker_init,
        initargs=(tasks[0].cv_threads,),
    ) as pool:
        futures: list[Future[_SeqOutcome]] = [pool.submit(_run_task, t) for t in tasks]
        for fut in progress(
            as_completed(futures), total=len(futures), desc="eval", enabled=enabled
        ):
            out.append(fut.result())
    order = {Path(t.path).name: i for i, t in enumerate(tasks)}
    out.sort(key=lambda s: order.get(s.name, 0))
    return out


# ----------------------------------------------------------------------------- scoring
def _stats(values: Iterable[float]) -> tuple[float, float]:
    arr = np.asarray(list(values), dtype=np.float64)
    arr = arr[np.isfinite(arr)]
    if arr.size == 0:
        return math.nan, math.nan
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
    missing: Literal["miss", "hold"] = "miss",
) -> dict[str, Any]:
    """Score OPE runs: figures per run, per (tracker, sequence) and per tracker.

    Parameters
    ----------
    runs:
        Runs of any trackers on any sequences (repeats marked by ``RunOutcome.repeat``).
    gts:
        ``{sequence: (n, 4) ground truth}``.
    missing:
        How frames without a predicted box are scored (see :func:`ope_metrics`).

    Returns
    -------
    dict
        ``{"results": {tracker: {sequence: {"runs": [...], "mean": {...}}}},
        "summary": {tracker: {...}}}``.  Per-sequence ``mean`` holds the mean over repeats of
        every figure with ``<figure>_std`` (population standard deviation) beside it, and the
        mean curves.  The tracker ``summary`` is the mean over sequences (each sequence weighs
        the same, as in OTB's overall plots), computed per repeat and then reported as mean
        and standard deviation over the repeats; ``fps`` is all timed updates over all their
        time.
    """
    grouped = _group(runs)
    results: dict[str, Any] = {}
    summary: dict[str, Any] = {}

    def figures(run: RunOutcome, seq_name: str) -> dict[str, Any]:
        return ope_metrics(run.boxes, gts[seq_name], missing=missing).to_dict()

    def seq_mean(per_run: list[dict[str, Any]]) -> dict[str, Any]:
        mean = _seq_summary(per_run, OPE_SCALARS + SPEED_SCALARS)
        for key in ("success_curve", "precision_curve", "norm_precision_curve"):
            mean[key] = _mean_curve([r[key] for r in per_run])
        for key in ("n_frames", "n_scored", "n_missing"):
            mean[key] = per_run[0][key]
        mean["n_no_prediction"] = _stats(r["n_no_prediction"] for r in per_run)[0]
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
        s["errors"] = sum(v["mean"]["errors"] for v in results[tracker].values())
        summary[tracker] = s
    return {"results": results, "summary": summary}


def score_vot(runs: Sequence[RunOutcome]) -> dict[str, Any]:
    """Gather VOT supervised runs per run, per (tracker, sequence) and per tracker.

    Parameters
    ----------
    runs:
        Runs made with the VOT protocol (``RunOutcome.vot`` set, or ``error`` set).

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
    return {"results": results, "summary": summary}


# ----------------------------------------------------------------------------- tables
def _f(v: Any, spec: str) -> str:
    if v is None:
        return "-"
    x = float(v)
    return "-" if math.isnan(x) else format(x, spec)


def _pm(d: Mapping[str, Any], key: str, spec: str, repeats: int) -> str:
    text = _f(d.get(key), spec)
    std = d.get(key + "_std")
    if repeats > 1 and text != "-" and std is not None and not math.isnan(float(std)):
        text += " ± " + format(float(std), spec)
    return text


def _ms(v: Any) -> str:
    return _f(None if v is None else float(v) * 1000.0, ".1f")


def _markdown(
    headers: Sequence[str], rows: Sequence[Sequence[str]], bold_rows: Sequence[Sequence[str]]
) -> list[str]:
    lines = ["| " + " | ".join(headers) + " |", "|" + "|".join(["---"] * len(headers)) + "|"]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    lines += ["| **" + r[0] + "** | " + " | ".join(r[1:]) + " |" for r in bold_rows]
    return lines


def format_ope_table(scored: Mapping[str, Any], repeats: int, timed: bool) -> str:
    """Markdown table of :func:`score_ope`'s output with a mean row per tracker.

    Parameters
    ----------
    scored:
        Output of :func:`score_ope`.
    repeats:
        Number of repeats (``> 1`` adds ``± std``).
    timed:
        Include the FPS and initialisation-time columns.

    Returns
    -------
    str
    """
    headers = [
        "Sequence",
        "Tracker",
        "Frames",
        "GT missing",
        "AUC",
        "SR@0.5",
        "P@20",
        "NP@0.2",
        "CLE px",
        "No box",
    ]
    if timed:
        headers += ["FPS", "Init ms"]
    rows: list[list[str]] = []
    results = scored["results"]
    seqs: list[str] = []
    for tr in results.values():
        seqs += [s for s in tr if s not in seqs]
    for seq in seqs:
        for tracker, tr in results.items():
            if seq not in tr:
                continue
            m = tr[seq]["mean"]
            row = [
                seq,
                tracker + (" (!)" if m["errors"] else ""),
                str(m["n_frames"]),
                str(m["n_missing"]),
                _pm(m, "auc", ".3f", repeats),
                _pm(m, "success_50", ".3f", repeats),
                _pm(m, "precision_20", ".3f", repeats),
                _pm(m, "norm_precision_20", ".3f", repeats),
                _pm(m, "mean_center_error", ".1f", repeats),
                _f(m["n_no_prediction"], ".0f"),
            ]
            if timed:
                row += [_pm(m, "fps", ".1f", repeats), _ms(m["init_time"])]
            rows.append(row)
    bold: list[list[str]] = []
    for tracker, s in scored["summary"].items():
        no_box = sum(float(v["mean"]["n_no_prediction"]) for v in results[tracker].values())
        row = [
            f"mean ({s['n_sequences']} seq)",
            tracker + (" (!)" if s["errors"] else ""),
            str(s["n_frames"]),
            str(s["n_missing"]),
            _pm(s, "auc", ".3f", repeats),
            _pm(s, "success_50", ".3f", repeats),
            _pm(s, "precision_20", ".3f", repeats),
            _pm(s, "norm_precision_20", ".3f", repeats),
            _pm(s, "mean_center_error", ".1f", repeats),
            _f(no_box, ".0f"),
        ]
        if timed:
            row += [_f(s["fps"], ".1f"), _ms(s["init_time"])]
        bold.append(row)
    notes = [
        "",
        (
            "AUC: mean of the success curve at IoU thresholds 0, 0.05, ..., 1 (IoU > t). "
            "SR@0.5: IoU > 0.5. P@20: centre error <= 20 px. NP@0.2: centre error divided by "
            "the ground-truth size per axis <= 0.2. CLE: mean centre error over frames with a "
            "box. GT missing: frames whose ground truth is absent or degenerate, left out of "
            "every figure. No box: scored frames where the tracker gave no box (scored as "
            "misses)."
        ),
    ]
    if timed:
        notes.append(
            "FPS: update-only frames per second on pre-decoded frames (mean rows: all "
            "updates / all update time). Init ms: time of init(). With -j > 1 the processes "
            "share the cores, so speed is best measured with -j 1."
        )
    notes += _run_notes(results, repeats, "(!) tracker errors (remaining frames scored as misses):")
    return "\n".join(_markdown(headers, rows, bold) + notes) + "\n"


def _run_notes(results: Mapping[str, Any], repeats: int, error_title: str) -> list[str]:
    """Table notes shared by the OPE and VOT tables: repeats, then any tracker errors."""
    notes = []
    if repeats > 1:
        notes.append(f"{repeats} repeats with different seeds: mean ± standard deviation.")
    errs = [
        (t, sq, r["error"])
        for t, tr in results.items()
        for sq, v in tr.items()
        for r in v["runs"]
        if r.get("error")
    ]
    if errs:
        notes.append(error_title)
        notes += [f"  {t} on {sq}: {e}" for t, sq, e in errs]
    return notes


def format_vot_table(
    scored: Mapping[str, Any], repeats: int, skip: int = 5, burnin: int = 10
) -> str:
    """Markdown table of :func:`score_vot`'s output with a summary row per tracker.

    Parameters
    ----------
    scored:
        Output of :func:`score_vot`.
    repeats:
        Number of repeats (``> 1`` adds ``± std``).
    skip, burnin:
        The protocol's settings, for the notes.

    Returns
    -------
    str
    """
    headers = [
        "Sequence",
        "Tracker",
        "Frames",
        "Accuracy",
        "Failures",
        "Robustness",
        "FPS",
        "Init ms",
    ]
    results = scored["results"]
    seqs: list[str] = []
    for tr in results.values():
        seqs += [s for s in tr if s not in seqs]
    rows: list[list[str]] = []
    for seq in seqs:
        for tracker, tr in results.items():
            if seq not in tr:
                continue
            m = tr[seq]["mean"]
            rows.append(
                [
                    seq,
                    tracker + (" (!)" if m["errors"] else ""),
                    str(m["n_frames"]),
                    _pm(m, "accuracy", ".3f", repeats),
                    _pm(m, "failures", ".1f", repeats),
                    _pm(m, "robustness", ".3f", repeats),
                    _pm(m, "fps", ".1f", repeats),
                    _ms(m["init_time"]),
                ]
            )
    bold: list[list[str]] = []
    for tracker, s in scored["summary"].items():
        fails = (
            _pm(s, "failures", ".1f", repeats)
            + " ("
            + _pm(s, "failures_per_sequence", ".2f", repeats)
            + "/seq)"
        )
        bold.append(
            [
                f"all ({s['n_sequences']} seq)",
                tracker + (" (!)" if s["errors"] else ""),
                str(s["n_frames"]),
                _pm(s, "accuracy", ".3f", repeats),
                fails,
                _pm(s, "robustness", ".3f", repeats),
                _f(s["fps"], ".1f"),
                _ms(s["init_time"]),
            ]
        )
    notes = [
        "",
        (
            "VOT2015 supervised protocol: failure = overlap 0 with the ground truth; the "
            f"tracker is re-initialised {skip} frames later; accuracy = mean overlap leaving "
            f"out the {burnin} frames from each (re)initialisation; robustness = "
            "exp(-100 * failures / frames) (VOT2016 reliability). Summary rows: accuracy = "
            "mean over sequences, failures = total (per sequence in brackets). FPS: "
            "update-only, frames decoded before timing."
        ),
    ]
    notes += _run_notes(results, repeats, "(!) tracker errors:")
    return "\n".join(_markdown(headers, rows, bold) + notes) + "\n"


# ----------------------------------------------------------------------------- I/O
def _box_path(root: Path, tracker: str, seq: str, repeat: int) -> Path:
    suffix = "" if repeat == 0 else f".r{repeat}"
    return root / safe_name(tracker) / f"{seq}{suffix}.txt"


def _write_boxes(root: Path, runs: Iterable[RunOutcome]) -> None:
    from ..data.boxes import write_boxes

    for r in runs:
        write_boxes(_box_path(root, r.tracker, r.sequence, r.repeat), r.boxes)


def _read_results(
    results_dir: Path, gts: Mapping[str, FloatArray], notes: list[str]
) -> list[RunOutcome]:
    """Box files ``results_dir/<tracker>/<seq>[.r<k>].txt`` as runs (untimed)."""
    from ..data.boxes import read_boxes

    if not results_dir.is_dir():
        raise FileNotFoundError(f"results folder not found: {results_dir}")
    pattern = re.compile(r"^(?P<seq>.+?)(?:\.r(?P<rep>\d+))?\.txt$")
    runs: list[RunOutcome] = []
    for tdir in sorted(p for p in results_dir.iterdir() if p.is_dir()):
        found = 0
        for f in sorted(tdir.glob("*.txt")):
            m = pattern.match(f.name)
            if m is None or m.group("seq") not in gts:
                continue
            seq = m.group("seq")
            gt = gts[seq]
            boxes = read_boxes(f)
            if len(boxes) > len(gt):
                notes.append(
                    f"{tdir.name}/{f.name}: {len(boxes)} boxes for {len(gt)} "
                    f"ground-truth frames; scoring the first {len(gt)}"
                )
                boxes = boxes[: len(gt)]
            elif len(boxes) < len(gt):
                notes.append(
                    f"{tdir.name}/{f.name}: only {len(boxes)} boxes for {len(gt)} "
                    "ground-truth frames; skipped"
                )
                continue
            rep = int(m.group("rep") or 0)
            runs.append(RunOutcome(tdir.name, seq, rep, rep, boxes))
            found += 1
        missing = sorted(set(gts) - {r.sequence for r in runs if r.tracker == tdir.name})
        if found and missing:
            notes.append(f"{tdir.name}: no box file for {', '.join(missing)}")
    if not runs:
        raise FileNotFoundError(
            f"no box files <tracker>/<sequence>.txt for the dataset's sequences under {results_dir}"
        )
    return runs


def _sequence_paths(dataset: Path, names: Sequence[str] | None) -> list[Path]:
    from ..data.sequences import GT_FILE, list_otb_sequences

    if (dataset / "img").is_dir() and (dataset / GT_FILE).is_file():
        paths = [dataset]
    else:
        paths = list_otb_sequences(dataset)
    if names:
        by_name = {p.name: p for p in paths}
        missing = [n for n in names if n not in by_name]
        if missing:
            raise FileNotFoundError(
                f"sequence(s) not found: {', '.join(missing)}; available: "
                f"{', '.join(sorted(by_name))}"
            )
        paths = [by_name[n] for n in names]
    if not paths:
        raise FileNotFoundError(
            f"no OTB sequence folder (img/ + groundtruth_rect.txt) in {dataset}"
        )
    return paths


def _ground_truths(paths: Sequence[Path]) -> dict[str, FloatArray]:
    from ..data.sequences import load_otb_sequence

    out: dict[str, FloatArray] = {}
    for p in paths:
        seq = load_otb_sequence(p)  # applies start.txt and cuts to the annotated frames
        assert seq.groundtruth is not None
        out[seq.name] = np.asarray(seq.groundtruth, dtype=np.float64)
    return out


def _check_trackers(specs: Sequence[str], notes: list[str]) -> list[str]:
    from .peers import make_tracker

    ok: list[str] = []
    for spec in specs:
        try:
            make_tracker(spec)
        except TrackerUnavailable as exc:
            notes.append(f"skipped {spec}: {str(exc).split('. ')[0]}")
            continue
        if spec not in ok:
            ok.append(spec)
    return ok


def run_eval(
    dataset: str | os.PathLike[str],
    out: str | os.PathLike[str],
    *,
    trackers: Sequence[str] = ("rcwmil",),
    results: str | os.PathLike[str] | None = None,
    protocol: Protocol = "ope",
    sequences: Sequence[str] | None = None,
    jobs: int = 1,
    repeats: int = 1,
    seed: int = 0,
    skip: int = 5,
    burnin: int = 10,
    missing: Literal["miss", "hold"] = "miss",
    plots: bool = True,
    cv_threads: int | None = None,
    show_progress: bool = True,
    log: Callable[[str], None] | None = None,
) -> dict[str, Any]:
    """Run (or read) and score trackers on a dataset; write the table, JSON, plots and boxes.

    Parameters
    ----------
    dataset:
        Folder of OTB sequence folders, or one sequence folder.
    out:
        Output folder (created).
    trackers:
        Tracker names (``rcwmil``, ``fct``, ``opencv:CSRT``...); unavailable OpenCV trackers
        are skipped with a note.  Ignored with ``results``.
    results:
        Folder ``<tracker>/<seq>.txt`` of boxes to score instead of running trackers (OPE).
    protocol:
        ``"ope"`` or ``"vot"``.
    sequences:
        Names to use (default: all).
    jobs:
        Worker processes (sequences in parallel).
    repeats:
        Runs per (tracker, sequence), seeds ``seed .. seed + repeats - 1``.
    seed:
        First seed.
    skip, burnin:
        VOT re-initialisation delay and accuracy burn-in.
    missing:
        OPE scoring of frames without a predicted box.
    plots:
        Write the success and precision plots (OPE).
    cv_threads:
        ``cv2.setNumThreads`` in the workers.
    show_progress:
        Progress bar on stderr.
    log:
        Receives notes (skipped trackers, odd files); default prints to stderr.

    Returns
    -------
    dict
        The JSON document written to ``eval_<protocol>.json``, plus ``"files"``: paths
        written.

    Raises
    ------
    ValueError
        Bad arguments (``repeats < 1``, ``--results`` with VOT, no usable tracker).
    FileNotFoundError
        Missing dataset, sequences or result files.
    RuntimeError
        matplotlib missing while plots are wanted (the message says how to install it).
    """
    say = log if log is not None else (lambda s: print(s, file=sys.stderr))
    if repeats < 1:
        raise ValueError(f"--repeats must be at least 1, got {repeats}")
    if jobs < 1:
        raise ValueError(f"-j must be at least 1, got {jobs}")
    if protocol not in ("ope", "vot"):
        raise ValueError(f"protocol must be 'ope' or 'vot', not {protocol!r}")
    if results is not None and protocol == "vot":
        raise ValueError(
            "--results scores box files with the OPE protocol; the VOT protocol "
            "re-initialises the tracker, so it has to run it"
        )
    want_plots = plots and protocol == "ope"
    if want_plots:
        from .plots import require_matplotlib

        require_matplotlib()  # fail before a long run, not after it
    dataset_p = Path(dataset)
    out_p = Path(out)
    paths = _sequence_paths(dataset_p, sequences)
    notes: list[str] = []
    seeds = tuple(seed + r for r in range(repeats))
    t_start = time.perf_counter()

    if results is not None:
        gts = _ground_truths(paths)
        runs = _read_results(Path(results), gts, notes)
        timed = False
        tracker_names = list(dict.fromkeys(r.tracker for r in runs))
        n_repeats = 1 + max(r.repeat for r in runs)
    else:
        specs = [t.strip() for t in trackers if t.strip()]
        tracker_names = _check_trackers(specs, notes)
        for n in notes:
            say(n)
        if not tracker_names:
            raise ValueError("no tracker left to run")
        tasks = [
            _Task(str(p), tuple(tracker_names), seeds, protocol, skip, burnin, cv_threads)
            for p in paths
        ]
        outcomes = _execute(tasks, jobs, show_progress)
        gts = {o.name: o.gt for o in outcomes}
        runs = [r for o in outcomes for r in o.runs]
        timed = True
        n_repeats = repeats
    wall = time.perf_counter() - t_start

    out_p.mkdir(parents=True, exist_ok=True)
    files: dict[str, str] = {}
    if protocol == "ope":
        scored = score_ope(runs, gts, missing=missing)
        table = format_ope_table(scored, n_repeats, timed)
    else:
        scored = score_vot(runs)
        table = format_vot_table(scored, n_repeats, skip, burnin)
    if notes:
        table += "\nNotes:\n" + "".join(f"- {n}\n" for n in notes)

    if results is None:
        box_root = out_p / ("boxes" if protocol == "ope" else "boxes_vot")
        _write_boxes(box_root, runs)
        files["boxes"] = str(box_root)
    if want_plots:
        from .plots import plot_precision, plot_success

        summ = scored["summary"]
        n_seq = len(gts)
        succ = out_p / "success_ope.png"
        prec = out_p / "precision_ope.png"
        plot_success(
            {t: s["success_curve"] for t, s in summ.items()},
            {t: s["auc"] for t, s in summ.items()},
            succ,
            title=f"Success plots of OPE ({n_seq} sequences)",
        )
        plot_precision(
            {t: s["precision_curve"] for t, s in summ.items()},
            {t: s["precision_20"] for t, s in summ.items()},
            prec,
            title=f"Precision plots of OPE ({n_seq} sequences)",
        )
        files["success_plot"] = str(succ)
        files["precision_plot"] = str(prec)

    table_path = out_p / f"eval_{protocol}.md"
    json_path = out_p / f"eval_{protocol}.json"
    table_path.write_text(table, encoding="utf-8")
    files["table"] = str(table_path)
    files["json"] = str(json_path)
    doc: dict[str, Any] = {
        "protocol": protocol,
        "dataset": str(dataset_p.resolve()),
        "sequences": list(gts),
        "trackers": tracker_names,
        "box_folders": {t: safe_name(t) for t in tracker_names},
        "repeats": n_repeats,
        "seeds": list(seeds) if results is None else None,
        "source": "run" if results is None else f"results:{Path(results).resolve()}",
        "settings": {
            "jobs": jobs,
            "missing": missing,
            "skip": skip,
            "burnin": burnin,
            "cv_threads": cv_threads,
            "success_thresholds": [float(t) for t in SUCCESS_THRESHOLDS],
            "precision_thresholds": [float(t) for t in PRECISION_THRESHOLDS],
            "std": "population (ddof=0) over repeats",
        },
        "environment": environment(),
        "wall_time": wall,
        "notes": notes,
        "summary": scored["summary"],
        "results": scored["results"],
        "files": files,
    }
    json_path.write_text(json.dumps(json_safe(doc), indent=1, allow_nan=False), encoding="utf-8")
    return doc
