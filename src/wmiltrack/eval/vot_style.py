"""VOT's supervised ("reset-based") experiment, as in the VOT2015 challenge.

The tracker is started on the first frame with its ground truth and run on.  Whenever its
box stops overlapping the ground truth (overlap exactly 0 on a frame whose ground truth is
present) that frame counts as a *failure*; the tracker is then started afresh ``skip``
frames later (VOT: 5) from that frame's ground truth, or from the next frame whose ground
truth is present.  The frames in between are *not tracked*.

Definitions used here
---------------------
overlap
    IoU of the reported box with the ground truth (:func:`wmiltrack.eval.metrics.iou`); a box with
    NaN (no output) has overlap 0 and therefore fails.
accuracy
    Mean overlap over the tracked frames with ground truth, leaving out (as the VOT toolkit
    does) the first ``burnin`` frames of every (re)initialisation -- the initialisation frame
    itself is one of them, and is always left out even with ``burnin=0`` since the tracker
    did not predict it -- and the failure frames themselves.  NaN if no frame is left.
failures
    Number of failures.  ``failures_per_100`` is ``100 * failures / n_frames``.
robustness
    VOT2016's reliability ``exp(-S * failures / n_frames)`` with ``S = sensitivity = 100``:
    1.0 with no failure, ``exp(-1) = 0.37`` at one failure every 100 frames.  (VOT2015 itself
    reported the raw failure count as "robustness"; that is ``failures``.)
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

from ..engine.result import TrackerLike
from .metrics import as_boxes, iou, valid_mask

__all__ = ["SupervisedResult", "run_supervised"]

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]


@dataclass(frozen=True)
class SupervisedResult:
    """Outcome of :func:`run_supervised` on one sequence.

    Attributes
    ----------
    accuracy:
        Mean overlap over the frames in ``accuracy_mask`` (NaN if none).
    failures:
        Number of failures.
    robustness:
        ``exp(-sensitivity * failures / n_frames)`` (VOT2016 reliability).
    failures_per_100:
        ``100 * failures / n_frames``.
    n_frames:
        Frames in the sequence.
    init_frames:
        Frames where the tracker was (re)initialised, the first one included.
    failure_frames:
        Frames where a failure was detected.
    overlaps:
        ``(n,)`` overlap per frame; NaN where not tracked or where the ground truth is absent.
        On initialisation frames it is the overlap of the ground-truth box with itself (1).
    boxes:
        ``(n, 4)`` boxes the tracker reported (the ground truth on initialisation frames);
        NaN rows where not tracked.
    tracked:
        ``(n,)`` True where the tracker was running (initialisation frames included).
    accuracy_mask:
        ``(n,)`` True for the frames averaged into ``accuracy``.
    skip, burnin, sensitivity:
        The protocol's settings.
    """

    accuracy: float
    failures: int
    robustness: float
    failures_per_100: float
    n_frames: int
    init_frames: list[int]
    failure_frames: list[int]
    overlaps: FloatArray = field(repr=False)
    boxes: FloatArray = field(repr=False)
    tracked: BoolArray = field(repr=False)
    accuracy_mask: BoolArray = field(repr=False)
    skip: int = 5
    burnin: int = 10
    sensitivity: float = 100.0

    def to_dict(self, per_frame: bool = False) -> dict[str, Any]:
        """Plain JSON-serialisable dictionary.

        Parameters
        ----------
        per_frame:
            Also include the per-frame overlaps (``None`` for NaN) and boxes.

        Returns
        -------
        dict
        """
        d: dict[str, Any] = {
            "accuracy": None if math.isnan(self.accuracy) else self.accuracy,
            "failures": self.failures,
            "robustness": self.robustness,
            "failures_per_100": self.failures_per_100,
            "n_frames": self.n_frames,
            "init_frames": list(self.init_frames),
            "failure_frames": list(self.failure_frames),
            "skip": self.skip,
            "burnin": self.burnin,
            "sensitivity": self.sensitivity,
        }
        if per_frame:
            d["overlaps"] = [None if math.isnan(v) else float(v) for v in self.overlaps]
            d["boxes"] = [
                None if np.isnan(row).any() else [float(v) for v in row] for row in self.boxes
            ]
        return d


def _next_valid(valid: BoolArray, start: int) -> int | None:
    idx = np.flatnonzero(valid[start:])
    return None if idx.size == 0 else start + int(idx[0])


def run_supervised(
    make_tracker: Callable[[], TrackerLike],
    frames: Sequence[npt.NDArray[np.uint8]],
    gt: npt.ArrayLike,
    *,
    skip: int = 5,
    burnin: int = 10,
    sensitivity: float = 100.0,
) -> SupervisedResult:
    """Run the VOT supervised experiment on one sequence.

    Parameters
    ----------
    make_tracker:
        Returns a new, uninitialised tracker; called at the start and after every failure,
        so no state survives a re-initialisation.
    frames:
        The decoded frames.
    gt:
        ``(n, 4)`` ground truth; rows with NaN or a non-positive size mean "target absent":
        no failure can be detected there and those frames are never averaged.
    skip:
        After a failure at frame ``f`` the tracker is re-initialised at ``f + skip`` (or the
        next frame with ground truth).  At least 1.
    burnin:
        Frames left out of the accuracy from every initialisation on (the initialisation frame
        counts as the first of them).
    sensitivity:
        ``S`` of the reliability ``exp(-S * failures / n_frames)``.

    Returns
    -------
    SupervisedResult

    Raises
    ------
    ValueError
        If ``frames`` and ``gt`` differ in length, no frame has ground truth, or ``skip < 1``
        or ``burnin < 0``.
    """
    g = as_boxes(gt, "gt")
    n = len(frames)
    _check_supervised(g, n, skip, burnin)
    valid = valid_mask(g)
    trace = _Trace.empty(n)
    start = _next_valid(valid, 0)
    if start is None:
        raise ValueError("no frame has a valid ground-truth box to start from")

    while start is not None:
        failed_at = _track_from(make_tracker(), frames, g, valid, start, burnin, trace)
        if failed_at is None:
            break
        trace.failure_frames.append(failed_at)
        restart = failed_at + skip
        start = _next_valid(valid, restart) if restart < n else None

    mask = trace.tracked & valid & ~trace.excluded
    mask[trace.failure_frames] = False
    accuracy = float(np.mean(trace.overlaps[mask])) if mask.any() else float("nan")
    failures = len(trace.failure_frames)
    return SupervisedResult(
        accuracy=accuracy,
        failures=failures,
        robustness=float(math.exp(-sensitivity * failures / n)),
        failures_per_100=100.0 * failures / n,
        n_frames=n,
        init_frames=trace.init_frames,
        failure_frames=trace.failure_frames,
        overlaps=trace.overlaps,
        boxes=trace.boxes,
        tracked=trace.tracked,
        accuracy_mask=mask,
        skip=skip,
        burnin=burnin,
        sensitivity=sensitivity,
    )


def _check_supervised(g: FloatArray, n: int, skip: int, burnin: int) -> None:
    """Refuse ground truth of another length than the frames and settings the protocol cannot
    follow, before any tracker runs."""
    if g.shape[0] != n:
        raise ValueError(f"{n} frames but {g.shape[0]} ground-truth rows")
    if skip < 1:
        raise ValueError(f"skip must be at least 1, got {skip}")
    if burnin < 0:
        raise ValueError(f"burnin must be non-negative, got {burnin}")


@dataclass
class _Trace:
    """The per-frame record of one supervised run, filled as the tracker is (re)started:
    overlaps, boxes, which frames were tracked and which are left out of the accuracy (the
    burn-in after each start), and the frames of each start and failure."""

    overlaps: FloatArray
    boxes: FloatArray
    tracked: BoolArray
    excluded: BoolArray
    init_frames: list[int] = field(default_factory=list)
    failure_frames: list[int] = field(default_factory=list)

    @classmethod
    def empty(cls, n: int) -> _Trace:
        """A record of ``n`` frames with nothing tracked yet (NaN overlaps and boxes)."""
        return cls(np.full(n, np.nan), np.full((n, 4), np.nan), np.zeros(n, dtype=bool),
                   np.zeros(n, dtype=bool))


def _track_from(tracker: TrackerLike, frames: Sequence[npt.NDArray[np.uint8]], g: FloatArray,
                valid: BoolArray, start: int, burnin: int, trace: _Trace) -> int | None:
    """Start ``tracker`` on frame ``start`` from its ground truth and run it on, recording each
    frame in ``trace``, until its box stops overlapping the ground truth: that frame, or
    ``None`` when it reaches the end without failing."""
    x, y, w, h = (float(v) for v in g[start])
    init_box = (x, y, w, h)
    tracker.init(frames[start], init_box)
    trace.init_frames.append(start)
    trace.boxes[start] = g[start]
    trace.overlaps[start] = 1.0
    trace.tracked[start] = True
    trace.excluded[start : start + max(burnin, 1)] = True
    for f in range(start + 1, len(frames)):
        box = np.asarray(tracker.update(frames[f]).box, dtype=np.float64)
        trace.boxes[f] = box
        trace.tracked[f] = True
        if valid[f]:
            ov = float(iou(box[None, :], g[f][None, :])[0])
            trace.overlaps[f] = ov
            if ov <= 0.0:
                return f
    return None
