"""The reported score: how confident a frame is, and what score the tracker reports (what the
score means for ``ok``, the lost state and learning is the judge's: :mod:`.judge`)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from .classifier import CONFIDENCE_OFFSET
from .colour import ColourModel, check_colour_model
from .frames import IntBox
from .settings import check_choices, is_number, need

__all__ = ["ContrastScore", "ReportedScore", "ScoreSettings", "confidence", "logistic"]


@dataclass(frozen=True)
class ScoreSettings:
    """The reported score (:mod:`wmiltrack.engine.policy`).

    Attributes
    ----------
    score_colour : float
        Weight ``w`` of the box's colour contrast in the reported confidence
        (``TrackResult.score``): ``(1 - w) * logistic(raw / K - offset) + w * clip(0.5 +
        contrast, 0, 1)``, ``contrast`` being the mean ``P(target | colour)`` inside the box
        minus that over a ring around it (:func:`wmiltrack.engine.colour.colour_contrast`):
        a box on the target holds its colours and its surroundings do not, while a lost box
        sees background on both sides. Needs the colour cue. Only the report changes. 0: off.
    score_colour_model : {"current", "first"}
        Which colour histograms ``score_colour``'s contrast reads: ``current``, the ones the
        search uses (updated every frame, so they follow the box wherever it goes), or
        ``first``, the histograms learnt on the first frame and never updated (a memory of
        what the target looked like: a box that drifted onto background keeps a high
        classifier confidence, since the classifier learns the background it sits on, but
        its colours no longer stand out under the first frame's model).
    score_luma : float
        Weight ``v`` of a second contrast in the reported confidence: the box's contrast under
        a histogram of the first frame's intensities (luma, 32 levels), learnt once and never
        updated, on colour and gray frames alike. The score becomes ``(1 - w - v) * conf +
        w * clip(0.5 + colour contrast, 0, 1) + v * clip(0.5 + luma contrast, 0, 1)``; on
        frames without colour the colour term reads the luma contrast. 0: off.
    colour_learning_rate, colour_sample : float, int
        The colour cue's (:class:`~wmiltrack.engine.colour.ColourSettings`, which documents them), shared: the
        reported score keeps histograms of its own, learnt as the cue's are (with
        ``score_colour_model="current"``, learnt on the same frames as the cue's, so equal to
        them).
    """

    score_colour: float = 0.0
    score_colour_model: Literal["current", "first"] = "current"
    score_luma: float = 0.0
    colour_learning_rate: float = 0.04
    colour_sample: int = 0

    def __post_init__(self) -> None:
        ScoreSettings.check(self)

    def check(self) -> None:
        """``ValueError`` naming the first setting out of range."""
        check_colour_model(self)
        check_choices(self, {"score_colour_model": ("current", "first")})
        need(is_number(self.score_colour) and 0.0 <= self.score_colour <= 1.0,
             f"score_colour must be in [0, 1], got {self.score_colour!r}")
        need(is_number(self.score_luma) and 0.0 <= self.score_luma <= 1.0
             and self.score_colour + self.score_luma <= 1.0,
             f"score_luma must be in [0, 1 - score_colour], got {self.score_luma!r}")


def logistic(z: float) -> float:
    """``1 / (1 + exp(-z))`` without overflow for any finite ``z``."""
    if z >= 0:
        return 1.0 / (1.0 + math.exp(-z))
    e = math.exp(z)
    return e / (1.0 + e)


def confidence(raw: float, k: int, offset: float = CONFIDENCE_OFFSET) -> float:
    """Confidence in [0, 1] of a frame from its best candidate's summed log ratio ``raw``.

    ``logistic(raw / k - offset)`` (``offset``: ``Params.confidence_offset``, by default
    :data:`~wmiltrack.engine.classifier.CONFIDENCE_OFFSET`): 0.5 at the point where, on the
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

    Its histograms are its own, learnt as the colour cue learns its (same settings, same
    frames): with ``score_colour_model="first"`` only on the first frame, with ``"current"``
    on every frame the parts learn from, so that they equal the cue's. ``colour``: whether the
    tracker has a colour cue (the colour term is left out without one).
    """

    def __init__(self, settings: ScoreSettings, *, colour: bool) -> None:
        self.settings = settings
        self.has_colour = colour
        self.colour: ColourModel | None = None  # colour histograms (None: no colour term)
        self.luma: ColourModel | None = None    # the first frame's intensities (score_luma > 0)

    def start(self, frame: np.ndarray, box: IntBox) -> None:
        """Learn the first frame's histograms (colour ones of the cue's kind: luma ones on a
        gray video, as :class:`~wmiltrack.engine.cues.ColourCue`)."""
        s = self.settings
        self.colour = self.luma = None
        if self.has_colour and s.score_colour > 0:
            self.colour = ColourModel(learning_rate=s.colour_learning_rate,
                                      intensity=not ColourModel.usable(frame),
                                      sample=s.colour_sample)
            self.colour.learn(frame, box)
        if s.score_luma > 0:
            self.luma = ColourModel(intensity=True, sample=s.colour_sample)
            self.luma.learn(frame, box)

    def learn(self, frame: np.ndarray, box: IntBox) -> None:
        """With ``score_colour_model="current"``, fold the frame into the colour histograms
        (the first frame's stay as they were otherwise)."""
        if self.colour is not None and self.settings.score_colour_model == "current":
            self.colour.learn(frame, box)

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

    def start(self, frame: np.ndarray, box: IntBox) -> None:
        """The first frame: the contrast's histograms, if any, learn it."""
        if self.report is not None:
            self.report.start(frame, box)

    def learn(self, frame: np.ndarray, box: IntBox) -> None:
        """A frame the parts learn from (the contrast's histograms may learn it)."""
        if self.report is not None:
            self.report.learn(frame, box)
