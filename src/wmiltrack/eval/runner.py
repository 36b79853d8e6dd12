"""Run trackers on sequences, score them (OTB one-pass) and time them honestly.

Timing rules
------------
* Frames are decoded before any clock starts; the trackers get the same in-memory arrays.
* ``time.perf_counter()`` is read right before and after each ``update`` call, and nothing
  else is inside the interval.  ``init`` is timed separately (``init_time``), and creating the
  tracker object is not timed.
* Python's garbage collector is run before a sequence and disabled during the timed loop
  (as :mod:`timeit` does), so a collection does not land on one tracker's update.
* ``fps`` is *update-only* throughput: ``updates / sum(update times)``.  The median
  per-update time is kept too (``median_update_time``), being robust to a slow outlier.
* With ``repeats > 1`` every (tracker, sequence) pair is run that many times, the trackers
  interleaved within each round so that slow drifts of the machine hit all of them alike;
  the reported FPS is the median over the rounds.  Boxes and scores come from the first
  round, and ``deterministic`` records whether every round gave the same boxes.
* If a tracker raises, the exception is recorded in ``RunResult.error`` (type, message and
  frame index) and shown in the tables; the remaining frames have NaN boxes and so count as
  misses.  Nothing is swallowed silently: a :class:`RuntimeWarning` is issued as well, and
  ``raise_errors=True`` re-raises instead.
"""

from __future__ import annotations

import gc
import math
import operator
import os
import platform
import time
import traceback
import warnings
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal, Protocol

import numpy as np
import numpy.typing as npt

from ..engine.result import TrackerLike
from .metrics import OPEResult, ope_metrics
from .peers import make_tracker

__all__ = [
    "EvalRecord",
    "RunResult",
    "SequenceLike",
    "cpu_model",
    "environment",
    "evaluate_sequences",
    "format_table",
    "fps_ratio",
    "json_safe",
    "run_sequence",
    "summarize",
]

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]
Frame = npt.NDArray[np.uint8]
TrackerSpec = str | Callable[[], TrackerLike]


class SequenceLike(Protocol):
    """What :func:`evaluate_sequences` needs of a sequence (``wmiltrack.data.sequences.Sequence``)."""

    @property
    def name(self) -> str:
        """Sequence name."""
        ...

    @property
    def groundtruth(self) -> npt.NDArray[np.float64] | None:
        """``(n, 4)`` ground-truth boxes (NaN rows where absent)."""
        ...

    def load(self) -> list[Frame]:
        """All frames, decoded."""
        ...


@dataclass(frozen=True)
class RunResult:
    """One tracker run over one sequence.

    Attributes
    ----------
    tracker:
        The tracker's name (its spec).
    boxes:
        ``(n, 4)`` boxes; row 0 is the initialisation box; NaN rows after an error.
    scores:
        ``(n,)`` confidence per frame; NaN on frame 0 and where the tracker gives none.
    oks:
        ``(n,)`` the tracker's own "found" flag (True on frame 0).
    init_time:
        Seconds spent in ``init`` (NaN if it raised).
    update_times:
        ``(n,)`` seconds spent in each ``update``; NaN on frame 0 and on frames not run.
    n_updates:
        Updates that completed.
    error:
        ``None``, or ``"<ExceptionType>: <message>"`` if the tracker raised.
    error_frame:
        Frame index where it raised (0 for ``init``), else ``None``.
    traceback:
        Formatted traceback of the error, else ``None``.
    """

    tracker: str
    boxes: FloatArray = field(repr=False)
    scores: FloatArray = field(repr=False)
    oks: BoolArray = field(repr=False)
    init_time: float
    update_times: FloatArray = field(repr=False)
    n_updates: int
    error: str | None = None
    error_frame: int | None = None
    traceback: str | None = field(default=None, repr=False)

    @property
    def total_update_time(self) -> float:
        """Sum of the update times in seconds."""
        return float(np.nansum(self.update_times))

    @property
    def fps(self) -> float:
        """Update-only frames per second: ``n_updates / total_update_time`` (NaN if none)."""
        t = self.total_update_time
        return self.n_updates / t if self.n_updates > 0 and t > 0 else float("nan")

    @property
    def median_update_time(self) -> float:
        """Median seconds per update (NaN if none)."""
        t = self.update_times[~np.isnan(self.update_times)]
        return float(np.median(t)) if t.size else float("nan")

    @property
    def completed(self) -> bool:
        """True when the tracker ran to the last frame without raising."""
        return self.error is None

    def to_dict(self, per_frame: bool = False) -> dict[str, Any]:
        """JSON-serialisable summary (optionally with boxes and times per frame)."""
        d: dict[str, Any] = {
            "tracker": self.tracker,
            "n_frames": int(self.boxes.shape[0]),
            "n_updates": self.n_updates,
            "fps": _num(self.fps),
            "median_update_time": _num(self.median_update_time),
            "total_update_time": self.total_update_time,
            "init_time": _num(self.init_time),
            "error": self.error,
            "error_frame": self.error_frame,
        }
        if per_frame:
            d["boxes"] = [[_num(v) for v in row] for row in self.boxes]
            d["scores"] = [_num(v) for v in self.scores]
            d["update_times"] = [_num(v) for v in self.update_times]
        return d


def _num(v: float | np.floating[Any]) -> float | None:
    f = float(v)
    return None if math.isnan(f) else f


def _spec_name(spec: TrackerSpec) -> str:
    if isinstance(spec, str):
        return spec.strip()
    return str(getattr(spec, "name", None) or getattr(spec, "__name__", None) or repr(spec))


def _factory(
    spec: TrackerSpec, seed: int, params: Mapping[str, Any] | None
) -> Callable[[], TrackerLike]:
    if isinstance(spec, str):
        kw = dict(params or {})
        return lambda: make_tracker(spec, seed=seed, **kw)
    if params:
        raise ValueError("params can only be given with a tracker name, not a factory")
    return spec


def run_sequence(
    spec: TrackerSpec,
    frames: Sequence[Frame],
    init_box: Sequence[float] | npt.NDArray[Any],
    *,
    seed: int = 0,
    params: Mapping[str, Any] | None = None,
    raise_errors: bool = False,
) -> RunResult:
    """Run one tracker over pre-decoded frames, timing each ``update``.

    Parameters
    ----------
    spec:
        A tracker name for :func:`wmiltrack.eval.peers.make_tracker` (``"rcwmil"``,
        ``"opencv:MIL"``...) or a callable returning a new tracker.
    frames:
        The decoded frames (decode before calling: decoding is not timed).
    init_box:
        ``(x, y, w, h)`` of the target in ``frames[0]``.
    seed:
        Tracker seed (ignored for a callable spec).
    params:
        Extra tracker parameters (only with a name).
    raise_errors:
        Re-raise an exception from the tracker instead of recording it.

    Returns
    -------
    RunResult

    Raises
    ------
    ValueError
        If ``frames`` is empty or ``init_box`` is not 4 numbers.
    Exception
        Whatever creating the tracker raises (unknown name, :class:`TrackerUnavailable`...),
        and, with ``raise_errors``, whatever ``init``/``update`` raise.
    """
    n = len(frames)
    if n == 0:
        raise ValueError("no frames to track")
    box0 = np.asarray(init_box, dtype=np.float64).reshape(-1)
    if box0.shape != (4,):
        raise ValueError(f"init_box must be 4 numbers x, y, w, h; got {init_box!r}")
    name = _spec_name(spec)
    tracker = _factory(spec, seed, params)()

    boxes = np.full((n, 4), np.nan)
    scores = np.full(n, np.nan)
    oks = np.zeros(n, dtype=bool)
    times = np.full(n, np.nan)
    init_time = float("nan")
    n_updates = 0
    error: str | None = None
    error_frame: int | None = None
    tb: str | None = None

    frame_list = list(frames)
    clock = time.perf_counter
    gc.collect()
    was_enabled = gc.isenabled()
    gc.disable()
    i = 0
    try:
        box_tuple = (float(box0[0]), float(box0[1]), float(box0[2]), float(box0[3]))
        t0 = clock()
        tracker.init(frame_list[0], box_tuple)
        init_time = clock() - t0
        boxes[0] = box0
        oks[0] = True
        for i in range(1, n):
            frame = frame_list[i]
            t0 = clock()
            r = tracker.update(frame)
            t1 = clock()
            times[i] = t1 - t0
            boxes[i] = r.box
            scores[i] = r.score
            oks[i] = r.ok
            n_updates += 1
    except Exception as exc:
        if raise_errors:
            raise
        error = f"{type(exc).__name__}: {exc}"
        error_frame = i
        tb = traceback.format_exc()
        if i < n:
            boxes[i:] = np.nan
            scores[i:] = np.nan
            oks[i:] = False
            times[i:] = np.nan
        warnings.warn(
            f"tracker {name!r} raised at frame {i}: {error}", RuntimeWarning, stacklevel=2
        )
    finally:
        if was_enabled:
            gc.enable()
    return RunResult(
        tracker=name,
        boxes=boxes,
        scores=scores,
        oks=oks,
        init_time=init_time,
        update_times=times,
        n_updates=n_updates,
        error=error,
        error_frame=error_frame,
        traceback=tb,
    )


@dataclass(frozen=True)
class EvalRecord:
    """Scores and speed of one tracker on one sequence.

    Attributes
    ----------
    tracker, sequence:
        Names.
    metrics:
        OTB one-pass scores of the first run.
    run:
        The first run (boxes, scores, per-frame times, error if any).
    fps_runs:
        Update-only FPS of every run.
    fps:
        Median of ``fps_runs``.
    median_update_time:
        Median over runs of each run's median seconds per update.
    deterministic:
        Whether every run gave the same boxes (``None`` with a single run).
    """

    tracker: str
    sequence: str
    metrics: OPEResult
    run: RunResult
    fps_runs: list[float]
    fps: float
    median_update_time: float
    deterministic: bool | None

    @property
    def n_frames(self) -> int:
        """Frames in the sequence."""
        return self.metrics.n_frames

    @property
    def error(self) -> str | None:
        """The first run's error, if any."""
        return self.run.error

    def to_dict(self, per_frame: bool = False) -> dict[str, Any]:
        """JSON-serialisable dictionary."""
        return {
            "tracker": self.tracker,
            "sequence": self.sequence,
            "fps": _num(self.fps),
            "fps_runs": [_num(v) for v in self.fps_runs],
            "median_update_time": _num(self.median_update_time),
            "deterministic": self.deterministic,
            "metrics": self.metrics.to_dict(per_frame=per_frame),
            "run": self.run.to_dict(per_frame=per_frame),
        }


def _median(values: Sequence[float]) -> float:
    arr = np.asarray(values, dtype=np.float64)
    arr = arr[~np.isnan(arr)]
    return float(np.median(arr)) if arr.size else float("nan")


def _progress(it: Iterable[Any], total: int | None, desc: str, enabled: bool) -> Iterable[Any]:
    from ..progress import progress

    return progress(it, total=total, desc=desc, enabled=None if enabled else False)


def evaluate_sequences(
    specs: Sequence[TrackerSpec],
    sequences: Iterable[SequenceLike],
    *,
    seed: int = 0,
    repeats: int = 1,
    progress: bool = True,
    params: Mapping[str, Mapping[str, Any]] | None = None,
    raise_errors: bool = False,
    missing: Literal["miss", "hold"] = "miss",
) -> list[EvalRecord]:
    """Run every tracker on every sequence (one-pass) and score it.

    Parameters
    ----------
    specs:
        Tracker names (or factories), e.g. ``["rcwmil", "opencv:MIL"]``.
    sequences:
        Sequences with ``name``, ``groundtruth`` and ``load()``; may be a generator (each
        sequence's frames are decoded once, used by all trackers, and dropped before the
        next sequence if nothing else holds it).  The tracker starts from the first
        ground-truth box.
    seed:
        Seed of every run (all repeats use the same seed: repeats measure time).
    repeats:
        Runs per (tracker, sequence); FPS is the median, accuracy is from the first run.
    progress:
        Show a progress bar over sequences (``wmiltrack.progress``).
    params:
        Per-tracker-name extra parameters, e.g. ``{"opencv:KCF": {"detect_thresh": 0.3}}``.
    raise_errors:
        Re-raise tracker exceptions instead of recording them.
    missing:
        How frames where a tracker gave no box are scored (see
        :func:`wmiltrack.eval.metrics.ope_metrics`): ``"miss"`` or ``"hold"`` (OTB toolkit).

    Returns
    -------
    list of EvalRecord
        In the order sequence by sequence, trackers in the order given.

    Raises
    ------
    ValueError
        If ``repeats < 1``, ``specs`` is empty, or a sequence has no ground truth.
    """
    if repeats < 1:
        raise ValueError(f"repeats must be at least 1, got {repeats}")
    if len(specs) == 0:
        raise ValueError("no trackers given")
    names = [_spec_name(s) for s in specs]
    total = operator.length_hint(sequences) or None
    records: list[EvalRecord] = []
    for seq in _progress(sequences, total, "sequences", progress):
        gt = seq.groundtruth
        if gt is None:
            raise ValueError(f"sequence {seq.name!r} has no ground truth")
        gt = np.asarray(gt, dtype=np.float64)
        frames = seq.load()
        init_box = gt[0]
        runs: dict[str, list[RunResult]] = {n: [] for n in names}
        for _ in range(repeats):
            for spec, name in zip(specs, names, strict=True):
                p = None if params is None or not isinstance(spec, str) else params.get(name)
                runs[name].append(
                    run_sequence(
                        spec, frames, init_box, seed=seed, params=p, raise_errors=raise_errors
                    )
                )
        for name in names:
            rs = runs[name]
            first = rs[0]
            deterministic = (
                None
                if len(rs) == 1
                else all(np.array_equal(first.boxes, r.boxes, equal_nan=True) for r in rs[1:])
            )
            records.append(
                EvalRecord(
                    tracker=name,
                    sequence=seq.name,
                    metrics=ope_metrics(first.boxes, gt, missing=missing),
                    run=first,
                    fps_runs=[r.fps for r in rs],
                    fps=_median([r.fps for r in rs]),
                    median_update_time=_median([r.median_update_time for r in rs]),
                    deterministic=deterministic,
                )
            )
        del frames
    return records


def fps_ratio(
    records: Sequence[EvalRecord], reference: str = "opencv:MIL"
) -> dict[tuple[str, str], float]:
    """FPS of each record divided by the reference tracker's FPS on the same sequence.

    Parameters
    ----------
    records:
        Output of :func:`evaluate_sequences` (the reference must have been run with them, so
        both were timed on the same machine in the same session).
    reference:
        Name of the reference tracker.

    Returns
    -------
    dict
        ``{(tracker, sequence): ratio}``; sequences without the reference are left out.
    """
    ref = {r.sequence: r.fps for r in records if r.tracker == reference}
    out: dict[tuple[str, str], float] = {}
    for r in records:
        if r.sequence in ref:
            base = ref[r.sequence]
            out[(r.tracker, r.sequence)] = r.fps / base if base > 0 else float("nan")
    return out


def _nanmean(values: Iterable[float]) -> float:
    arr = np.asarray(list(values), dtype=np.float64)
    arr = arr[~np.isnan(arr)]
    return float(arr.mean()) if arr.size else float("nan")


def _pooled_fps(recs: Sequence[EvalRecord]) -> float:
    frames = sum(r.run.n_updates for r in recs)
    seconds = sum(r.run.n_updates / r.fps for r in recs if r.run.n_updates and r.fps > 0)
    return frames / seconds if seconds > 0 else float("nan")


def summarize(
    records: Sequence[EvalRecord], reference: str = "opencv:MIL"
) -> dict[str, dict[str, Any]]:
    """Per-tracker means over sequences.

    Parameters
    ----------
    records:
        Output of :func:`evaluate_sequences`.
    reference:
        Tracker whose FPS the others are compared with.

    Returns
    -------
    dict
        ``{tracker: {"n_sequences", "auc", "success_50", "precision_20", "norm_precision_20",
        "mean_center_error", "no_box", "fps", "fps_ratio", "errors"}}``.  Accuracy figures
        are means of the per-sequence figures; ``fps`` is all update frames divided by
        all update time (the median run of each sequence), and ``fps_ratio`` is that over the
        reference's, on the sequences both ran (NaN if the reference was not run).
    """
    order: list[str] = []
    for r in records:
        if r.tracker not in order:
            order.append(r.tracker)
    ref_recs = {r.sequence: r for r in records if r.tracker == reference}
    out: dict[str, dict[str, Any]] = {}
    for name in order:
        recs = [r for r in records if r.tracker == name]
        fps = _pooled_fps(recs)
        shared = [r for r in recs if r.sequence in ref_recs]
        if shared:
            mine = _pooled_fps(shared)
            theirs = _pooled_fps([ref_recs[r.sequence] for r in shared])
            ratio = mine / theirs if theirs > 0 else float("nan")
        else:
            ratio = float("nan")
        out[name] = {
            "n_sequences": len(recs),
            "auc": _nanmean(r.metrics.auc for r in recs),
            "success_50": _nanmean(r.metrics.success_50 for r in recs),
            "precision_20": _nanmean(r.metrics.precision_20 for r in recs),
            "norm_precision_20": _nanmean(r.metrics.norm_precision_20 for r in recs),
            "mean_center_error": _nanmean(r.metrics.mean_center_error for r in recs),
            "fps": fps,
            "fps_ratio": ratio,
            "no_box": sum(r.metrics.n_no_prediction for r in recs),
            "errors": sum(r.error is not None for r in recs),
        }
    return out


def _fmt(v: float, spec: str) -> str:
    return "-" if v is None or (isinstance(v, float) and math.isnan(v)) else format(v, spec)


_HEADERS = (
    "Sequence",
    "Tracker",
    "Frames",
    "AUC",
    "SR@0.5",
    "P@20",
    "CLE px",
    "No box",
    "FPS",
    "FPS ratio",
)


def format_table(
    records: Sequence[EvalRecord],
    *,
    reference: str = "opencv:MIL",
    style: Literal["markdown", "plain"] = "markdown",
) -> str:
    """Format results as a table: one row per (sequence, tracker) and a mean row per tracker.

    Parameters
    ----------
    records:
        Output of :func:`evaluate_sequences`.
    reference:
        Tracker whose FPS the ``FPS ratio`` column divides by (measured in the same run).
    style:
        ``"markdown"`` (pipe table) or ``"plain"`` (aligned columns).

    Returns
    -------
    str
        The table, followed by notes on the definitions and any tracker errors.
    """
    ratios = fps_ratio(records, reference)
    rows: list[tuple[str, ...]] = []
    for r in records:
        m = r.metrics
        flag = " (!)" if r.error is not None else ""
        rows.append(
            (
                r.sequence,
                r.tracker + flag,
                str(m.n_scored if m.n_missing == 0 else f"{m.n_scored}/{m.n_frames}"),
                _fmt(m.auc, ".3f"),
                _fmt(m.success_50, ".3f"),
                _fmt(m.precision_20, ".3f"),
                _fmt(m.mean_center_error, ".1f"),
                str(m.n_no_prediction),
                _fmt(r.fps, ".1f"),
                _fmt(ratios.get((r.tracker, r.sequence), float("nan")), ".2f"),
            )
        )
    summary = summarize(records, reference)
    mean_rows: list[tuple[str, ...]] = []
    for name, s in summary.items():
        frames = sum(r.metrics.n_frames for r in records if r.tracker == name)
        mean_rows.append(
            (
                f"mean ({s['n_sequences']} seq)",
                name + (" (!)" if s["errors"] else ""),
                str(frames),
                _fmt(s["auc"], ".3f"),
                _fmt(s["success_50"], ".3f"),
                _fmt(s["precision_20"], ".3f"),
                _fmt(s["mean_center_error"], ".1f"),
                str(s["no_box"]),
                _fmt(s["fps"], ".1f"),
                _fmt(s["fps_ratio"], ".2f"),
            )
        )

    if style == "markdown":
        lines = ["| " + " | ".join(_HEADERS) + " |", "|" + "|".join(["---"] * len(_HEADERS)) + "|"]
        lines += ["| " + " | ".join(row) + " |" for row in rows]
        lines += ["| **" + row[0] + "** | " + " | ".join(row[1:]) + " |" for row in mean_rows]
    elif style == "plain":
        table = [_HEADERS, *rows, *mean_rows]
        widths = [max(len(row[c]) for row in table) for c in range(len(_HEADERS))]

        def line(row: tuple[str, ...]) -> str:
            return "  ".join(
                cell.ljust(w) if c < 2 else cell.rjust(w)
                for c, (cell, w) in enumerate(zip(row, widths, strict=True))
            ).rstrip()

        rule = "  ".join("-" * w for w in widths)
        lines = [
            line(_HEADERS),
            rule,
            *(line(r) for r in rows),
            rule,
            *(line(r) for r in mean_rows),
        ]
    else:
        raise ValueError(f"style must be 'markdown' or 'plain', not {style!r}")

    notes = [
        "",
        (
            "AUC: mean success rate over IoU thresholds 0, 0.05, ..., 1 (IoU > t); "
            "SR@0.5: IoU > 0.5; P@20: centre error <= 20 px; "
            "CLE: mean centre error over frames with a box; No box: scored frames where the "
            "tracker gave no box (scored as misses unless --missing hold)."
        ),
        (
            "Frames: scored frames (scored/total when some ground truth is absent). "
            "FPS: update-only frames per second (decoding and init excluded). "
            f"FPS ratio: FPS / FPS of {reference} on the same sequence in the same run."
        ),
        "Mean rows: accuracy = mean over sequences; FPS = all update frames / all update time.",
    ]
    errs = [r for r in records if r.error is not None]
    if errs:
        notes.append("(!) tracker errors (remaining frames scored as misses):")
        notes += [
            f"  {r.tracker} on {r.sequence}, frame {r.run.error_frame}: {r.error}" for r in errs
        ]
    return "\n".join(lines + notes)


# ----------------------------------------------------------------------------- reporting
def cpu_model() -> str:
    """The CPU's model name (``/proc/cpuinfo``; ``platform.processor()`` elsewhere)."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.lower().startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "?"


def environment() -> dict[str, Any]:
    """Machine and versions that timings depend on, for benchmark reports.

    Returns
    -------
    dict
        Date, Python, platform, CPU model and count, numpy, the installed OpenCV wheel and
        version with its thread count, matplotlib (None if absent) and wmiltrack.
    """
    import cv2

    from .. import __version__
    from .peers import installed_opencv

    try:
        import matplotlib

        mpl: str | None = matplotlib.__version__
    except ImportError:
        mpl = None
    dist, ver = installed_opencv()
    return {
        "date": time.strftime("%Y-%m-%d %H:%M:%S"),
        "python": platform.python_version(),
        "platform": platform.platform(),
        "cpu": cpu_model(),
        "cpu_count": os.cpu_count(),
        "numpy": np.__version__,
        "opencv": cv2.__version__,
        "opencv_wheel": f"{dist} {ver}",
        "opencv_threads": cv2.getNumThreads(),
        "matplotlib": mpl,
        "wmiltrack": __version__,
    }


def json_safe(obj: Any) -> Any:
    """A copy fit for strict JSON: NaN -> None, infinities -> "inf"/"-inf", numpy scalars ->
    Python numbers, tuples -> lists, dict keys -> str (recursively)."""
    if isinstance(obj, (float, np.floating)):
        f = float(obj)
        if math.isnan(f):
            return None
        if math.isinf(f):
            return "inf" if f > 0 else "-inf"
        return f
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, dict):
        return {str(k): json_safe(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [json_safe(v) for v in obj]
    return obj
