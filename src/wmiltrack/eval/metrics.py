"""One-pass evaluation (OPE) of single-object trackers, as the OTB toolkit scores it.

Boxes are ``(x, y, w, h)`` rows: top-left corner, width and height, in pixels.  A box covers
the continuous region ``[x, x + w) x [y, y + h)``; this is what OTB's ``calcRectInt.m``
computes (it writes ``right = x + w - 1`` and adds ``1`` back to every extent), so the
overlaps here match the toolkit's to rounding.

Figures reported by :func:`ope_metrics`

* **success curve**: at each threshold ``t`` of ``np.linspace(0, 1, 21)`` the fraction of
  scored frames whose IoU is strictly greater than ``t`` (OTB: ``overlap > t``).  ``auc`` is
  the mean of these 21 points, so a perfect tracker scores ``20/21`` (no IoU exceeds 1).
* **precision curve**: at each integer threshold ``0..50`` px the fraction of scored frames
  whose centre error is at most ``t`` (OTB: ``errCenter <= t``); ``precision_20`` at 20 px.
* **normalised precision** (TrackingNet / LaSOT): the centre offset divided by the
  ground-truth width and height per axis, then the Euclidean norm; curve at
  ``np.linspace(0, 0.5, 51)`` with ``<= t``, ``norm_precision_20`` at 0.2.

Frames whose ground truth has a NaN or a non-positive width or height are left out of every
figure and counted in ``n_missing``.  A predicted box containing NaN (tracker gave no box)
counts as IoU 0 and infinite centre error, so it fails every threshold and makes the mean
centre error infinite; with ``missing="hold"`` it is replaced by the last box given before it
instead, which is what the OTB toolkit's ``calcSeqErrRobust.m`` does with NaN or degenerate
result rows.  (:mod:`wmiltrack.eval.scoring` applies the evaluation's convention, the same for
every tracker, before calling :func:`ope_metrics`.)
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
import numpy.typing as npt

__all__ = [
    "NORM_PRECISION_THRESHOLDS",
    "PRECISION_THRESHOLDS",
    "SUCCESS_THRESHOLDS",
    "OPEResult",
    "as_boxes",
    "center_error",
    "hold_missing",
    "iou",
    "normalized_center_error",
    "ope_metrics",
    "valid_mask",
]

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]

#: Overlap thresholds of the success plot (OTB: ``0:0.05:1``).
SUCCESS_THRESHOLDS: FloatArray = np.linspace(0.0, 1.0, 21)
#: Centre-error thresholds of the precision plot in pixels (OTB: ``0:50``).
PRECISION_THRESHOLDS: FloatArray = np.arange(0, 51, dtype=np.float64)
#: Thresholds of the normalised precision plot (LaSOT: ``0:0.01:0.5``).
NORM_PRECISION_THRESHOLDS: FloatArray = np.linspace(0.0, 0.5, 51)


def as_boxes(boxes: npt.ArrayLike, name: str = "boxes") -> FloatArray:
    """Return ``boxes`` as a float64 array of shape ``(n, 4)``.

    Parameters
    ----------
    boxes:
        Anything :func:`numpy.asarray` turns into ``(n, 4)`` numbers; a single box of shape
        ``(4,)`` becomes ``(1, 4)``.
    name:
        Used in the error message.

    Returns
    -------
    numpy.ndarray
        A new ``(n, 4)`` float64 array.

    Raises
    ------
    ValueError
        If the shape is not ``(n, 4)`` or ``(4,)``.
    """
    arr = np.array(boxes, dtype=np.float64, copy=True)
    if arr.ndim == 1 and arr.shape[0] == 4:
        arr = arr.reshape(1, 4)
    if arr.ndim != 2 or arr.shape[1] != 4:
        raise ValueError(f"{name} must have shape (n, 4) as x, y, w, h rows; got {arr.shape}")
    return arr


def _pair(a: npt.ArrayLike, b: npt.ArrayLike) -> tuple[FloatArray, FloatArray]:
    aa = as_boxes(a, "a")
    bb = as_boxes(b, "b")
    if aa.shape != bb.shape:
        raise ValueError(f"box arrays differ in length: {aa.shape[0]} vs {bb.shape[0]}")
    return aa, bb


def iou(a: npt.ArrayLike, b: npt.ArrayLike) -> FloatArray:
    """Intersection over union of paired boxes.

    Parameters
    ----------
    a, b:
        ``(n, 4)`` arrays of ``x, y, w, h`` rows (continuous boxes ``[x, x+w) x [y, y+h)``).

    Returns
    -------
    numpy.ndarray
        ``(n,)`` overlaps in ``[0, 1]``.  A row with NaN in either box gives ``0``, as does a
        pair whose union is empty.  A negative width or height counts as an empty box.
    """
    aa, bb = _pair(a, b)
    wa = np.maximum(aa[:, 2], 0.0)
    ha = np.maximum(aa[:, 3], 0.0)
    wb = np.maximum(bb[:, 2], 0.0)
    hb = np.maximum(bb[:, 3], 0.0)
    with np.errstate(invalid="ignore"):
        iw = np.minimum(aa[:, 0] + wa, bb[:, 0] + wb) - np.maximum(aa[:, 0], bb[:, 0])
        ih = np.minimum(aa[:, 1] + ha, bb[:, 1] + hb) - np.maximum(aa[:, 1], bb[:, 1])
        inter = np.maximum(iw, 0.0) * np.maximum(ih, 0.0)
        union = wa * ha + wb * hb - inter
        out = np.where(union > 0, inter / np.where(union > 0, union, 1.0), 0.0)
    out = np.where(np.isfinite(out), out, 0.0)
    return np.clip(out, 0.0, 1.0)


def _centers(boxes: FloatArray) -> FloatArray:
    return boxes[:, :2] + boxes[:, 2:] / 2.0


def center_error(a: npt.ArrayLike, b: npt.ArrayLike) -> FloatArray:
    """Euclidean distance in pixels between the centres of paired boxes.

    Parameters
    ----------
    a, b:
        ``(n, 4)`` arrays of ``x, y, w, h`` rows.

    Returns
    -------
    numpy.ndarray
        ``(n,)`` distances; ``inf`` where either box has a NaN.
    """
    aa, bb = _pair(a, b)
    d = np.hypot(*(_centers(aa) - _centers(bb)).T)
    return np.where(np.isnan(d), np.inf, d)


def normalized_center_error(pred: npt.ArrayLike, gt: npt.ArrayLike) -> FloatArray:
    """Centre error with each axis divided by the ground-truth size (TrackingNet, LaSOT).

    Parameters
    ----------
    pred, gt:
        ``(n, 4)`` arrays of ``x, y, w, h`` rows; ``gt`` gives the normalising size.

    Returns
    -------
    numpy.ndarray
        ``(n,)`` values of ``hypot(dx / w_gt, dy / h_gt)``; ``inf`` where a box has a NaN or
        the ground-truth size is not positive.
    """
    pp, gg = _pair(pred, gt)
    diff = _centers(pp) - _centers(gg)
    with np.errstate(divide="ignore", invalid="ignore"):
        d = np.hypot(diff[:, 0] / gg[:, 2], diff[:, 1] / gg[:, 3])
    ok = (gg[:, 2] > 0) & (gg[:, 3] > 0) & np.isfinite(d)
    return np.where(ok, d, np.inf)


def valid_mask(gt: npt.ArrayLike) -> BoolArray:
    """Frames whose ground truth can be scored.

    Parameters
    ----------
    gt:
        ``(n, 4)`` ground-truth boxes.

    Returns
    -------
    numpy.ndarray
        ``(n,)`` booleans: ``False`` where the row has a NaN (or infinity) or a width or height
        that is not positive (target absent or unannotated).
    """
    g = as_boxes(gt, "gt")
    ok: BoolArray = np.all(np.isfinite(g), axis=1) & (g[:, 2] > 0) & (g[:, 3] > 0)
    return ok


@dataclass(frozen=True)
class OPEResult:
    """Scores of one tracker on one sequence (one-pass evaluation).

    Attributes
    ----------
    success_curve:
        Fraction of scored frames with IoU ``> t`` for each ``t`` in :data:`SUCCESS_THRESHOLDS`.
    auc:
        Mean of ``success_curve`` (OTB's "AUC").
    success_50:
        Fraction of scored frames with IoU ``> 0.5``.
    precision_curve:
        Fraction with centre error ``<= t`` px for ``t`` in :data:`PRECISION_THRESHOLDS`.
    precision_20:
        Fraction with centre error ``<= 20`` px.
    norm_precision_curve:
        Fraction with normalised centre error ``<= t`` for :data:`NORM_PRECISION_THRESHOLDS`.
    norm_precision_20:
        Fraction with normalised centre error ``<= 0.2``.
    mean_iou:
        Mean IoU over scored frames (frames without a prediction count as 0).
    mean_center_error:
        Mean centre error in pixels over all scored frames.  A frame without a predicted box
        has an infinite error, so the mean is infinite when there is one (it is a miss here
        as in every other figure); NaN if no frame is scored.
    n_frames:
        Number of frames in the sequence (scored or not).
    n_scored:
        Frames scored (``n_frames - n_missing``).
    n_missing:
        Frames left out because their ground truth is absent or degenerate.
    n_no_prediction:
        Scored frames whose predicted box has a NaN.
    ious, center_errors, norm_center_errors:
        Per-frame values, NaN on frames that were not scored (``inf`` errors where the
        prediction was missing).
    """

    success_curve: FloatArray
    auc: float
    success_50: float
    precision_curve: FloatArray
    precision_20: float
    norm_precision_curve: FloatArray
    norm_precision_20: float
    mean_iou: float
    mean_center_error: float
    n_frames: int
    n_scored: int
    n_missing: int
    n_no_prediction: int
    ious: FloatArray = field(repr=False)
    center_errors: FloatArray = field(repr=False)
    norm_center_errors: FloatArray = field(repr=False)

    def to_dict(self, per_frame: bool = False) -> dict[str, Any]:
        """Plain JSON-serialisable dictionary of the figures.

        Parameters
        ----------
        per_frame:
            Also include the per-frame ``ious`` and centre errors (``None`` for NaN,
            ``"inf"`` for infinity).

        Returns
        -------
        dict
            Scalars as Python numbers, curves as lists.
        """
        d: dict[str, Any] = {
            "auc": self.auc,
            "success_50": self.success_50,
            "precision_20": self.precision_20,
            "norm_precision_20": self.norm_precision_20,
            "mean_iou": self.mean_iou,
            "mean_center_error": _json_float(self.mean_center_error),
            "n_frames": self.n_frames,
            "n_scored": self.n_scored,
            "n_missing": self.n_missing,
            "n_no_prediction": self.n_no_prediction,
            "success_curve": [float(v) for v in self.success_curve],
            "precision_curve": [float(v) for v in self.precision_curve],
            "norm_precision_curve": [float(v) for v in self.norm_precision_curve],
        }
        if per_frame:
            d["ious"] = [_json_float(v) for v in self.ious]
            d["center_errors"] = [_json_float(v) for v in self.center_errors]
            d["norm_center_errors"] = [_json_float(v) for v in self.norm_center_errors]
        return d


def _json_float(v: float | np.floating[Any]) -> float | str | None:
    f = float(v)
    if np.isnan(f):
        return None
    if np.isinf(f):
        return "inf" if f > 0 else "-inf"
    return f


def _rate(mask: BoolArray) -> float:
    return float(np.mean(mask)) if mask.size else float("nan")


def _curve_gt(values: FloatArray, thresholds: FloatArray) -> FloatArray:
    if values.size == 0:
        return np.full(thresholds.shape, np.nan)
    return np.asarray((values[None, :] > thresholds[:, None]).mean(axis=1), dtype=np.float64)


def _curve_le(values: FloatArray, thresholds: FloatArray) -> FloatArray:
    if values.size == 0:
        return np.full(thresholds.shape, np.nan)
    return np.asarray((values[None, :] <= thresholds[:, None]).mean(axis=1), dtype=np.float64)


def hold_missing(pred: npt.ArrayLike) -> FloatArray:
    """Replace each missing predicted box by the last box given before it.

    A row is missing when it has a NaN or a non-positive width or height.  This is what the
    OTB toolkit's ``calcSeqErrRobust.m`` does to a result file before scoring it.  Missing
    rows before the first given box stay NaN.

    Parameters
    ----------
    pred:
        ``(n, 4)`` predicted boxes.

    Returns
    -------
    numpy.ndarray
        A new ``(n, 4)`` array.
    """
    p = as_boxes(pred, "pred")
    given = valid_mask(p)
    last = np.where(given, np.arange(len(p)), -1)
    np.maximum.accumulate(last, out=last)
    out = np.full_like(p, np.nan)
    have = last >= 0
    out[have] = p[last[have]]
    return out


def ope_metrics(
    pred: npt.ArrayLike, gt: npt.ArrayLike, *, missing: Literal["miss", "hold"] = "miss"
) -> OPEResult:
    """Score a trajectory against the ground truth as the OTB toolkit does.

    Parameters
    ----------
    pred:
        ``(n, 4)`` predicted boxes, one per frame including the first (initialisation) frame,
        as OTB does.  Rows with NaN mean "no box".
    gt:
        ``(n, 4)`` ground-truth boxes; rows failing :func:`valid_mask` are not scored.
    missing:
        ``"miss"`` (default): a frame without a predicted box has IoU 0 and infinite centre
        error, failing every threshold.  ``"hold"``: such a frame gets the last box given
        before it (:func:`hold_missing`), as the OTB toolkit's ``calcSeqErrRobust.m`` does;
        ``n_no_prediction`` still counts the frames that had no box of their own.

    Returns
    -------
    OPEResult
        All figures; curves and rates are NaN if no frame can be scored.

    Raises
    ------
    ValueError
        If the arrays are not ``(n, 4)`` or their lengths differ (a trajectory that is
        shorter or longer than the ground truth is an error, not something to pad).
    """
    p = as_boxes(pred, "pred")
    g = as_boxes(gt, "gt")
    if missing not in ("miss", "hold"):
        raise ValueError(f"missing must be 'miss' or 'hold', not {missing!r}")
    if p.shape[0] != g.shape[0]:
        raise ValueError(
            f"prediction has {p.shape[0]} boxes but the ground truth has {g.shape[0]} rows; "
            "score exactly one box per ground-truth frame"
        )
    n = g.shape[0]
    valid = valid_mask(g)
    no_pred = ~np.all(np.isfinite(p), axis=1)
    if missing == "hold":
        p = hold_missing(p)
    ov_all = iou(p, g)
    ce_all = center_error(p, g)
    nce_all = normalized_center_error(p, g)

    ov = ov_all[valid]
    ce = ce_all[valid]
    nce = nce_all[valid]

    success = _curve_gt(ov, SUCCESS_THRESHOLDS)
    precision = _curve_le(ce, PRECISION_THRESHOLDS)
    norm_precision = _curve_le(nce, NORM_PRECISION_THRESHOLDS)

    nan = np.full(n, np.nan)
    return OPEResult(
        success_curve=success,
        auc=float(np.mean(success)),
        success_50=_rate(ov > 0.5),
        precision_curve=precision,
        precision_20=_rate(ce <= 20.0),
        norm_precision_curve=norm_precision,
        norm_precision_20=_rate(nce <= 0.2),
        mean_iou=float(np.mean(ov)) if ov.size else float("nan"),
        mean_center_error=float(np.mean(ce)) if ce.size else float("nan"),
        n_frames=n,
        n_scored=int(valid.sum()),
        n_missing=int(n - valid.sum()),
        n_no_prediction=int(np.sum(no_pred & valid)),
        ious=np.where(valid, ov_all, nan),
        center_errors=np.where(valid, ce_all, nan),
        norm_center_errors=np.where(valid, nce_all, nan),
    )
