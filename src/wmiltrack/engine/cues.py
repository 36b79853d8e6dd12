"""Cues: other evidence about where the target is, merged into the translation search.

A cue values every candidate box of a frame by the mean of a per-pixel map over the box (read
from an integral image of the map in four loads, in the core's search). The search picks the
candidate with the largest ``(1 - sum of weights) * classifier confidence + sum of weight *
box mean``. After each frame the tracker tells every cue where the target was, so the cue can
learn. A new cue is one class with the three members of :class:`Cue`; pass it to
:class:`~wmiltrack.Tracker` as ``cues=[...]``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol, runtime_checkable

import numpy as np
import numpy.typing as npt

from .colour import ColourModel, ColourSettings, box_contrast
from .frames import IntBox

__all__ = ["ColourCue", "Cue", "CueTable", "check_cue_weights"]

FloatArray = npt.NDArray[np.float64]

CueTable = tuple[FloatArray, int, int]
"""An integral image of a cue's per-pixel map over a frame region: ``(table, x0, y0)``, the table
``(rows + 1) x (cols + 1)`` float64 with a zero first row and column, its pixel ``(0, 0)`` at
frame position ``(x0, y0)``."""


@runtime_checkable
class Cue(Protocol):
    """What the tracker asks of a cue.

    Four optional attributes: ``at_centre = True`` makes :meth:`table` return the map itself
    (``rows x cols`` over the clipped region), read at each candidate's centre pixel instead of
    averaged over the box (a correlation filter's response is such a map), and the region it
    is asked for is then that of the candidates' centres only; ``pooled``, a bool such a cue
    sets in :meth:`table`, makes a coarse grid (step s) read the map's best within s / 2
    pixels of each candidate's centre, so that a peak narrower than the step is not missed;
    ``learn_above = s``
    lets the cue learn only from frames whose reported score is at least ``s``; ``confidence``,
    a float the cue sets in :meth:`table` saying how well it found the target there (on its own
    scale, higher is surer, NaN for no opinion), is one more witness the lost state
    (``redetect``) requires to fall before it calls the target lost.
    """

    #: The cue's weight in the merged score, in [0, 1] (the weights of a tracker's cues add
    #: up to at most 1).
    weight: float

    def start(self, frame: np.ndarray, box: IntBox) -> None:
        """Learn from the first frame, where the target is ``box``."""

    def table(self, frame: np.ndarray, region: tuple[int, int, int, int]) -> CueTable:
        """The map's integral image over ``region = (x0, y0, x1, y1)`` clipped to the frame; every
        candidate box of the search lies inside the clipped region."""

    def learn(self, frame: np.ndarray, box: IntBox) -> None:
        """Learn from a frame after the tracker placed the target at ``box``."""


def check_cue_weights(colour_weight: float, template_weight: float, cues: Sequence[object] = ()
                      ) -> None:
    """The one rule on the cues' weights, for every way of adding cues (:class:`Params`
    construction and ``replace``, ``Tracker(..., cues=...)``): each added cue is a :class:`Cue`
    with a weight in [0, 1], and ``colour_weight``, ``template_weight`` and the added cues'
    weights add up to at most 1 (the classifier's share of the merged score is 1 minus their
    sum). A ``TypeError`` or ``ValueError`` otherwise."""
    added: list[float] = []
    for cue in cues:
        if not isinstance(cue, Cue):
            raise TypeError(f"a cue needs weight, start, table and learn; got {cue!r}")
        if not 0.0 <= cue.weight <= 1.0:
            raise ValueError(f"a cue's weight must be in [0, 1], got {cue.weight!r}")
        added.append(float(cue.weight))
    total = colour_weight + template_weight + sum(added)
    if total > 1.0 + 1e-12:
        terms = " + ".join(f"{w:g}" for w in (colour_weight, template_weight, *added))
        raise ValueError("the cues' weights (colour_weight + template_weight + each added cue's "
                         f"weight) add up to more than 1: {terms} = {total:g}")


class ColourCue:
    """``P(target | colour)`` from foreground and background colour histograms (Staple-style;
    :class:`~wmiltrack.engine.colour.ColourModel`), or from luma histograms on a gray video with
    ``gray_colour``."""

    def __init__(self, settings: ColourSettings, *, intensity: bool) -> None:
        self.weight = settings.colour_weight
        self.model = ColourModel(learning_rate=settings.colour_learning_rate, intensity=intensity,
                                 sample=settings.colour_sample)
        self._table: CueTable | None = None

    @staticmethod
    def wanted(settings: ColourSettings, frame: np.ndarray) -> bool:
        """Whether a tracker with these settings, started on ``frame``, has a colour cue."""
        return settings.colour_weight > 0 and (settings.gray_colour or ColourModel.usable(frame))

    def start(self, frame: np.ndarray, box: IntBox) -> None:
        self.model.learn(frame, box)

    def table(self, frame: np.ndarray, region: tuple[int, int, int, int]) -> CueTable:
        self._table = self.model.integral(frame, region)
        return self._table

    def learn(self, frame: np.ndarray, box: IntBox) -> None:
        self._table = None
        self.model.learn(frame, box)

    def contrast(self, box: IntBox) -> float:
        """The box's colour contrast (:func:`~wmiltrack.engine.colour.box_contrast`) read
        from this frame's search table (the box and its ring clipped to the table's region)."""
        if self._table is None:
            raise ValueError("no search table this frame: call table() first")
        table, x0, y0 = self._table
        return box_contrast(table, x0, y0, box)
