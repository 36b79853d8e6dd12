"""The judge of ``TrackResult.ok``: a memory of the target and a delay before a verdict.

A tracker's own score follows the tracker: when the box drifts onto a distractor, everything
that learns (the classifier, the colour histograms, the live correlation filter) learns the
distractor, and the score stays up. The judge asks a part that never learnt since the first
frame, the correlation filter as it was then (kept by
:class:`~wmiltrack.engine.template.CorrelationTemplate`), how well the live filter's search
sample still answers it, blends that with the reported score, and changes its verdict only
after several frames agree (see :class:`~wmiltrack.engine.settings.JudgeSettings`).
"""

from __future__ import annotations

import math

from .policy import logistic
from .settings import JudgeSettings

__all__ = ["LostJudge"]


class LostJudge:
    """Whether the target is tracked, frame by frame, with hysteresis.

    :meth:`verdict` takes each frame's reported score and the first-frame filter's response
    peak on that frame (NaN when the filter did not search: that frame leaves the counts at
    zero and the verdict as it was). ``threshold``: the reported score at which the judge's
    score term is zero (the policy's ``lost_threshold``, given by
    :func:`~wmiltrack.engine.tracker.compose`).
    """

    def __init__(self, settings: JudgeSettings, *, threshold: float = 0.5) -> None:
        self.settings = settings
        self.threshold = threshold
        self.lost = False
        self.turned = False  # whether the last frame changed the verdict
        self._run = 0  # frames in a row that argue for changing the verdict

    def judged(self, score: float, first_peak: float) -> float:
        """The judged confidence in [0, 1] of one frame (NaN without a first-frame peak)."""
        s = self.settings
        if not (math.isfinite(first_peak) and math.isfinite(score)):
            return math.nan
        z = (s.judge_score * (score - self.threshold)
             + s.judge_memory * math.log(max(first_peak, 1e-6) / s.judge_peak))
        return logistic(z)

    def verdict(self, score: float, first_peak: float) -> bool:
        """Fold in one frame; whether the target counts as tracked on it."""
        s = self.settings
        c = self.judged(score, first_peak)
        against = c < s.judge_low if not self.lost else c > s.judge_high  # False for NaN
        self._run = self._run + 1 if against else 0
        self.turned = self._run >= (s.judge_leave if self.lost else s.judge_enter)
        if self.turned:
            self.lost = not self.lost
            self._run = 0
        return not self.lost
