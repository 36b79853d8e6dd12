"""Score a trajectory on a sequence from :func:`wmiltrack.data.layouts.load_layout` the way its
benchmark does.

* OPE figures (:func:`wmiltrack.eval.metrics.ope_metrics`) for every layout.  Absent frames are
  ``nan`` ground-truth rows, which ``ope_metrics`` leaves out.  When the sequence's
  ``meta["absent_policy"]`` is ``"fail"`` (LaSOT) they are put back as failures with
  :func:`count_absent_as_failures`, which is what LaSOT's toolkit computes
  (``HengLan/LaSOT_Evaluation_Toolkit``, ``utils/eval_tracker.m``: successes over the visible
  frames divided by the length of the sequence).
* GOT-10k figures (:func:`wmiltrack.eval.got10k_metrics.got10k_metrics`) for the GOT-10k layout,
  with the image size from ``meta_info.ini`` as the clipping bound.
* Nothing for sequences annotated on the first frame only (GOT-10k ``test``, TrackingNet
  ``TEST``): those are scored by the benchmarks' servers.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any, Literal

import numpy.typing as npt

from ..data.sequences import Sequence
from .got10k_metrics import GOT10kResult, got10k_metrics
from .metrics import OPEResult, ope_metrics

__all__ = ["BenchmarkScores", "benchmark_scores", "count_absent_as_failures"]


def count_absent_as_failures(result: OPEResult) -> OPEResult:
    """Turn OPE figures over the scored frames into figures over all frames, unscored ones failing.

    Parameters
    ----------
    result:
        From :func:`~wmiltrack.eval.metrics.ope_metrics`, which leaves frames with absent or
        degenerate ground truth out (``n_missing`` of them).

    Returns
    -------
    OPEResult
        Every curve, ``auc``, the rates and ``mean_iou`` multiplied by ``n_scored / n_frames``
        (an unscored frame fails every threshold and has overlap 0); counts, centre errors and
        per-frame arrays unchanged.  LaSOT's toolkit computes exactly this for the success and
        the (normalised) precision plots.
    """
    if result.n_frames == 0 or result.n_missing == 0:
        return result
    f = result.n_scored / result.n_frames
    return replace(
        result,
        success_curve=result.success_curve * f,
        auc=result.auc * f,
        success_50=result.success_50 * f,
        precision_curve=result.precision_curve * f,
        precision_20=result.precision_20 * f,
        norm_precision_curve=result.norm_precision_curve * f,
        norm_precision_20=result.norm_precision_20 * f,
        mean_iou=result.mean_iou * f,
    )


@dataclass(frozen=True)
class BenchmarkScores:
    """Figures of one trajectory on one benchmark sequence.

    Attributes
    ----------
    layout:
        The sequence's layout (``meta["layout"]``, ``"otb"`` if absent).
    ope:
        OPE figures with the benchmark's absent-frame policy applied; ``None`` if the sequence is
        annotated on its first frame only.
    got10k:
        GOT-10k figures for GOT-10k sequences, else ``None``.
    note:
        How absent frames were counted, or why nothing was scored.
    """

    layout: str
    ope: OPEResult | None
    got10k: GOT10kResult | None
    note: str

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-serialisable dictionary."""
        return {
            "layout": self.layout,
            "ope": None if self.ope is None else self.ope.to_dict(),
            "got10k": None if self.got10k is None else self.got10k.to_dict(),
            "note": self.note,
        }


def benchmark_scores(
    pred: npt.ArrayLike, seq: Sequence, *, missing: Literal["miss", "hold"] = "miss"
) -> BenchmarkScores:
    """Score ``pred`` on ``seq`` with its benchmark's conventions.

    Parameters
    ----------
    pred:
        ``(n, 4)`` boxes, one per frame including the first.
    seq:
        A sequence with ground truth, typically from :func:`wmiltrack.data.layouts.load_layout`.
    missing:
        Passed to :func:`~wmiltrack.eval.metrics.ope_metrics`.

    Returns
    -------
    BenchmarkScores

    Raises
    ------
    ValueError
        If the sequence has no ground truth or ``pred`` has the wrong shape.
    """
    if seq.groundtruth is None:
        raise ValueError(f"sequence {seq.name!r} has no ground truth to score against")
    layout = str(seq.meta.get("layout", "otb"))
    if seq.meta.get("first_frame_only", False):
        return BenchmarkScores(
            layout, None, None, "only the first frame is annotated: scored by the benchmark's server"
        )
    ope = ope_metrics(pred, seq.groundtruth, missing=missing)
    policy = seq.meta.get("absent_policy", "exclude")
    if policy == "fail":
        ope = count_absent_as_failures(ope)
        note = "absent frames count as failures (LaSOT toolkit)"
    else:
        note = "absent frames are left out"
    got: GOT10kResult | None = None
    if layout == "got10k":
        res = seq.meta.get("resolution")
        bound = (float(res[0]), float(res[1])) if res is not None else None
        got = got10k_metrics(pred, seq.groundtruth, bound=bound)
    return BenchmarkScores(layout, ope, got, note)
