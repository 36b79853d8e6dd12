"""What the tracker asks of each kind of part: the scale estimator, the motion model, the
re-detection, a second expert, the judge and the reported score (the cues' interface is
:class:`~wmiltrack.engine.cues.Cue`; an appearance model is a
:class:`~wmiltrack.engine.appearance.HaarAppearance`).

Each interface is exactly what :class:`~wmiltrack.engine.tracker.Tracker` calls on a part of
that kind, so a class with these members (no base class needed) can stand in for the built-in
one: ``Tracker(..., parts={"judge": ..., "scale": ..., ...})`` takes a factory per kind (see
:data:`PartFactory`), called with that kind's own settings only.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

import numpy as np

from .appearance import AppearanceSettings, HaarAppearance
from .experts import ExpertSettings
from .frames import IntBox
from .judge import Evidence, JudgeSettings
from .motion import MotionSettings
from .policy import ScoreSettings
from .recovery import RecoverySettings
from .scale import ScaleSettings

if TYPE_CHECKING:
    from .state import ExpertReport, FrameState

__all__ = ["PART_KINDS", "PART_SETTINGS", "Judge", "MotionModel", "PartFactory", "Recovery",
           "ScaleEstimator", "ScorePolicy", "SecondExpert"]


@runtime_checkable
class ScaleEstimator(Protocol):
    """Tries other box sizes after the translation search, and learns the target's size.

    Built-in: :class:`~wmiltrack.engine.scale.HaarScale` (the appearance model's features at
    neighbouring sizes), :class:`~wmiltrack.engine.scale.DSSTScale` (DSST's 1-D filter).
    """

    #: The boxes tried at other sizes by the last :meth:`search` (the part replaces it at each
    #: search; the tracker copies it into the frame's record for :meth:`Tracker.samples`).
    tried: list[IntBox]
    #: The part learns (:meth:`learn`) only from frames whose reported score is at least this.
    learn_above: float

    @property
    def scale(self) -> float:
        """The box size relative to the first box."""

    def start(self, frame: np.ndarray, box: IntBox) -> None:
        """Learn from the first frame, where the target is ``box``."""

    def margin(self, box: IntBox) -> int:
        """Pixels the search's integral image must extend beyond its usual margin, for the
        largest box this part tries or learns at around ``box``."""

    def search(self, model: HaarAppearance, frame: np.ndarray, box: IntBox, raw: float,
               contrast: Callable[[IntBox], float] | None) -> tuple[IntBox, float]:
        """The box at the best size around ``box`` (the translation search's choice, of raw
        score ``raw``) and the raw score to report. ``model`` can score boxes of any size on
        this frame (:meth:`~wmiltrack.engine.appearance.HaarAppearance.grid`); ``contrast``
        is the colour cue's box contrast on this frame, if there is a colour cue."""

    def learning_extras(self, model: HaarAppearance, box: IntBox
                        ) -> tuple[np.ndarray | None, int, tuple[Any, ...] | None]:
        """What the part adds to the appearance model's learning at ``box``: extra negative
        feature values (or None), their count, and a target model for the core to update from
        the same positives (or None; see :meth:`take_learnt`). ``(None, 0, None)``: nothing."""

    def take_learnt(self, learnt: tuple[Any, Any], n_pos: int) -> None:
        """Keep the target model that the learning step updated (after
        :meth:`learning_extras` gave one; called every learning step)."""

    def learn(self, frame: np.ndarray, box: IntBox) -> None:
        """Learn from a frame after the tracker placed the target at ``box``."""


@runtime_checkable
class MotionModel(Protocol):
    """Says where the next search is centred, and follows the target's moves.

    Built-in: :class:`~wmiltrack.engine.motion.VelocityMotion` (constant velocity),
    :class:`~wmiltrack.engine.template.CorrelationTemplate` (its filter's peak, with
    ``template_motion``). Without one the search is centred on the last box.
    """

    def start(self, frame: np.ndarray, box: IntBox) -> None:
        """The first frame, where the target is ``box``."""

    def origin(self, box: IntBox, frame: np.ndarray | None = None) -> IntBox:
        """The box to centre the search on, for a target last seen at ``box``. ``frame`` is
        the frame about to be searched, or None when the tracker asks before it has one
        (:meth:`Tracker.search_region`): then the guess from past frames."""

    def follow(self, previous: IntBox, box: IntBox, tracked: bool) -> None:
        """A frame moved the target from ``previous`` to ``box``; ``tracked``: whether it
        counted as confidently tracked (a held or re-detected frame has ``previous == box``
        and ``tracked`` False)."""


@runtime_checkable
class Recovery(Protocol):
    """Finds a lost target again over the whole frame, and gives the judge one witness of a
    lost target: the box's likeness to its picture of the target.

    Built-in: :class:`~wmiltrack.engine.recovery.Redetector` (``redetect=True``). The judge
    decides when the target is lost (:class:`Judge`); while it is, the tracker holds the last
    confident box, nothing learns, and each frame whose usual search did not find the target
    back asks :meth:`find`.
    """

    def start(self, frame: np.ndarray, box: IntBox) -> None:
        """The first frame, where the target is ``box``; no history."""

    def likeness(self, frame: np.ndarray, box: IntBox) -> tuple[float, float] | None:
        """How much ``box`` looks like the target, and how much the tracked boxes usually do
        (a running mean), or None when the part cannot say."""

    def find(self, frame: np.ndarray, frames_lost: int) -> IntBox | None:
        """Look for the target over the whole frame, lost for ``frames_lost`` frames so far:
        a box to resume from, or None (the frame stays lost)."""

    def learn(self, frame: np.ndarray, box: IntBox) -> None:
        """Learn from a tracked frame after the tracker placed the target at ``box``."""


@runtime_checkable
class SecondExpert(Protocol):
    """Another locator beside the tracker, whose evidence the judge weighs with the tracker's:
    it locates the target on each frame (a stage right after the tracker's locate, before the
    judge) and reports what it saw into the frame's record (``FrameState.expert``); after the
    judge's verdict it follows the frame's result.

    Built-in: :class:`~wmiltrack.engine.experts.NetworkExpert` (a Siamese network, rcwmil-nano;
    ``network=``).
    """

    def start(self, frame: np.ndarray, box: IntBox) -> None:
        """The first frame, where the target is ``box``."""

    def locate(self, state: FrameState) -> ExpertReport:
        """Its evidence on the record's frame (``state.frame``; ``state.box`` the tracker's
        located box, ``state.lost`` whether the frame started with the target lost,
        ``state.lost_for`` for how many frames)."""

    def follow(self, state: FrameState) -> None:
        """The judged record of the frame (its verdict, ``exact`` the frame's box where the
        judge took it from the experts): follow it."""


@runtime_checkable
class Judge(Protocol):
    """The one place that decides what a frame means: its verdict (tracked, doubtful, lost,
    found; :class:`~wmiltrack.engine.state.Verdict`), ``ok``, whether the parts learn from it
    and whether the motion model takes its move as a velocity.

    Built-in: :class:`~wmiltrack.engine.judge.FrameJudge` (the threshold on the score, the
    memory of the target, the lost state's running means, a second expert's likeness).
    """

    def start(self, frame: np.ndarray, box: IntBox) -> None:
        """The first frame, where the target is ``box``; no history."""

    def back(self, state: FrameState, evidence: Evidence) -> bool:
        """Whether a lost target's frame found the target again at the located box (else
        the recovery looks over the whole frame); changes nothing."""

    def verdict(self, state: FrameState, evidence: Evidence) -> FrameState:
        """The frame's record with ``verdict``, ``ok``, ``learns`` and ``steady`` set (a lost
        frame: the box held at ``state.previous`` and score 0), and, where a second expert
        reported (``state.expert``), the frame's box (``exact``; ``box`` where the tracker is
        to learn there) and score. Called once per frame, after the search and the score
        (and, for a lost target's frame, the recovery); the parts learn at the record's
        ``box`` if its ``learns`` says so."""


@runtime_checkable
class ScorePolicy(Protocol):
    """The score the tracker reports for a frame (``TrackResult.score``).

    Built-in: :class:`~wmiltrack.engine.policy.ReportedScore` (the classifier's confidence, or
    its blend with the box's colour and intensity contrast).
    """

    @property
    def plain(self) -> bool:
        """Whether the score is the classifier's confidence itself and the policy learns
        nothing (a paper preset's frame then runs as one core call, without :meth:`learn`)."""

    def start(self, frame: np.ndarray, box: IntBox) -> None:
        """The first frame, where the target is ``box``."""

    def score(self, conf: float, frame: np.ndarray, box: IntBox) -> float:
        """The score to report for a frame of classifier confidence ``conf`` at ``box``."""

    def learn(self, frame: np.ndarray, box: IntBox) -> None:
        """A frame the parts learn from, the target at ``box`` (after :meth:`score`)."""


#: A factory of one kind of part, called when the tracker starts (:meth:`Tracker.init`) with
#: the part's own settings (the kind's class in :data:`PART_SETTINGS`, holding the tracker's
#: values of its fields), the first frame and the first box (clipped, whole pixels); an
#: appearance model's factory also gets the tracker's ``seed=`` (it draws the feature bank and
#: the negatives). It returns the part (whose ``start`` the tracker then calls), or None for
#: no part of that kind (not for the appearance model, the judge or the policy).
PartFactory = Callable[..., Any]

#: The kinds of part a user may supply (``Tracker(parts={kind: factory})``), with the interface
#: each must have (an appearance model is a
#: :class:`~wmiltrack.engine.appearance.HaarAppearance`: the core's search and learning read
#: its feature bank and Gaussians).
PART_KINDS: dict[str, type[Any]] = {
    "appearance": HaarAppearance,
    "policy": ScorePolicy,
    "judge": Judge,
    "scale": ScaleEstimator,
    "motion": MotionModel,
    "recovery": Recovery,
    "expert": SecondExpert,
}

#: The settings each kind of part is made with (:func:`~wmiltrack.engine.settings.own`).
PART_SETTINGS: dict[str, type[Any]] = {
    "appearance": AppearanceSettings,
    "policy": ScoreSettings,
    "judge": JudgeSettings,
    "scale": ScaleSettings,
    "motion": MotionSettings,
    "recovery": RecoverySettings,
    "expert": ExpertSettings,
}
