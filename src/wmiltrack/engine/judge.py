"""The judge: the one place that decides what a frame means, its verdict (tracked, doubtful, lost,
found), hence ``TrackResult.ok``, the lost state, whether the parts learn, and whether the
motion model takes the frame's move as a velocity.

Three rules, each with its own memory, kept in one part:

* the threshold: ``ok`` while the reported score is at least ``lost_threshold``;
* the memory of the target (``judge_memory > 0``): a tracker's own score follows the tracker;
  when the box drifts onto a distractor, everything that learns (the classifier, the colour
  histograms, the live correlation filter) learns the distractor, and the score stays up. The
  correlation filter as it was on the first frame, never trained since, says how well the live
  filter's search sample still answers it; that is blended with the reported score, and the
  verdict changes only after several frames agree (hysteresis);
* the lost state (``redetect``): a target that disappears takes the classifier's confidence
  down by half from one frame to the next, while lighting and pose change it over tens of
  frames; the confidence is read against its own running mean over tracked frames, and the
  cues' own confidences and the box's likeness to the recovery's grey template must fall
  alike before the frame counts as lost.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import NamedTuple

from .policy import logistic
from .settings import JudgeSettings
from .state import FrameState, Verdict

__all__ = ["NO_EVIDENCE", "Evidence", "FrameJudge"]

# a tracked frame's verdicts, read once (an enum member read from its class costs ~70 ns)
_TRACKED, _DOUBTFUL = Verdict.TRACKED, Verdict.DOUBTFUL


class Evidence(NamedTuple):
    """What the judge weighs besides the frame's record, gathered by the tracker from the other
    parts: the cues' own confidences on this frame (:class:`~wmiltrack.engine.cues.Cue`), the
    box's likeness to the recovery's picture of the target (a call giving ``(likeness, its
    running mean)``, or None without one: :meth:`~wmiltrack.engine.recovery.Redetector.likeness`)
    and the first-frame correlation filter's response peak on this frame (NaN without it)."""

    witnesses: tuple[float, ...] = ()
    look: Callable[[], tuple[float, float] | None] | None = None
    first_peak: float = math.nan


#: No evidence besides the record (a paper preset's frame).
NO_EVIDENCE = Evidence()


class FrameJudge:
    """The built-in judge (:class:`~wmiltrack.engine.settings.JudgeSettings`).

    State: ``lost`` whether the memory of the target holds it for lost, ``turned`` whether the
    last frame changed that; ``reference`` the running mean of the classifier's confidence over
    tracked frames (None right after the start or a re-detection), ``witnesses`` those of the
    cues' own confidences, ``seen`` the tracked frames judged since then.
    """

    def __init__(self, settings: JudgeSettings) -> None:
        self.settings = settings
        self.lost = False
        self.turned = False
        self._run = 0  # frames in a row that argue for changing the memory's verdict
        self.reference: float | None = None
        self.witnesses: list[float] = []
        self.seen = 0

    def start(self, frame: object, box: object) -> None:
        """No history: the first frame is tracked."""
        self.lost = self.turned = False
        self._run = 0
        self._forget()

    @property
    def always_learns(self) -> bool:
        """Whether every frame's verdict lets the parts learn (no lost state, no gate): a
        paper preset's frame may then learn in the same core call that locates."""
        s = self.settings
        return not (s.redetect or s.judge_gates or s.judge_holds)

    # -- the verdict ---------------------------------------------------------------------
    def back(self, state: FrameState, evidence: Evidence) -> bool:
        """Whether a lost target's frame found it again at the located box: its confidence or
        its likeness to the target is back above ``lost_drop`` times the running mean. The
        cues' own confidences are not asked: a cue that learnt the target's surroundings (the
        correlation filter's padding) answers nearly as well on the place it left."""
        return not self._dropped(state.conf, evidence.look, ())

    def verdict(self, state: FrameState, evidence: Evidence) -> FrameState:
        """The record with the frame's verdict, ``ok``, ``learns`` and ``steady`` (and, for a
        lost frame, the box held at the last one and score 0)."""
        if state.lost:
            return self._lost_frame(state, evidence)
        if self.settings.redetect:
            if self._dropped(state.conf, evidence.look, evidence.witnesses):
                self._tracked(0.0, evidence.first_peak)  # (the memory counts the frame)
                return state.evolve(box=state.previous, score=0.0, verdict=Verdict.LOST,
                                    ok=False, learns=False, steady=False)
            self._remember(state.conf, evidence.witnesses)
        tracked = self._tracked(state.score, evidence.first_peak)
        if self.lost and self.turned and self.settings.judge_holds:  # the box stays
            return state.evolve(score=0.0, verdict=Verdict.LOST, ok=False, learns=False,
                                steady=False)
        return state.judged(_TRACKED if tracked else _DOUBTFUL, tracked, self._learns(),
                            state.conf >= self.settings.lost_threshold)

    def _lost_frame(self, state: FrameState, evidence: Evidence) -> FrameState:
        """A lost target's frame: found where the recovery placed the box (``rescued``: the
        running means start again) or where the usual search sees it back; else lost."""
        if state.rescued:
            self._forget()  # the classifier may have fallen behind the target's look
        elif not self.back(state, evidence):
            self._tracked(0.0, evidence.first_peak)
            return state.evolve(box=state.previous, score=0.0, verdict=Verdict.LOST, ok=False,
                                learns=False, steady=False)
        return state.evolve(verdict=Verdict.FOUND, ok=self._tracked(state.score,
                                                                     evidence.first_peak),
                            learns=self._learns(), steady=False)

    def _learns(self) -> bool:
        """Whether the parts learn from a frame that is not lost (not while the memory holds
        the target for lost, with ``judge_gates``)."""
        return not (self.lost and self.settings.judge_gates)

    # -- the threshold and the memory of the target --------------------------------------
    def judged(self, score: float, first_peak: float) -> float:
        """The memory's judged confidence in [0, 1] of one frame (NaN without a peak)."""
        s = self.settings
        if not (math.isfinite(first_peak) and math.isfinite(score)):
            return math.nan
        z = (s.judge_score * (score - s.lost_threshold)
             + s.judge_memory * math.log(max(first_peak, 1e-6) / s.judge_peak))
        return logistic(z)

    def _tracked(self, score: float, first_peak: float) -> bool:
        """Fold in one frame's reported score (once per frame); whether it counts as tracked:
        the threshold, or with ``judge_memory`` the memory's verdict, which changes after
        ``judge_enter`` frames in a row below ``judge_low`` (``judge_leave`` above
        ``judge_high``); a frame without a first-frame peak leaves it as it was."""
        s = self.settings
        if s.judge_memory <= 0:
            return score >= s.lost_threshold
        c = self.judged(score, first_peak)
        against = c < s.judge_low if not self.lost else c > s.judge_high  # False for NaN
        self._run = self._run + 1 if against else 0
        self.turned = self._run >= (s.judge_leave if self.lost else s.judge_enter)
        if self.turned:
            self.lost = not self.lost
            self._run = 0
        return not self.lost

    # -- the lost state's running means --------------------------------------------------
    def _dropped(self, conf: float, look: Callable[[], tuple[float, float] | None] | None,
                 witnesses: tuple[float, ...]) -> bool:
        """Whether the classifier's confidence, every cue's own confidence and the box's
        likeness to the target all fell below ``lost_drop`` times their running means (a
        target that changes its look keeps one of them; one that is hidden or gone loses
        all)."""
        drop, ref = self.settings.lost_drop, self.reference
        if ref is None or self.seen < self.settings.recover_warmup or conf >= drop * ref:
            return False  # (NaN: dropped)
        for value, mean in zip(witnesses, self.witnesses):
            if value >= drop * mean:
                return False
        likeness = look() if look is not None else None
        if likeness is None:
            return True
        m, usual = likeness
        return not m >= drop * usual

    def _remember(self, conf: float, witnesses: tuple[float, ...]) -> None:
        """A tracked frame's confidences join their running means."""
        ref, a = self.reference, self.settings.recover_memory
        self.reference = conf if ref is None else a * ref + (1.0 - a) * conf
        if len(self.witnesses) != len(witnesses):
            self.witnesses = list(witnesses)
        else:
            self.witnesses = [a * m + (1.0 - a) * v for m, v in zip(self.witnesses, witnesses)]
        self.seen += 1

    def _forget(self) -> None:
        """The running means start again."""
        self.reference = None
        self.witnesses = []
        self.seen = 0
