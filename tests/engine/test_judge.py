"""The judge of ``ok`` (rcwmil-cf): a first-frame filter as a memory of the target, blended
with the reported score, with hysteresis; only ``ok`` changes, never a box."""

from __future__ import annotations

import math

import numpy as np
import pytest

import wmiltrack
from wmiltrack.data.synthetic import make_sequence
from wmiltrack.engine.judge import Evidence, FrameJudge, JudgeSettings
from wmiltrack.engine.state import FrameState, Verdict, new_frame

_FRAME = np.zeros((4, 4), np.uint8)
_START = FrameState(_FRAME, (0, 0, 2, 2), box=(0, 0, 2, 2), verdict=Verdict.TRACKED, ok=True)


class _Judge(FrameJudge):
    """The judge with its memory, fed one (score, first-frame peak) at a time."""

    def __init__(self, **kw: float) -> None:
        super().__init__(JudgeSettings(judge_memory=3.0, **kw))  # type: ignore[arg-type]

    def verdict_of(self, score: float, first_peak: float) -> bool:
        state = new_frame(_FRAME, _START, None).evolve(conf=score, score=score)
        return self.verdict(state, Evidence(first_peak=first_peak)).ok


def _judge(**kw: float) -> _Judge:
    return _Judge(**kw)


def test_judged_confidence_is_the_documented_logistic() -> None:
    j = _judge()
    assert j.memory_confidence(0.5, 0.082) == pytest.approx(0.5)
    z = 8.0 * (0.7 - 0.5) + 3.0 * math.log(0.2 / 0.082)
    assert j.memory_confidence(0.7, 0.2) == pytest.approx(1.0 / (1.0 + math.exp(-z)))
    assert math.isnan(j.memory_confidence(0.7, math.nan))


def test_lost_after_three_low_frames_in_a_row_and_back_after_two_high() -> None:
    j = _judge()
    low, high, middling = (0.1, 0.01), (0.9, 0.5), (0.55, 0.09)
    assert j.verdict_of(*low) and j.verdict_of(*low)
    assert j.verdict_of(*middling)  # breaks the run: not lost yet
    assert j.verdict_of(*low) and j.verdict_of(*low)
    assert not j.verdict_of(*low)  # the third low frame in a row
    assert not j.verdict_of(*middling) and not j.verdict_of(*high)
    assert not j.verdict_of(*low)  # a low frame breaks the run of high ones
    assert not j.verdict_of(*high)
    assert j.verdict_of(*high)  # the second high frame in a row
    assert j.verdict_of(0.9, math.nan)  # a frame without the filter's search changes nothing


def test_settings_are_checked() -> None:
    with pytest.raises(ValueError, match="judge_low"):
        JudgeSettings(judge_low=0.9, judge_high=0.4)
    with pytest.raises(ValueError, match="judge_enter"):
        JudgeSettings(judge_enter=0)
    with pytest.raises(ValueError, match="needs the correlation-filter template"):
        wmiltrack.Tracker("rcwmil-plus", judge_memory=3.0)


def _run(seq: object, **kw: object) -> tuple[np.ndarray, np.ndarray]:
    frames, gt = seq.load(), seq.groundtruth  # type: ignore[attr-defined]
    t = wmiltrack.Tracker("rcwmil-cf", seed=0, **kw)
    t.init(frames[0], tuple(gt[0]))
    rs = [t.update(f) for f in frames[1:]]
    return np.array([r.box for r in rs]), np.array([r.ok for r in rs])


def test_the_judge_changes_ok_only_and_flags_a_target_out_of_view() -> None:
    seq = make_sequence(120, seed=2, out_of_view=(50, 30))
    boxes, ok = _run(seq, judge_gates=False, judge_holds=False)
    plain_boxes, plain_ok = _run(seq, judge_memory=0.0, judge_gates=False, judge_holds=False)
    assert np.array_equal(boxes, plain_boxes)
    assert not np.array_equal(ok, plain_ok)  # the verdicts do differ
    gone = ok[49 + 3:49 + 30]  # update i is frame i + 1; the judge waits 3 frames
    assert (~gone).mean() >= 0.8
    assert ok[:45].all()  # the target in view and tracked from the start


def test_gating_and_holding_need_the_judge_and_the_lost_state() -> None:
    with pytest.raises(ValueError, match="need the judge"):
        wmiltrack.Tracker("rcwmil-cf", judge_memory=0.0)
    with pytest.raises(ValueError, match="redetect"):
        wmiltrack.Tracker("rcwmil-cf", redetect=False)
    wmiltrack.Tracker("rcwmil-cf", redetect=False, judge_holds=False)  # gating alone is fine


def test_while_the_judge_holds_the_target_for_lost_nothing_learns() -> None:
    """With ``judge_gates`` a frame the judge holds for lost teaches no part: the classifier's
    bags are empty and the template's filter is left as it was."""
    seq = make_sequence(100, seed=2, out_of_view=(40, 40))
    frames, gt = seq.load(), seq.groundtruth
    t = wmiltrack.Tracker("rcwmil-cf", seed=0, judge_holds=False)
    t.init(frames[0], tuple(gt[0]))
    judged_lost = 0
    for f in frames[1:80]:
        template = t.parts.template
        assert template is not None
        before = template.filter.copy()
        t.update(f)
        judge = t.parts.judge
        assert judge is not None
        if judge.memory_lost and not judge.turned:
            judged_lost += 1
            pos, neg = t.samples()["positive"], t.samples()["negative"]
            assert len(pos) == 0 and len(neg) == 0
            probe = template.filter.locate(frames[0], (gt[0][0] + gt[0][2] / 2, gt[0][1] + gt[0][3] / 2))
            old = before.locate(frames[0], (gt[0][0] + gt[0][2] / 2, gt[0][1] + gt[0][3] / 2))
            assert probe.peak == old.peak
    assert judged_lost >= 10


def test_when_the_judge_turns_to_lost_the_tracker_enters_the_lost_state() -> None:
    seq = make_sequence(100, seed=2, out_of_view=(40, 40))
    frames, gt = seq.load(), seq.groundtruth
    t = wmiltrack.Tracker("rcwmil-cf", seed=0)
    t.init(frames[0], tuple(gt[0]))
    entered = 0
    for f in frames[1:]:
        t.update(f)
        judge = t.parts.judge
        assert judge is not None
        if judge.turned and judge.memory_lost:
            assert t.lost  # the recovery looks for the target from the next frame
            entered += 1
    assert entered >= 1
