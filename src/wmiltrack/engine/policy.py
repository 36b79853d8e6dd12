"""The reported score: how confident a frame is, and what score the tracker reports (what the
score means for ``ok``, the lost state and learning is the judge's: :mod:`.judge`)."""

from __future__ import annotations

import math

import numpy as np

from .colour import ColourModel
from .frames import IntBox
from .settings import CONFIDENCE_OFFSET, ScoreSettings

__all__ = ["ContrastScore", "ReportedScore", "confidence", "logistic"]


def logistic(z: float) -> float:
    """``1 / (1 + exp(-z))`` without overflow for any finite ``z``."""
    if z >= 0:
        return 1.0 / (1.0 + math.exp(-z))
    e = math.exp(z)
    return e / (1.0 + e)


def confidence(raw: float, k: int, offset: float = CONFIDENCE_OFFSET) -> float:
    """Confidence in [0, 1] of a frame from its best candidate's summed log ratio ``raw``.

    ``logistic(raw / k - offset)`` (``offset``: ``Params.confidence_offset``, by default
    :data:`~wmiltrack.engine.settings.CONFIDENCE_OFFSET`): 0.5 at the point where, on the
    benchmark sequences, tracked and lost frames were equally likely; 0 when no candidate
    was scored. This is ``TrackResult.score`` of the six paper variants.
    """
    if not math.isfinite(raw):
        return 0.0
    return logistic(raw / max(k, 1) - offset)


class ContrastScore:
    """The reported score of rcwmil-plus: the classifier's confidence blended with the box's
    contrast under colour and intensity histograms (``Params.score_colour``, ``score_luma``).

    A box that drifted onto background keeps a high classifier confidence (the classifier
    learns whatever it sits on), but its colours and brightness no longer stand out from its
    surroundings under the first frame's histograms.
    """

    def __init__(self, settings: ScoreSettings, colour: ColourModel | None,
                 luma: ColourModel | None) -> None:
        self.settings = settings
        self.colour = colour  # the search cue's model, or the first frame's copy; None: no colour
        self.luma = luma      # the first frame's intensities (score_luma > 0)

    def __call__(self, conf: float, frame: np.ndarray, box: IntBox) -> float:
        """``(1 - w - v) conf + w clip(0.5 + colour contrast, 0, 1) + v clip(0.5 + luma
        contrast, 0, 1)``; without colour the colour term reads the luma contrast, or is left
        out (``v = 0``: the classifier's confidence alone)."""
        w, v = self.settings.score_colour, self.settings.score_luma
        luma = 0.0
        if self.luma is not None:
            luma = min(max(0.5 + self.luma.contrast(frame, box), 0.0), 1.0)
        if self.colour is None:  # no colour in this video
            return (1.0 - w - v) * conf + (w + v) * luma if v > 0 else conf
        contrast = self.colour.contrast(frame, box)
        return (1.0 - w - v) * conf + w * min(max(0.5 + contrast, 0.0), 1.0) + v * luma


class ReportedScore:
    """The score to report: the classifier's confidence (the paper), or a
    :class:`ContrastScore` of it."""

    def __init__(self, settings: ScoreSettings, report: ContrastScore | None = None) -> None:
        self.settings = settings
        self.report = report

    @property
    def plain(self) -> bool:
        """Whether this is the paper's policy, which a one-call frame step can carry out."""
        return self.report is None

    def score(self, conf: float, frame: np.ndarray, box: IntBox) -> float:
        """The score to report for a frame of confidence ``conf`` whose box is ``box``."""
        return conf if self.report is None else self.report(conf, frame, box)
