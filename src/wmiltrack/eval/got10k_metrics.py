"""GOT-10k's figures: average overlap (AO), success rates SR@0.5 and SR@0.75, success curve.

Follows the evaluation of the official toolkit (got10k-toolkit, ``got10k/experiments/got10k.py``,
``ExperimentGOT10k.report`` and ``_evaluate``; overlaps from ``got10k/utils/metrics.py``,
``rect_iou``):

* the **first frame is not scored** (the toolkit compares ``boxes[1:]`` with ``anno[1:]``: it is
  the initialisation frame);
* only frames where the target is visible are scored (the toolkit keeps ``cover.label > 0``;
  here: frames whose ground-truth row is finite, which is how
  :func:`wmiltrack.data.layouts.load_layout` marks GOT-10k's absent frames, optionally
  intersected with a ``visible`` mask);
* when the image size is known, **both boxes are clipped to the image** first (``bound=(W, H)``,
  the toolkit reads it from ``meta_info.ini``): ``x`` to ``[0, W]``, then ``w`` to ``[0, W - x]``,
  likewise for ``y`` and ``h``;
* overlaps are of continuous boxes ``[x, x + w) x [y, y + h)``
  (:func:`wmiltrack.eval.metrics.iou`; the toolkit divides by ``union + eps``, a difference below
  ``1e-15``);
* ``AO`` is the mean overlap, ``SR@t`` the fraction of overlaps **strictly greater** than ``t``
  (toolkit: ``np.mean(ious > 0.5)``), and the success curve the fraction ``> t`` at the 101
  thresholds ``np.linspace(0, 1, 101)``;
* over a dataset, the toolkit **pools the frames** of all sequences (and of all repetitions of a
  sequence) and takes the figures over the pool: a long sequence weighs more.  :func:`got10k_aggregate`
  does that, and also gives the mean of the per-sequence figures.

Differences, on purpose: a predicted box with a ``nan`` (no box) scores overlap 0 (the toolkit
would propagate ``nan`` into the mean); SR@0.75 is computed like SR@0.5 (the toolkit's
``_evaluate`` returns SR@0.5 only; the GOT-10k leaderboard reports both).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

from .metrics import as_boxes, iou

__all__ = [
    "GOT10K_THRESHOLDS",
    "GOT10kAggregate",
    "GOT10kResult",
    "clip_to_bound",
    "got10k_aggregate",
    "got10k_ious",
    "got10k_metrics",
]

FloatArray = npt.NDArray[np.float64]

GOT10K_THRESHOLDS: FloatArray = np.linspace(0.0, 1.0, 101)
"""Overlap thresholds of GOT-10k's success curve (toolkit: ``np.linspace(0, 1, 101)``)."""


def clip_to_bound(boxes: npt.ArrayLike, bound: tuple[float, float]) -> FloatArray:
    """Clip ``(x, y, w, h)`` boxes to an image of size ``bound = (width, height)``.

    Parameters
    ----------
    boxes:
        ``(n, 4)`` boxes.
    bound:
        Image width and height.

    Returns
    -------
    numpy.ndarray
        A new array: ``x`` clipped to ``[0, W]``, then ``w`` to ``[0, W - x]`` (``y``, ``h`` alike),
        as the GOT-10k toolkit's ``rect_iou(..., bound=...)`` does.  ``nan`` stays ``nan``.
    """
    b = as_boxes(boxes, "boxes").copy()
    width, height = float(bound[0]), float(bound[1])
    b[:, 0] = np.clip(b[:, 0], 0.0, width)
    b[:, 1] = np.clip(b[:, 1], 0.0, height)
    b[:, 2] = np.clip(b[:, 2], 0.0, width - b[:, 0])
    b[:, 3] = np.clip(b[:, 3], 0.0, height - b[:, 1])
    return b


def got10k_ious(
    pred: npt.ArrayLike,
    gt: npt.ArrayLike,
    *,
    visible: npt.ArrayLike | None = None,
    bound: tuple[float, float] | None = None,
) -> FloatArray:
    """Per-frame overlaps as GOT-10k scores them, ``nan`` on frames it does not score.

    Parameters
    ----------
    pred, gt:
        ``(n, 4)`` predicted and ground-truth boxes, frame 0 (initialisation) included.
    visible:
        Optional ``(n,)`` booleans (or GOT-10k ``cover.label`` values, visible where ``> 0``);
        frames outside it are not scored.
    bound:
        Optional image ``(width, height)`` to clip both boxes to (see :func:`clip_to_bound`).

    Returns
    -------
    numpy.ndarray
        ``(n,)`` overlaps; ``nan`` at frame 0, where the ground truth has a ``nan``, and outside
        ``visible``.

    Raises
    ------
    ValueError
        If the arrays are not ``(n, 4)``, lengths differ, or ``visible`` has another length.
    """
    p = as_boxes(pred, "pred")
    g = as_boxes(gt, "gt")
    if p.shape != g.shape:
        raise ValueError(
            f"prediction has {p.shape[0]} boxes but the ground truth has {g.shape[0]} rows"
        )
    n = g.shape[0]
    scored = np.all(np.isfinite(g), axis=1)
    if n:
        scored[0] = False
    if visible is not None:
        vis = np.asarray(visible)
        if vis.shape != (n,):
            raise ValueError(f"visible must have shape ({n},), got {vis.shape}")
        scored &= vis.astype(np.float64) > 0
    if bound is not None:
        p = clip_to_bound(p, bound)
        g = clip_to_bound(g, bound)
    ov = iou(p, g)
    return np.where(scored, ov, np.nan)


@dataclass(frozen=True)
class GOT10kResult:
    """GOT-10k figures over a set of scored frames.

    Attributes
    ----------
    ao:
        Average overlap.
    sr50, sr75:
        Fraction of scored frames with overlap ``> 0.5`` and ``> 0.75``.
    success_curve:
        Fraction with overlap ``> t`` for each ``t`` of :data:`GOT10K_THRESHOLDS`.
    n_frames:
        Frames in the sequence(s), scored or not.
    n_scored:
        Frames scored (the figures are ``nan`` when this is 0).
    ious:
        Per-frame overlaps, ``nan`` on frames not scored.
    """

    ao: float
    sr50: float
    sr75: float
    success_curve: FloatArray
    n_frames: int
    n_scored: int
    ious: FloatArray = field(repr=False)

    def to_dict(self, per_frame: bool = False) -> dict[str, Any]:
        """Plain JSON-serialisable dictionary (``nan`` becomes ``None``).

        Parameters
        ----------
        per_frame:
            Also include the per-frame ``ious``.
        """
        d: dict[str, Any] = {
            "ao": _num(self.ao),
            "sr50": _num(self.sr50),
            "sr75": _num(self.sr75),
            "n_frames": self.n_frames,
            "n_scored": self.n_scored,
            "success_curve": [_num(v) for v in self.success_curve],
        }
        if per_frame:
            d["ious"] = [_num(v) for v in self.ious]
        return d


def _num(v: float | np.floating[Any]) -> float | None:
    f = float(v)
    return None if np.isnan(f) else f


def _figures(ious: FloatArray) -> GOT10kResult:
    ov = ious[~np.isnan(ious)]
    if ov.size == 0:
        nan = float("nan")
        curve = np.full(GOT10K_THRESHOLDS.shape, np.nan)
        return GOT10kResult(nan, nan, nan, curve, int(ious.size), 0, ious)
    curve = np.asarray((ov[:, None] > GOT10K_THRESHOLDS[None, :]).mean(axis=0), dtype=np.float64)
    return GOT10kResult(
        ao=float(ov.mean()),
        sr50=float(np.mean(ov > 0.5)),
        sr75=float(np.mean(ov > 0.75)),
        success_curve=curve,
        n_frames=int(ious.size),
        n_scored=int(ov.size),
        ious=ious,
    )


def got10k_metrics(
    pred: npt.ArrayLike,
    gt: npt.ArrayLike,
    *,
    visible: npt.ArrayLike | None = None,
    bound: tuple[float, float] | None = None,
) -> GOT10kResult:
    """Score one trajectory the way the GOT-10k toolkit does.

    Parameters
    ----------
    pred, gt, visible, bound:
        As for :func:`got10k_ious`.

    Returns
    -------
    GOT10kResult
        AO, SR@0.5, SR@0.75 and the 101-point success curve over the scored frames (frame 0
        and absent frames left out); ``nan`` figures if no frame is scored.
    """
    return _figures(got10k_ious(pred, gt, visible=visible, bound=bound))


@dataclass(frozen=True)
class GOT10kAggregate:
    """GOT-10k figures over several sequences.

    Attributes
    ----------
    pooled:
        Figures over the scored frames of all sequences taken together: the toolkit's
        ``overall`` numbers.
    per_sequence:
        Means over sequences of ``ao``, ``sr50``, ``sr75`` and the success curve (sequences with
        no scored frame are skipped).
    n_sequences:
        Number of results aggregated.
    """

    pooled: GOT10kResult
    per_sequence: dict[str, Any]
    n_sequences: int

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-serialisable dictionary."""
        return {
            "n_sequences": self.n_sequences,
            "pooled": self.pooled.to_dict(),
            "per_sequence": self.per_sequence,
        }


def got10k_aggregate(results: Sequence[GOT10kResult]) -> GOT10kAggregate:
    """Combine per-sequence results (several repetitions of a sequence may be passed too).

    Parameters
    ----------
    results:
        One :class:`GOT10kResult` per sequence (or per run).

    Returns
    -------
    GOT10kAggregate
        ``pooled`` follows the toolkit (frames of every result concatenated);
        ``per_sequence`` is the plain mean of the per-result figures.

    Raises
    ------
    ValueError
        If ``results`` is empty.
    """
    if len(results) == 0:
        raise ValueError("got10k_aggregate() needs at least one result")
    pooled = _figures(np.concatenate([r.ious for r in results]))
    keep = [r for r in results if r.n_scored > 0]
    mean: dict[str, Any] = {}
    for key in ("ao", "sr50", "sr75"):
        mean[key] = float(np.mean([getattr(r, key) for r in keep])) if keep else None
    mean["success_curve"] = (
        [float(v) for v in np.mean([r.success_curve for r in keep], axis=0)] if keep else None
    )
    return GOT10kAggregate(pooled=pooled, per_sequence=mean, n_sequences=len(results))
