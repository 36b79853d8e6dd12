"""Tests of wmiltrack.eval.metrics against hand-computed cases."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from wmiltrack.eval.metrics import (
    NORM_PRECISION_THRESHOLDS,
    PRECISION_THRESHOLDS,
    SUCCESS_THRESHOLDS,
    center_error,
    iou,
    normalized_center_error,
    ope_metrics,
    valid_mask,
)


def _track(n: int, box: tuple[float, float, float, float]) -> np.ndarray:
    return np.tile(np.asarray(box, dtype=np.float64), (n, 1))


def test_thresholds_are_otbs() -> None:
    assert SUCCESS_THRESHOLDS.shape == (21,)
    assert SUCCESS_THRESHOLDS[0] == 0.0 and SUCCESS_THRESHOLDS[-1] == 1.0
    assert np.allclose(np.diff(SUCCESS_THRESHOLDS), 0.05)
    assert PRECISION_THRESHOLDS.tolist() == list(range(51))
    assert NORM_PRECISION_THRESHOLDS.shape == (51,)
    assert NORM_PRECISION_THRESHOLDS[-1] == 0.5


def test_iou_hand_cases() -> None:
    a = np.array(
        [
            [0, 0, 10, 10],
            [0, 0, 10, 10],
            [0, 0, 10, 10],
            [0, 0, 10, 10],
            [0, 0, 10, 10],
            [0, 0, 10, 10],
        ],
        dtype=float,
    )
    b = np.array(
        [
            [0, 0, 10, 10],  # identical
            [5, 5, 10, 10],  # 25 / (100 + 100 - 25)
            [10, 0, 10, 10],  # touching edges: continuous boxes do not overlap
            [2, 3, 4, 5],  # inside: 20 / 100
            [np.nan, 0, 10, 10],  # no prediction
            [20, 20, 5, 5],  # disjoint
        ]
    )
    got = iou(a, b)
    assert got == pytest.approx([1.0, 25 / 175, 0.0, 0.2, 0.0, 0.0])
    assert iou(b[:4], a[:4]) == pytest.approx(got[:4])  # symmetric


def test_iou_matches_otb_calc_rect_int_on_integers() -> None:
    # OTB: right = x + w - 1, overlap extent = min(right) - max(left) + 1.
    rng = np.random.default_rng(1)
    a = rng.integers(0, 50, size=(200, 4)).astype(float) + [0, 0, 1, 1]
    b = rng.integers(0, 50, size=(200, 4)).astype(float) + [0, 0, 1, 1]
    ra, rb = a[:, 0] + a[:, 2] - 1, b[:, 0] + b[:, 2] - 1
    ta, tb = a[:, 1] + a[:, 3] - 1, b[:, 1] + b[:, 3] - 1
    inter = np.maximum(0, np.minimum(ra, rb) - np.maximum(a[:, 0], b[:, 0]) + 1) * np.maximum(
        0, np.minimum(ta, tb) - np.maximum(a[:, 1], b[:, 1]) + 1
    )
    otb = inter / (a[:, 2] * a[:, 3] + b[:, 2] * b[:, 3] - inter)
    assert iou(a, b) == pytest.approx(otb)


def test_center_errors() -> None:
    a = np.array([[0, 0, 10, 20], [0, 0, 10, 20], [np.nan] * 4])
    b = np.array([[3, 4, 10, 20], [0, 0, 20, 40], [0, 0, 1, 1]])
    # centres (5,10) vs (8,14) -> 5;  (5,10) vs (10,20) -> hypot(5,10)
    assert center_error(a, b) == pytest.approx([5.0, math.hypot(5, 10), math.inf])
    # normalised by the second argument (ground truth): 3/10, 4/20
    assert normalized_center_error(a, b)[0] == pytest.approx(math.hypot(0.3, 0.2))
    assert normalized_center_error(a, b)[1] == pytest.approx(math.hypot(5 / 20, 10 / 40))
    assert normalized_center_error(a, b)[2] == math.inf


def test_valid_mask() -> None:
    gt = np.array([[1, 1, 5, 5], [np.nan] * 4, [1, 1, 0, 5], [1, 1, 5, -1], [0, 0, 1, 1]])
    assert valid_mask(gt).tolist() == [True, False, False, False, True]


def test_perfect_track() -> None:
    gt = _track(30, (10, 20, 30, 40))
    r = ope_metrics(gt.copy(), gt)
    # every IoU is 1: "IoU > t" holds for 20 of the 21 thresholds (not t = 1)
    assert r.success_curve.tolist() == [1.0] * 20 + [0.0]
    assert r.auc == pytest.approx(20 / 21)
    assert r.success_50 == 1.0
    assert r.precision_20 == 1.0
    assert r.precision_curve.tolist() == [1.0] * 51
    assert r.norm_precision_20 == 1.0
    assert r.mean_center_error == 0.0
    assert r.mean_iou == 1.0
    assert (r.n_frames, r.n_scored, r.n_missing, r.n_no_prediction) == (30, 30, 0, 0)


def test_constant_offset() -> None:
    gt = _track(10, (100, 100, 10, 20))
    pred = _track(10, (103, 104, 10, 20))
    # intersection 7 * 16 = 112, union 200 + 200 - 112 = 288, IoU = 112/288 = 0.3889
    r = ope_metrics(pred, gt)
    assert r.mean_iou == pytest.approx(112 / 288)
    # IoU > t for t = 0, 0.05, ..., 0.35: 8 of 21 thresholds
    assert r.success_curve.tolist() == [1.0] * 8 + [0.0] * 13
    assert r.auc == pytest.approx(8 / 21)
    assert r.success_50 == 0.0
    # centre error 5 px: error <= t for t = 5..50
    assert r.mean_center_error == pytest.approx(5.0)
    assert r.precision_curve.tolist() == [0.0] * 5 + [1.0] * 46
    assert r.precision_20 == 1.0
    # normalised: hypot(3/10, 4/20) = 0.3606 > 0.2
    assert r.norm_center_errors[0] == pytest.approx(math.hypot(0.3, 0.2))
    assert r.norm_precision_20 == 0.0
    assert r.norm_precision_curve[NORM_PRECISION_THRESHOLDS >= 0.37].min() == 1.0
    assert r.norm_precision_curve[NORM_PRECISION_THRESHOLDS <= 0.36].max() == 0.0


def test_half_good_half_offset() -> None:
    gt = _track(4, (0, 0, 10, 10))
    pred = np.array([[0, 0, 10, 10], [0, 0, 10, 10], [5, 0, 10, 10], [5, 0, 10, 10]], float)
    # IoU 1, 1, 1/3, 1/3;  centre errors 0, 0, 5, 5
    r = ope_metrics(pred, gt)
    expected = [(np.array([1, 1, 1 / 3, 1 / 3]) > t).mean() for t in SUCCESS_THRESHOLDS.tolist()]
    assert r.success_curve == pytest.approx(expected)
    # thresholds 0 .. 0.30 (7 points) -> 1.0;  0.35 .. 0.95 (13) -> 0.5;  1.0 -> 0
    assert r.auc == pytest.approx((7 * 1.0 + 13 * 0.5) / 21)
    assert r.success_50 == 0.5
    assert r.precision_curve[:5].tolist() == [0.5] * 5
    assert r.mean_center_error == pytest.approx(2.5)


def test_total_loss() -> None:
    gt = _track(20, (0, 0, 10, 10))
    far = _track(20, (500, 500, 10, 10))
    r = ope_metrics(far, gt)
    assert r.auc == 0.0 and r.success_50 == 0.0 and r.precision_20 == 0.0
    assert r.mean_center_error == pytest.approx(math.hypot(500, 500))
    none = np.full((20, 4), np.nan)
    r2 = ope_metrics(none, gt)
    assert r2.auc == 0.0 and r2.precision_20 == 0.0 and r2.norm_precision_20 == 0.0
    assert r2.n_no_prediction == 20
    assert math.isinf(r2.mean_center_error)  # a frame without a box is a miss here too
    # one frame without a box among perfect ones: the mean centre error is not the perfect 0
    one = gt.copy()
    one[5] = np.nan
    r3 = ope_metrics(one, gt)
    assert math.isinf(r3.mean_center_error) and r3.precision_20 == pytest.approx(19 / 20)
    assert np.all(np.isinf(r2.center_errors))


def test_missing_gt_frames_are_excluded_and_counted() -> None:
    gt = _track(10, (0, 0, 10, 10))
    gt[3] = np.nan
    gt[7] = [0, 0, 0, 10]
    pred = _track(10, (0, 0, 10, 10))
    pred[3] = [300, 300, 10, 10]  # wrong, but its frame is not scored
    pred[7] = [300, 300, 10, 10]
    pred[5] = [300, 300, 10, 10]  # wrong and scored: 1 of 8
    r = ope_metrics(pred, gt)
    assert (r.n_frames, r.n_scored, r.n_missing) == (10, 8, 2)
    assert r.success_50 == pytest.approx(7 / 8)
    assert r.precision_20 == pytest.approx(7 / 8)
    assert math.isnan(r.ious[3]) and math.isnan(r.ious[7])
    assert r.ious[5] == 0.0


def test_length_mismatch_is_a_clear_error() -> None:
    gt = _track(10, (0, 0, 10, 10))
    with pytest.raises(ValueError, match="9 boxes but the ground truth has 10"):
        ope_metrics(gt[:9], gt)
    with pytest.raises(ValueError, match="11 boxes"):
        ope_metrics(_track(11, (0, 0, 10, 10)), gt)
    with pytest.raises(ValueError, match=r"shape \(n, 4\)"):
        ope_metrics(np.zeros((10, 3)), gt)


def test_no_scored_frame_gives_nan() -> None:
    gt = np.full((3, 4), np.nan)
    r = ope_metrics(np.zeros((3, 4)), gt)
    assert r.n_missing == 3 and math.isnan(r.auc) and math.isnan(r.precision_20)


def test_to_dict_is_json() -> None:
    gt = _track(5, (0, 0, 10, 10))
    pred = gt.copy()
    pred[2] = np.nan
    d = ope_metrics(pred, gt).to_dict(per_frame=True)
    text = json.dumps(d, allow_nan=False)
    back = json.loads(text)
    assert back["n_no_prediction"] == 1
    assert back["center_errors"][2] == "inf"
    assert len(back["success_curve"]) == 21


def test_missing_hold_is_otb_toolkit_behaviour() -> None:
    gt = _track(6, (0, 0, 10, 10))
    pred = _track(6, (0, 0, 10, 10))
    pred[1] = [5, 0, 10, 10]
    pred[2] = np.nan  # held: (5, 0, 10, 10) -> IoU 1/3
    pred[3] = [1, 1, 0, 0]  # degenerate, held too
    miss = ope_metrics(pred, gt)
    hold = ope_metrics(pred, gt, missing="hold")
    assert miss.ious[2] == 0.0 and math.isinf(miss.center_errors[2])
    assert hold.ious[2] == pytest.approx(1 / 3) and hold.ious[3] == pytest.approx(1 / 3)
    assert hold.center_errors[2] == pytest.approx(5.0)
    assert miss.n_no_prediction == hold.n_no_prediction == 1  # NaN rows only
    with pytest.raises(ValueError, match="missing"):
        ope_metrics(pred, gt, missing="drop")  # type: ignore[arg-type]
    lead = _track(3, (0, 0, 10, 10))
    lead[0] = np.nan
    from wmiltrack.eval.metrics import hold_missing

    assert (
        np.isnan(hold_missing(lead)[0]).all()
        and hold_missing(lead)[1:].tolist() == [[0, 0, 10, 10]] * 2
    )
