"""What the tracker asks of each kind of part: the scale estimator, the motion model, the lost
state with its re-detection, and the judge of ``ok`` (the cues' interface is
:class:`~wmiltrack.engine.cues.Cue`).

Each interface is exactly what :class:`~wmiltrack.engine.tracker.Tracker` calls on a part of
that kind, so a class with these members (no base class needed) can stand in for the built-in
one: ``Tracker(..., parts={"scale": ..., "motion": ..., "recovery": ...})`` takes a factory
per kind (see :data:`PartFactory`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

import numpy as np

from .frames import IntBox

if TYPE_CHECKING:
    from .appearance import HaarAppearance
    from .params import Params

__all__ = ["PART_KINDS", "Judge", "MotionModel", "PartFactory", "Recovery", "ScaleEstimator"]


@runtime_checkable
class ScaleEstimator(Protocol):
    """Tries other box sizes after the translation search, and learns the target's size.

    Built-in: :class:`~wmiltrack.engine.scale.HaarScale` (the appearance model's features at
    neighbouring sizes), :class:`~wmiltrack.engine.template.DSSTScale` (DSST's 1-D filter).
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
    """The lost state: notices a target that is hidden or gone, and finds it again.

    Built-in: :class:`~wmiltrack.engine.recovery.Redetector` (``redetect=True``). While
    :attr:`lost` is True the tracker holds the last confident box, reports score 0 and ``ok``
    False, and nothing learns; each frame it first searches around that box as usual, asks
    :meth:`back`, and else :meth:`find`.
    """

    #: Whether the target counts as lost.
    lost: bool
    #: Frames in the lost state so far (the judge of ``ok`` may start the lost state: it sets
    #: ``lost`` True and this to 1).
    frames_lost: int

    def start(self, frame: np.ndarray, box: IntBox) -> None:
        """The first frame, where the target is ``box``; no history."""

    def judge(self, conf: float, frame: np.ndarray, box: IntBox,
              witnesses: Sequence[float] = ()) -> bool:
        """Whether a tracked frame whose box ``box`` has the classifier's confidence ``conf``
        (and the cues' own confidences ``witnesses``) means the target is lost; True starts
        the lost state (the part sets :attr:`lost`)."""

    def back(self, conf: float, frame: np.ndarray, box: IntBox) -> bool:
        """Whether a lost frame's usual search, which put the box at ``box`` with confidence
        ``conf``, found the target again (True ends the lost state)."""

    def find(self, frame: np.ndarray) -> IntBox | None:
        """Look for the target over the whole frame: a box to resume from (ends the lost
        state), or None (the frame stays lost)."""

    def learn(self, frame: np.ndarray, box: IntBox) -> None:
        """Learn from a tracked frame after the tracker placed the target at ``box``."""


@runtime_checkable
class Judge(Protocol):
    """Decides ``ok`` frame by frame with a memory of the target, instead of the policy's
    threshold on the score.

    Built-in: :class:`~wmiltrack.engine.judge.LostJudge` (``judge_memory > 0``), which reads
    the first-frame correlation filter's peak.
    """

    #: Whether the judge holds the target for lost (with ``judge_gates`` nothing learns then).
    lost: bool
    #: Whether the last frame changed the verdict (with ``judge_holds``, a turn to lost
    #: starts the lost state).
    turned: bool

    def verdict(self, score: float, first_peak: float) -> bool:
        """Fold in one frame's reported score and the first-frame filter's peak on it (NaN
        when it did not search); whether the target counts as tracked on it."""


#: A factory of one kind of part, called when the tracker starts (:meth:`Tracker.init`): the
#: tracker's parameters, the first frame and the first box (clipped, whole pixels). It returns
#: the part (whose ``start`` the tracker then calls), or None for no part of that kind.
PartFactory = Callable[["Params", np.ndarray, IntBox], Any]

#: The kinds of part a user may supply (``Tracker(parts={kind: factory})``), with the interface
#: each must have.
PART_KINDS: dict[str, type[Any]] = {
    "scale": ScaleEstimator,
    "motion": MotionModel,
    "recovery": Recovery,
}
