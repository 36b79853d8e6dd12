"""Tests of the VOT supervised protocol with a scripted tracker."""

from __future__ import annotations

import json
import math
from collections.abc import Callable

import numpy as np
import pytest

from wmiltrack.engine.result import TrackResult
from wmiltrack.eval.vot_style import run_supervised

BOX = (10.0, 10.0, 20.0, 20.0)
FAR = (200.0, 200.0, 20.0, 20.0)


def _iou_shift(s: int) -> float:
    inter = (20 - s) * 20
    return inter / (800 - inter)


class Scripted:
    """Reports the ground truth shifted right by ``frame % 3`` px; far away on ``lose`` frames.

    Frames are arrays holding their own index, so the tracker knows where it is.
    """

    def __init__(
        self, log: list[tuple[int, tuple[float, ...]]], lose: set[int], nan: set[int]
    ) -> None:
        self.log = log
        self.lose = lose
        self.nan = nan

    def init(self, frame: np.ndarray, box: tuple[float, ...]) -> None:
        self.log.append((int(frame[0]), tuple(box)))

    def update(self, frame: np.ndarray) -> TrackResult:
        i = int(frame[0])
        if i in self.nan:
            return TrackResult((math.nan,) * 4, math.nan, False)
        if i in self.lose:
            return TrackResult(FAR, 0.1, False)
        x, y, w, h = BOX
        return TrackResult((x + i % 3, y, w, h), 0.9, True)


def _setup(
    n: int, lose: set[int], nan: frozenset[int] = frozenset()
) -> tuple[
    Callable[[], Scripted], list[np.ndarray], np.ndarray, list[tuple[int, tuple[float, ...]]]
]:
    log: list[tuple[int, tuple[float, ...]]] = []
    frames = [np.array([i], dtype=np.int64) for i in range(n)]
    gt = np.tile(np.array(BOX), (n, 1))
    return (lambda: Scripted(log, lose, set(nan))), frames, gt, log


def test_failures_reinit_and_burnin() -> None:
    make, frames, gt, log = _setup(40, {12, 30})
    r = run_supervised(make, frames, gt)
    assert r.failures == 2
    assert r.failure_frames == [12, 30]
    assert r.init_frames == [0, 17, 35]  # f + 5
    assert [f for f, _ in log] == [0, 17, 35]  # a new tracker each time, init with the GT
    assert all(b == BOX for _, b in log)
    # frames between a failure and the re-initialisation are not tracked
    assert r.tracked.tolist() == [(i <= 12) or (17 <= i <= 30) or (i >= 35) for i in range(40)]
    assert np.isnan(r.boxes[13:17]).all() and np.isnan(r.overlaps[13:17]).all()
    assert r.overlaps[12] == 0.0 and r.overlaps[30] == 0.0
    # burn-in: 0..9, 17..26, 35..44 are left out, as are failure frames 12 and 30
    assert np.flatnonzero(r.accuracy_mask).tolist() == [10, 11, 27, 28, 29]
    expected = np.mean([_iou_shift(i % 3) for i in (10, 11, 27, 28, 29)])
    assert r.accuracy == pytest.approx(expected)
    assert r.failures_per_100 == pytest.approx(5.0)
    assert r.robustness == pytest.approx(math.exp(-100 * 2 / 40))


def test_no_failure_and_burnin_values() -> None:
    make, frames, gt, _ = _setup(20, set())
    r = run_supervised(make, frames, gt, burnin=3)
    assert r.failures == 0 and r.init_frames == [0] and r.robustness == 1.0
    assert np.flatnonzero(r.accuracy_mask).tolist() == list(range(3, 20))
    assert r.accuracy == pytest.approx(np.mean([_iou_shift(i % 3) for i in range(3, 20)]))
    # burnin=0 still leaves the initialisation frame out
    r0 = run_supervised(make, frames, gt, burnin=0)
    assert np.flatnonzero(r0.accuracy_mask).tolist() == list(range(1, 20))


def test_reinit_skips_frames_without_ground_truth() -> None:
    make, frames, gt, _ = _setup(30, {5})
    gt[10] = np.nan  # 5 + 5 has no ground truth
    gt[11] = [0, 0, 0, 0]  # nor does 11
    r = run_supervised(make, frames, gt, burnin=1)
    assert r.init_frames == [0, 12]
    assert not r.tracked[10] and not r.tracked[11]


def test_losing_where_gt_is_absent_is_not_a_failure() -> None:
    make, frames, gt, _ = _setup(20, {7})
    gt[7] = np.nan
    r = run_supervised(make, frames, gt)
    assert r.failures == 0
    assert r.tracked[7] and math.isnan(r.overlaps[7]) and not r.accuracy_mask[7]


def test_no_box_is_a_failure_and_late_failure_ends_run() -> None:
    make, frames, gt, _ = _setup(20, {18}, frozenset({4}))
    r = run_supervised(make, frames, gt, skip=5)
    assert r.failure_frames == [4, 18]
    assert r.init_frames == [0, 9]  # 18 + 5 is past the end: no re-initialisation
    assert not r.tracked[19]
    # burn-in covers 0..9 and 9..18, 18 is the failure: nothing is left to average
    assert not r.accuracy_mask.any() and math.isnan(r.accuracy)


def test_start_at_first_valid_frame_and_errors() -> None:
    make, frames, gt, _ = _setup(10, set())
    gt[0] = np.nan
    r = run_supervised(make, frames, gt)
    assert r.init_frames == [1]
    with pytest.raises(ValueError, match="ground-truth rows"):
        run_supervised(make, frames[:9], gt)
    with pytest.raises(ValueError, match="no frame"):
        run_supervised(make, frames, np.full((10, 4), np.nan))
    with pytest.raises(ValueError, match="skip"):
        run_supervised(make, frames, gt, skip=0)


def test_to_dict_is_json() -> None:
    make, frames, gt, _ = _setup(25, {12})
    d = run_supervised(make, frames, gt).to_dict(per_frame=True)
    back = json.loads(json.dumps(d, allow_nan=False))
    assert back["failures"] == 1 and back["init_frames"] == [0, 17]
    assert back["overlaps"][14] is None and back["boxes"][14] is None
