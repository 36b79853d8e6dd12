"""OpenCV-shaped use: frames from cv2.VideoCapture, gray frames, int/float boxes, reinit, score."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

import wmiltrack
from wmiltrack.compat import TrackerCompat, TrackerCT, TrackerRCWMIL
from wmiltrack.data.synthetic import make_sequence
from wmiltrack.eval.metrics import iou


@pytest.fixture(scope="module")
def seq() -> tuple[list[np.ndarray], np.ndarray]:
    s = make_sequence(40, seed=3, occlusion=False, illumination=False, clutter=False)
    gt = s.groundtruth
    assert gt is not None
    return s.load(), np.asarray(gt)


def test_video_capture_frames_drop_in(seq: tuple[list[np.ndarray], np.ndarray], tmp_path: Path) -> None:
    frames, gt = seq
    path = tmp_path / "clip.avi"
    h, w = frames[0].shape[:2]
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 25.0, (w, h))
    assert writer.isOpened()
    for f in frames:
        writer.write(f)
    writer.release()

    cap = cv2.VideoCapture(str(path))
    ok, frame = cap.read()
    assert ok and frame.shape == (h, w, 3)
    tracker = TrackerRCWMIL.create()
    x, y, bw, bh = (int(v) for v in gt[0])
    assert tracker.init(frame, (x, y, bw, bh)) is None     # OpenCV >= 4.5: init returns None
    boxes = [gt[0]]
    while True:
        ok, frame = cap.read()
        if not ok:
            break
        ok, rect = tracker.update(frame)
        assert isinstance(ok, bool) and len(rect) == 4 and all(type(v) is int for v in rect)
        assert 0.0 <= tracker.getTrackingScore() <= 1.0
        boxes.append(np.array(rect, dtype=float))
    cap.release()
    assert len(boxes) == len(frames)
    assert float(np.mean(iou(np.array(boxes), gt))) > 0.6
    assert tracker.last_result is not None and tracker.last_result.ok


def test_gray_frames_float_and_int_boxes_agree(seq: tuple[list[np.ndarray], np.ndarray]) -> None:
    frames, gt = seq
    gray = [cv2.cvtColor(f, cv2.COLOR_BGR2GRAY) for f in frames[:10]]
    a = wmiltrack.Tracker("rcwmil", seed=0)
    b = wmiltrack.Tracker("rcwmil", seed=0)
    a.init(gray[0], tuple(int(round(v)) for v in gt[0]))
    b.init(frames[0], tuple(float(round(v)) for v in gt[0]))   # BGR, float box: same luma, same box
    for g, f in zip(gray[1:], frames[1:10]):
        ok_a, box_a = a.update(g)
        ok_b, box_b = b.update(f)
        assert box_a == box_b


def test_reinit_restarts_without_rebuilding(seq: tuple[list[np.ndarray], np.ndarray]) -> None:
    frames, gt = seq
    t = wmiltrack.Tracker("rcwmil", seed=0)
    t.init(frames[0], gt[0])
    first = [t.update(f).box for f in frames[1:6]]
    same = t
    t.reinit(frames[0], gt[0])
    assert t is same and [t.update(f).box for f in frames[1:6]] == first
    t.reinit(frames[10], gt[10])            # restart somewhere else in the sequence
    assert t.update(frames[11]).ok


def test_create_with_params_and_overrides() -> None:
    t = TrackerCT.create({"num_features": 30, "num_selected": 30})
    assert t.tracker.params.variant == "ct" and t.tracker.params.num_features == 30
    p = wmiltrack.Params.for_variant("rcwmil", num_selected=10)
    assert TrackerRCWMIL.create(p).tracker.params.num_selected == 10
    assert TrackerCompat("wmil").tracker.variant == "wmil"
    with pytest.raises(TypeError, match="params"):
        TrackerRCWMIL.create(42)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="before getTrackingScore"):  # no target yet
        TrackerRCWMIL.create().getTrackingScore()


def test_score_drops_when_the_target_vanishes() -> None:
    """The documented rule: ok (score >= lost_threshold) while tracked, mostly not once gone."""
    s = make_sequence(60, seed=1, occlusion=False, illumination=False, clutter=True)
    other = make_sequence(60, seed=501, occlusion=False, illumination=False, clutter=True).load()
    frames = s.load()[:30] + other[30:]
    gt = s.groundtruth
    assert gt is not None
    t = wmiltrack.Tracker("rcwmil", seed=0)
    t.init(frames[0], gt[0])
    res = [t.update(f) for f in frames[1:]]
    before = np.array([r.score for r in res[:29]])
    after = np.array([r.score for r in res[29:]])
    assert np.median(before) > 0.5 > np.median(after)
    assert np.mean([r.ok for r in res[:29]]) > 0.8
    assert np.mean([not r.ok for r in res[29:]]) > 0.6
