"""One frame's record: what the tracker knows about a frame at each stage of its step.

A frame walks through one list of stages (:attr:`~wmiltrack.engine.tracker.Tracker.stages`:
locate, a second expert's locate, rescale, score, recover, judge, learn, follow); each stage
takes the record and returns a new one, so a value of the frame is written once, by the stage
that finds it, and read by the stages after it instead of travelling through the tracker's
attributes. The record of the last
frame is the tracker's whole state between frames (its box, score, ``ok``, and whether the
target is lost).
"""

from __future__ import annotations

import enum
from collections.abc import Callable
from typing import Any, NamedTuple

import numpy as np

from .frames import IntBox

__all__ = ["ExpertReport", "FloatBox", "FrameState", "SearchStage", "Verdict", "new_frame"]

#: A box ``(x, y, w, h)`` in fractional pixels (a second expert's).
FloatBox = tuple[float, float, float, float]

#: One stage of a translation search as :meth:`~wmiltrack.Tracker.samples` reports it: the box
#: the stage started from, its radius and its step.
SearchStage = tuple[IntBox, int, int]


class Verdict(enum.Enum):
    """What the judge made of a frame (as DiMP's flag steers its state update and learning)."""

    #: The target is where the box is: ``ok``; the parts learn unless the judge holds them back
    #: (the record's ``learns``).
    TRACKED = "tracked"
    #: The box is kept (not held) but the frame is not confident: not ``ok``, the lost state not
    #: entered; the parts learn unless the judge holds them back (``judge_gates``).
    DOUBTFUL = "doubtful"
    #: The target is lost: the box is held at the last confident one, the score is 0, ``ok`` is
    #: False, nothing learns, and the next frame starts by looking for the target again.
    LOST = "lost"
    #: A lost target was found again on this frame (by the usual search or over the whole
    #: frame): the lost state ends there and the parts learn from the new box.
    FOUND = "found"


class ExpertReport(NamedTuple):
    """A second expert's evidence on a frame (:class:`~wmiltrack.engine.parts.SecondExpert`),
    for the judge: ``box`` its own choice; ``likeness`` a call measuring how alike that box is
    to the expert's memory of the target (1: the same; called at most once, only when the
    judge needs it: a measure may cost a network pass); ``places`` on a lost target's frame,
    the other places it searched, each ``(box, likeness)``, in the order searched."""

    box: FloatBox
    likeness: Callable[[], float]
    places: tuple[tuple[FloatBox, float], ...] = ()


class FrameState(NamedTuple):
    """The record of one frame (immutable: a stage returns a new one, :meth:`evolve`).

    ``frame`` the checked image, ``previous`` the box at the end of the frame before, ``lost``
    whether the frame started with the target lost, ``integral`` a luma integral image of the
    frame that the tracker may borrow (``Tracker.update(integral=...)``), ``origin`` where the
    last search was centred, ``box`` the target's box so far, ``raw`` the search's raw score
    (the summed log ratio of the chosen candidate, ``-inf`` when no candidate fitted), ``conf``
    the classifier's confidence, ``score`` the reported score; the judge's ``verdict``,
    ``ok``, ``learns`` (whether the parts learn from the frame) and ``steady`` (whether the
    motion model takes the frame's move as a velocity); ``searched`` the stages of the last
    search (what :meth:`Tracker.samples` shows), ``tried`` the boxes the scale estimator
    tried, ``learnt`` whether the appearance model has learnt from the frame (a paper
    preset's one-call step learns as it locates), ``rescued`` whether the recovery placed the
    box by looking over the whole frame, ``lost_for`` the frames in the lost state so far
    (counting this one once it is judged lost); ``expert`` a second expert's evidence on the
    frame (:class:`ExpertReport`, None without one); ``exact`` the frame's box in fractional
    pixels where the judge took it from a second expert (None: the frame's box is ``box``,
    the tracker's own, in whole pixels); ``rested`` the frames in a row, this one included,
    on which the tracker rested while a second expert alone located the target
    (:attr:`~wmiltrack.engine.experts.ExpertSettings.tracker_every`; 0: the tracker ran);
    ``vouched`` whether the judge found the second expert's box and the tracker's in
    agreement, the tracker ``ok``, and nothing counting against the target.
    The frame's result (``TrackResult``) is ``exact`` or
    ``box``, ``score`` and ``ok``: one record, which every view of the tracker reads.
    """

    frame: np.ndarray
    previous: IntBox
    lost: bool = False
    integral: Any = None
    origin: IntBox = (0, 0, 0, 0)
    box: IntBox = (0, 0, 0, 0)
    raw: float = float("nan")
    conf: float = float("nan")
    score: float = float("nan")
    verdict: Verdict | None = None
    ok: bool = False
    learns: bool = False
    steady: bool = False
    searched: tuple[SearchStage, ...] = ()
    tried: tuple[IntBox, ...] = ()
    learnt: bool = False
    rescued: bool = False
    lost_for: int = 0
    expert: ExpertReport | None = None
    exact: FloatBox | None = None
    rested: int = 0
    vouched: bool = False

    def evolve(self, **changes: Any) -> FrameState:
        """A copy with the fields named in ``changes`` replaced (``_replace``, at half its
        cost: a paper preset's frame makes several records, in about 150 µs in all)."""
        values = list(self)
        for name, value in changes.items():
            values[_POSITION[name]] = value
        return _new_tuple(FrameState, values)

    # The three records every frame makes, each a stage's findings (:meth:`evolve` with these
    # fields, in about 60 % of its time: a paper preset's whole Python step is about 12 µs).
    def located(self, origin: IntBox, box: IntBox, raw: float,
                searched: tuple[SearchStage, ...], learnt: bool) -> FrameState:
        """The record with the locate stage's findings."""
        s = self
        return _new_tuple(FrameState, (s[0], s[1], s[2], s[3], origin, box, raw, s[7], s[8],
                                       s[9], s[10], s[11], s[12], searched, s[14], learnt,
                                       *s[16:]))

    def scored(self, conf: float, score: float) -> FrameState:
        """The record with the score stage's findings."""
        return _new_tuple(FrameState, (*self[:7], conf, score, *self[9:]))

    def judged(self, verdict: Verdict, ok: bool, learns: bool, steady: bool) -> FrameState:
        """The record with the judge's verdict and what follows from it."""
        return _new_tuple(FrameState, (*self[:9], verdict, ok, learns, steady, *self[13:]))


_POSITION = {name: i for i, name in enumerate(FrameState._fields)}
_LOST = Verdict.LOST  # (an enum member read from its class costs ~70 ns, this name ~10 ns)
_new_tuple = tuple.__new__
_NAN = float("nan")


def new_frame(frame: np.ndarray, last: FrameState, integral: Any) -> FrameState:
    """The record a frame starts with, after the ``last`` frame's: its box is the last one,
    nothing found yet."""
    box, lost = last.box, last.verdict is _LOST
    return _new_tuple(FrameState, (frame, box, lost, integral, box, box, _NAN, _NAN, _NAN, None,
                                   False, False, False, (), (), False, False, last.lost_for,
                                   None, None, 0, False))
