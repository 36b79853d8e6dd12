"""The judge: the one place that decides what a frame means, its verdict (tracked, doubtful, lost,
found), hence ``TrackResult.ok``, the lost state, whether the parts learn, and whether the
motion model takes the frame's move as a velocity.

Four rules, each with its own memory, kept in one part, one verdict a frame:

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
  alike before the frame counts as lost;
* a second expert (rcwmil-nano's network, the record's ``expert``): its box and the box's
  likeness to the expert's memory of the target are weighed with the tracker's box and ``ok``;
  the frame's verdict, box and score are then the experts' (see :class:`JudgeSettings`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import NamedTuple

from .geometry import overlap, placed_at, within
from .policy import logistic
from .recovery import check_recover_memory
from .settings import check_ints, check_numbers, need
from .state import ExpertReport, FrameState, Verdict

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
      ``judge_high`` (the one pair of hysteresis settings: the second expert's rule below
      counts its frames with them too).

    Only ``ok`` changes: the boxes are the same with the memory or without it. Needs the
    correlation-filter template (``template_weight > 0`` or ``template_motion``).

    With ``redetect``, the judge also starts the lost state: a frame whose classifier
    confidence drops below ``lost_drop`` times its running mean over tracked frames, while the
    cues' own confidences and the box's correlation with the recovery's grey template fell
    alike, is lost: the box is held at the last confident one, ``ok`` is False and nothing
    learns; each lost frame the target is found again where the usual search around the held
    box sees the confidence back, or where the recovery finds it over the whole frame
    (:class:`~wmiltrack.engine.recovery.RecoverySettings`).

    With a second expert (``network``, rcwmil-nano), its evidence decides the frame: where its
    box and the tracker's agree (IoU >= ``expert_agree``) the frame's box is their mix, the
    tracker's share ``expert_blend``; where they do not, the expert's. A frame counts against
    the target when the expert's likeness is below ``like_low``, or below ``like_drop`` times
    the running mean of the tracked frames' likeness (``like_rate`` a frame), unless the
    experts agree and the tracker says ``ok`` (two experts that agree are rarely both wrong);
    ``judge_enter`` such frames in a row start the lost state, ``judge_leave`` frames in a row
    above both ``like_high`` and ``like_found`` times the mean end it. On frames the experts
    vouch for, the likeness is measured every ``likeness_every``-th. The tracker learns at the
    frame's box (moved there at its own size) on a tracked frame that does not count against
    the target, and learns nothing while it does or the target is lost.

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
    expert_agree : float
        The IoU of the second expert's and the tracker's boxes at which they agree.
    expert_blend : float
        The tracker's share of the frame's box where they agree, in [0, 1].
    like_low, like_high : float
        The likeness below which a frame counts against the target and above which a lost
        frame counts for it.
    like_drop : float
        The share of the likeness's running mean below which a frame counts against the
        target (0: never).
    like_found : float
        The share of the running mean above which a lost frame counts for the target (with
        ``like_high``), at least ``like_drop``.
    like_rate : float
        The running mean's learning rate, in (0, 1].
    likeness_every : int
        On frames where the experts agree and the tracker says ``ok`` (which never count
        against the target), the likeness is measured only every ``likeness_every``-th such
        frame (it may cost a pass of the network); the reported score repeats the last
        measured one in between. 1: every frame.
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
    expert_agree: float = 0.3
    expert_blend: float = 0.2
    like_low: float = 0.45
    like_high: float = 0.6
    like_drop: float = 0.8
    like_found: float = 0.9
    like_rate: float = 0.05
    likeness_every: int = 1

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
        self._check_experts()

    def _check_experts(self) -> None:
        """The second expert's rule's settings."""
        check_ints(self, "likeness_every")
        need(self.likeness_every >= 1, f"likeness_every must be >= 1, got {self.likeness_every}")
        check_numbers(self, "expert_agree", "expert_blend", "like_low", "like_high", "like_drop",
                      "like_found", "like_rate")
        need(0.0 <= self.like_drop <= self.like_found <= 1.0,
             f"like_drop and like_found must satisfy 0 <= like_drop <= like_found <= 1, got "
             f"{self.like_drop} and {self.like_found}")
        need(0.0 < self.like_rate <= 1.0, f"like_rate must be in (0, 1], got {self.like_rate}")
        need(0.0 <= self.expert_agree <= 1.0, f"expert_agree must be in [0, 1], got {self.expert_agree}")
        need(0.0 <= self.expert_blend <= 1.0, f"expert_blend must be in [0, 1], got {self.expert_blend}")
        need(-1.0 <= self.like_low <= self.like_high <= 1.0,
             f"like_low and like_high must satisfy -1 <= like_low <= like_high <= 1, got "
             f"{self.like_low} and {self.like_high}")


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

    State: ``memory_lost`` whether the memory of the target holds it for lost, ``turned`` whether the
    last frame changed that; ``reference`` the running mean of the classifier's confidence over
    tracked frames (None right after the start or a re-detection), ``witnesses`` those of the
    cues' own confidences, ``seen`` the tracked frames judged since then; with a second
    expert, ``typical`` the running mean of its likeness over tracked frames and ``shown`` the
    last measured confidence, ``experts_lost`` whether the second expert's rule holds the
    target for lost.
    """

    def __init__(self, settings: JudgeSettings) -> None:
        self.settings = settings
        self.memory_lost = False
        self.turned = False
        self._run = 0  # frames in a row that argue for changing the memory's verdict
        self.reference: float | None = None
        self.witnesses: list[float] = []
        self.seen = 0
        self._restart_experts()

    def start(self, frame: object, box: object) -> None:
        """No history: the first frame is tracked."""
        self.memory_lost = self.turned = False
        self._run = 0
        self._forget()
        self._restart_experts()

    def _restart_experts(self) -> None:
        """The second expert's rule without history."""
        self.typical = math.nan
        self.shown = 1.0
        self.experts_lost = False
        self._against = 0  # frames in a row that argue for changing the experts' verdict
        self._since = 0  # vouched frames since the likeness was last measured

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
        lost frame, the box held at the last one and score 0); with a second expert's report
        (``state.expert``), the tracker's own judgement is weighed with it and the frame's
        box (``exact``, and the tracker's ``box`` where it learns there) and score are the
        experts' (:meth:`_weigh_experts`)."""
        if state.rested:  # (the tracker did not look: its judgement of the last frame stands)
            own = state.judged(_TRACKED, True, True, True)
        else:
            own = self._own_verdict(state, evidence)
        return own if state.expert is None else self._weigh_experts(own, state.expert)

    def _own_verdict(self, state: FrameState, evidence: Evidence) -> FrameState:
        """The tracker's own judgement of the frame (the first three rules)."""
        if state.lost:
            return self._lost_frame(state, evidence)
        if self.settings.redetect:
            if self._dropped(state.conf, evidence.look, evidence.witnesses):
                self._tracked(0.0, evidence.first_peak)  # (the memory counts the frame)
                return state.evolve(box=state.previous, score=0.0, verdict=Verdict.LOST,
                                    ok=False, learns=False, steady=False)
            self._remember(state.conf, evidence.witnesses)
        tracked = self._tracked(state.score, evidence.first_peak)
        if self.memory_lost and self.turned and self.settings.judge_holds:  # the box stays
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
        return not (self.memory_lost and self.settings.judge_gates)

    # -- the threshold and the memory of the target --------------------------------------
    def memory_confidence(self, score: float, first_peak: float) -> float:
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
        c = self.memory_confidence(score, first_peak)
        against = c < s.judge_low if not self.memory_lost else c > s.judge_high  # False for NaN
        self._run = self._run + 1 if against else 0
        self.turned = self._run >= (s.judge_leave if self.memory_lost else s.judge_enter)
        if self.turned:
            self.memory_lost = not self.memory_lost
            self._run = 0
        return not self.memory_lost

    # -- the second expert ------------------------------------------------------------------
    def _weigh_experts(self, own: FrameState, report: ExpertReport) -> FrameState:
        """The frame judged with a second expert's ``report`` after the tracker's own
        judgement ``own``: the verdict from the likeness (tracked, lost, found), the box the
        experts' mix where they agree, else the expert's."""
        if own.lost:
            return self._look_again(own, report)
        s = self.settings
        fh, fw = own.frame.shape[:2]
        agree = overlap(report.box, own.box) >= s.expert_agree
        vouched = agree and own.ok
        self._since += 1
        likeness = math.nan  # (not measured: a frame the experts vouch for)
        if not vouched or self._since >= s.likeness_every:
            self._since = 0
            likeness = report.likeness()
            self.shown = self.confidence(likeness)
        verdict = self._by_likeness(likeness, vouched)
        b = 0.0 if own.rested else s.expert_blend  # (a rested tracker's box is the last frame's)
        box = within(tuple((1 - b) * n + b * t for n, t in zip(report.box, own.box))
                     if agree else report.box, fw, fh)
        if verdict is Verdict.LOST:
            return own.evolve(exact=box, score=self.shown, verdict=verdict, ok=False,
                              learns=False, steady=False)
        doubting = self._against > 0  # (counting towards lost: nothing learns, nothing moves)
        learns = own.learns and not doubting
        moved = not doubting and (learns or not agree or own.rested > 0)
        return own.evolve(box=placed_at(own.box, box, fw, fh) if moved else own.box, exact=box,
                          score=self.shown, verdict=verdict, ok=True, learns=learns,
                          steady=own.steady and agree, vouched=vouched and not doubting)

    def _look_again(self, own: FrameState, report: ExpertReport) -> FrameState:
        """A lost target's frame with a second expert: its own choice, unless another place it
        searched is alike the target (above :meth:`found_level`) and more alike; found after
        enough such frames, when the tracker moves there and learns again."""
        best, likeness = report.box, report.likeness()
        level = self.found_level()
        for box, like in report.places:
            if like > max(likeness, level):
                best, likeness = box, like
        verdict = self._by_likeness(likeness, False)
        fh, fw = own.frame.shape[:2]
        exact = within(best, fw, fh)
        score = self.confidence(likeness)
        if verdict is Verdict.FOUND:
            return own.evolve(box=placed_at(own.box, exact, fw, fh), exact=exact, score=score,
                              verdict=verdict, ok=True, learns=self._learns(), steady=False)
        return own.evolve(exact=exact, score=score, verdict=Verdict.LOST, ok=False, learns=False,
                          steady=False)

    def _by_likeness(self, likeness: float, vouched: bool) -> Verdict:
        """The experts' verdict (tracked, lost or found) of a frame whose chosen box has
        ``likeness`` (NaN: not measured), the experts vouching for it or not (``vouched``),
        with hysteresis; ``_against`` counts the frames in a row that argue for a change."""
        s = self.settings
        lost = self.experts_lost
        if math.isnan(likeness):
            self._against = self._against if lost else 0
            return Verdict.LOST if lost else Verdict.TRACKED
        if math.isnan(self.typical):
            self.typical = likeness
        if not lost:
            against = (likeness < s.like_low or likeness < s.like_drop * self.typical) and not vouched
            self._against = self._against + 1 if against else 0
            if self._against == 0:
                self.typical += s.like_rate * (likeness - self.typical)
            if self._against < s.judge_enter:
                return Verdict.TRACKED
            self.experts_lost, self._against = True, 0
            return Verdict.LOST
        self._against = self._against + 1 if likeness > self.found_level() else 0
        if self._against < s.judge_leave:
            return Verdict.LOST
        self.experts_lost, self._against = False, 0
        return Verdict.FOUND

    def found_level(self) -> float:
        """The likeness above which a lost frame counts for the target."""
        s = self.settings
        typical = self.typical if math.isfinite(self.typical) else 0.0
        return max(s.like_high, s.like_found * typical)

    def confidence(self, likeness: float) -> float:
        """A likeness mapped to [0, 1]: 0.5 at the lower of ``like_low`` and the dropped
        running mean, rising with the likeness (a logistic of slope 20)."""
        s = self.settings
        typical = self.typical if math.isfinite(self.typical) else 1.0
        z = 20.0 * (likeness - max(s.like_low, s.like_drop * typical))
        return 1.0 / (1.0 + math.exp(-z)) if math.isfinite(z) else 0.0

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
