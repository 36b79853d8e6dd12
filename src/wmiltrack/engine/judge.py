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
from dataclasses import dataclass
from typing import NamedTuple

from .policy import logistic
from .recovery import check_recover_memory
from .settings import check_ints, check_numbers, need
from .state import FrameState, Verdict

__all__ = ["NO_EVIDENCE", "Evidence", "FrameJudge", "JudgeSettings"]

# a tracked frame's verdicts, read once (an enum member read from its class costs ~70 ns)
_TRACKED, _DOUBTFUL = Verdict.TRACKED, Verdict.DOUBTFUL


@dataclass(frozen=True)
class JudgeSettings:
    """The judge (:class:`wmiltrack.engine.judge.FrameJudge`): each frame's verdict (tracked,
    doubtful, lost, found), hence ``TrackResult.ok``, the lost state and what learns.

    Without its memory (``judge_memory = 0``), ``ok`` is the reported score against
    ``lost_threshold``, frame by frame.
    A tracker that drifted onto a distractor keeps a high score there (everything it learns
    follows it), so on the 34 development sequences that rule flags 12.8 % of well-tracked
    frames and misses 28 % of the frames off the target. The judge adds a memory and a delay:

    * a memory of the target: the correlation filter as it was on the first frame, never
      trained again, answers the live filter's search sample each frame; its response peak
      stays up on the target and falls on whatever the live filter drifted to;
    * the judged confidence is ``logistic(judge_score * (score - lost_threshold) +
      judge_memory * ln(first_peak / judge_peak))``;
    * hysteresis: the target counts as lost after ``judge_enter`` frames in a row judged below
      ``judge_low``, and as found again after ``judge_leave`` frames in a row above
      ``judge_high``.

    Only ``ok`` changes: the boxes are the same with the memory or without it. Needs the
    correlation-filter template (``template_weight > 0`` or ``template_motion``).

    With ``redetect``, the judge also starts the lost state: a frame whose classifier
    confidence drops below ``lost_drop`` times its running mean over tracked frames, while the
    cues' own confidences and the box's correlation with the recovery's grey template fell
    alike, is lost: the box is held at the last confident one, ``ok`` is False and nothing
    learns; each lost frame the target is found again where the usual search around the held
    box sees the confidence back, or where the recovery finds it over the whole frame
    (:class:`~wmiltrack.engine.recovery.RecoverySettings`).

    Attributes
    ----------
    lost_threshold : float
        ``TrackResult.ok`` is False when the reported score falls below this; the motion
        model takes a frame's move as a velocity only when the classifier's confidence is at
        least this.
    redetect : bool
        Whether a lost target is held, not learnt, and searched for over the whole frame.
    lost_drop : float
        A frame counts as lost when its confidence is below this fraction of the running mean
        confidence of the tracked frames (in (0, 1)).
    recover_memory : float
        Weight of the old value in the running means of the confidence and the cues' own
        confidences, in [0, 1) (shared with
        :class:`~wmiltrack.engine.recovery.RecoverySettings`: one rate for the running means
        of the lost state).
    recover_warmup : int
        Tracked frames before the first judgement: the first frames' confidence is inflated
        (the classifier has just been trained on the first box) and their running mean not yet
        formed.
    judge_memory : float
        Weight of the log of the first-frame filter's peak; 0 leaves the judge out.
    judge_score : float
        Weight of the reported score's distance from ``lost_threshold``.
    judge_peak : float
        The first-frame filter's peak at which that term is 0.
    judge_low, judge_high : float
        The judged confidence below which a frame counts against the target, and above which
        it counts for it, in (0, 1) with ``judge_low <= judge_high``.
    judge_enter, judge_leave : int
        Frames in a row that start and end the lost state (>= 1).
    judge_gates : bool
        While the judge holds the target for lost, no part learns (the boxes then change).
    judge_holds : bool
        When the judge's verdict turns to lost, the tracker enters the recovery's lost state
        (``redetect``): the box is held, nothing learns, and the target is looked for over
        the whole frame until the classifier or the re-detection finds it again.
    """

    lost_threshold: float = 0.5
    redetect: bool = False
    lost_drop: float = 0.6
    recover_memory: float = 0.9
    recover_warmup: int = 10
    judge_memory: float = 0.0
    judge_score: float = 8.0
    judge_peak: float = 0.082
    judge_low: float = 0.4
    judge_high: float = 0.9
    judge_enter: int = 3
    judge_leave: int = 2
    judge_gates: bool = False
    judge_holds: bool = False

    def __post_init__(self) -> None:
        JudgeSettings.check(self)

    def check(self) -> None:
        """``ValueError`` naming the first setting out of range."""
        check_numbers(self, "lost_threshold")
        need(0.0 <= self.lost_threshold <= 1.0,
             f"lost_threshold must be in [0, 1], got {self.lost_threshold}")
        need(isinstance(self.redetect, bool), f"redetect must be True or False, got {self.redetect!r}")
        check_numbers(self, "lost_drop")
        need(0.0 < self.lost_drop < 1.0, f"lost_drop must be in (0, 1), got {self.lost_drop}")
        check_recover_memory(self)
        check_ints(self, "recover_warmup")
        need(self.recover_warmup >= 0, f"recover_warmup must be >= 0, got {self.recover_warmup}")
        check_numbers(self, "judge_memory", "judge_score", "judge_peak", "judge_low", "judge_high")
        check_ints(self, "judge_enter", "judge_leave")
        need(self.judge_memory >= 0.0, f"judge_memory must be >= 0, got {self.judge_memory}")
        need(self.judge_score >= 0.0, f"judge_score must be >= 0, got {self.judge_score}")
        need(self.judge_peak > 0.0, f"judge_peak must be > 0, got {self.judge_peak}")
        need(0.0 < self.judge_low <= self.judge_high < 1.0,
             f"judge_low and judge_high must satisfy 0 < judge_low <= judge_high < 1, got "
             f"{self.judge_low} and {self.judge_high}")
        need(self.judge_enter >= 1, f"judge_enter must be >= 1, got {self.judge_enter}")
        need(self.judge_leave >= 1, f"judge_leave must be >= 1, got {self.judge_leave}")
        need(isinstance(self.judge_gates, bool),
             f"judge_gates must be True or False, got {self.judge_gates!r}")
        need(isinstance(self.judge_holds, bool),
             f"judge_holds must be True or False, got {self.judge_holds!r}")


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
    """The built-in judge (:class:`JudgeSettings`).

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
