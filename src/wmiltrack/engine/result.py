"""The value every tracker in wmiltrack returns for one frame."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np
import numpy.typing as npt

Box = tuple[float, float, float, float]
Frame = npt.NDArray[np.uint8]


@dataclass(frozen=True, slots=True)
class TrackResult:
    """Outcome of one ``update``.

    Attributes
    ----------
    box:
        ``(x, y, w, h)`` of the target in pixel coordinates (top-left corner, width, height).
    score:
        Confidence in ``[0, 1]``; ``nan`` when the tracker gives none (some OpenCV trackers).
        wmiltrack's trackers: the classifier's confidence (``engine.tracker.confidence``);
        rcwmil-plus: its mean with the box's colour and intensity contrast under the first
        frame's histograms (``Params.score_colour``, ``score_luma``). Higher is more
        confident; 0.5 is where tracked and lost frames were equally likely.
    ok:
        ``False`` when the tracker judges the target lost or hidden: for the paper presets and
        rcwmil-plus, the score against ``lost_threshold`` (and the lost state); rcwmil-cf's judge
        and rcwmil-nano's decide from more than this frame's score (a memory of the target, with
        hysteresis), so a frame may be ``ok`` with a low score and the reverse; OpenCV's
        trackers: their failure flag.
    """

    box: Box
    score: float
    ok: bool = True

    def __iter__(self):  # type: ignore[no-untyped-def]
        """Unpack as OpenCV does: ``ok, box = tracker.update(frame)``."""
        yield self.ok
        yield self.box


@runtime_checkable
class TrackerLike(Protocol):
    """What the evaluation code needs of a tracker (``wmiltrack.Tracker`` and the peers)."""

    def init(self, frame: Frame, box: Box) -> object:
        """Start tracking the target in ``box`` (``x, y, w, h``) of ``frame``."""
        ...

    def update(self, frame: Frame) -> TrackResult:
        """Locate the target in the next frame."""
        ...
