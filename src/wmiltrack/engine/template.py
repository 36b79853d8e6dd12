"""The correlation-filter template as a tracker part: a cue (and optionally the motion model) from
a translation filter on fHOG (DSST's 1-D scale filter, the other correlation filter, is a scale
estimator: :class:`~wmiltrack.engine.scale.DSSTScale`).

Haar features on luma and colour histograms say little about a target whose lighting changes
(a shadow, a tunnel); HOG's block-normalised gradients do (Staple, CSR-DCF, ECO). The filter
is trained and applied in the Fourier domain by the core (:mod:`wmiltrack.engine.correlation`);
these classes fit it into the engine of parts.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from .correlation import CorrelationFilter, CorrelationSettings, FilterLearning, Location, SparseUpdates
from .frames import IntBox
from .geometry import centre, centred
from .settings import check_numbers, is_int, need

if TYPE_CHECKING:
    pass

__all__ = ["CorrelationTemplate", "TemplateSettings"]


@dataclass(frozen=True)
class TemplateSettings:
    """The correlation-filter template (:class:`wmiltrack.engine.template.CorrelationTemplate`):
    a translation filter on fHOG over a fixed-size template (Staple), merged into the search as
    a cue read at each candidate's centre, and optionally the motion model.

    Attributes
    ----------
    template_weight : float
        Weight of the filter's response (divided by its peak, clipped to [0, 1]) in the
        search's merge, beside the colour cue's (0: no template).
    template_motion : bool
        Centre the search on the filter's peak (searched over the target plus twice its mean
        side around the last box) instead of the motion model's prediction.
    template_area : float
        Template pixels the search region is resampled to (Staple: 150**2).
    template_learning_rate : float
        Weight of each new frame in the filter (Staple: 0.01).
    template_gate : float
        The correlation filters (the template and DSST's scale filter) learn only from frames
        whose reported score is at least this (0: every frame), so that an occluder or a drift
        the score notices stays out of them.
    template_every : int
        The correlation filters (the template and DSST's scale filter) learn from every
        ``template_every``-th frame they may learn from (ECO's sparse updates: each learning
        step costs a feature extraction and a transform per channel), their rates raised to
        keep the same memory.
    template_channels : int
        The template's 31 fHOG channels projected onto this many (ECO's compression: the
        principal axes of the first frame's features, fixed from then on), so that each
        frame transforms fewer planes; 0 keeps all 31.
    template_cell : int
        fHOG cell side in template pixels (Staple: 4); with ``template_area`` it sets the
        filter's grid, ``sqrt(template_area) / template_cell`` cells a side.
    template_reuse : bool
        The template learns from the frame's search sample, moved to the frame's final box
        (ECO: one feature extraction and one transform a frame instead of two), when that box
        is near the searched centre and of about the searched size; otherwise, and without
        this, from a new sample around the final box.
    template_pool_psr : float
        On frames where the filter's response has a peak-to-sidelobe ratio of at least this,
        a coarse search grid (step s) reads the filter's map at its best within s / 2 pixels
        of each candidate's centre instead of at the centre alone: the peak of a filter on
        2-pixel cells is narrower than the grid's step, and read at the grid's points a wide
        secondary hill can outscore it (0: never). A response without a clear peak (the
        target gone) is read at the centres, where its noise counts least.
    """

    template_weight: float = 0.0
    template_motion: bool = False
    template_area: float = 150.0**2
    template_learning_rate: float = 0.01
    template_gate: float = 0.0
    template_every: int = 1
    template_channels: int = 0
    template_cell: int = 4
    template_reuse: bool = False
    template_pool_psr: float = 0.0

    def __post_init__(self) -> None:
        TemplateSettings.check(self)

    def check(self) -> None:
        """``ValueError`` naming the first setting out of range."""
        check_numbers(self, "template_weight", "template_area", "template_learning_rate",
                      "template_gate", "template_pool_psr")
        need(0.0 <= self.template_weight <= 1.0,
             f"template_weight must be in [0, 1], got {self.template_weight}")
        need(isinstance(self.template_motion, bool),
             f"template_motion must be True or False, got {self.template_motion!r}")
        need(self.template_area >= 32.0**2, f"template_area must be >= 1024, got {self.template_area}")
        need(0.0 < self.template_learning_rate <= 1.0,
             f"template_learning_rate must be in (0, 1], got {self.template_learning_rate}")
        need(0.0 <= self.template_gate <= 1.0,
             f"template_gate must be in [0, 1], got {self.template_gate}")
        need(is_int(self.template_every) and 1 <= self.template_every <= 100,
             f"template_every must be an int in 1..100, got {self.template_every!r}")
        need(self.template_pool_psr >= 0.0,
             f"template_pool_psr must be >= 0, got {self.template_pool_psr}")
        need(is_int(self.template_channels) and 0 <= self.template_channels <= 31,
             f"template_channels must be an int in 0..31, got {self.template_channels!r}")
        need(is_int(self.template_cell) and 1 <= self.template_cell <= 16
             and self.template_area >= (4 * self.template_cell) ** 2,
             f"template_cell must be an int in 1..16 with template_area >= (4 cell)**2, "
             f"got {self.template_cell!r}")
        need(isinstance(self.template_reuse, bool),
             f"template_reuse must be True or False, got {self.template_reuse!r}")


class CorrelationTemplate:
    """A translation correlation filter, as a cue read at each candidate's centre and, with
    ``template_motion``, as the motion model.

    Each frame the filter searches a region of the target plus twice its mean side around the
    last box (:meth:`origin`); its response, divided by its peak and clipped to [0, 1], is the
    cue's map over the search region (:meth:`table`). It learns from frames whose reported score
    is at least ``template_gate`` (:attr:`learn_above`). Its ``confidence`` is the last search's
    response peak: HOG's normalised gradients keep it up under a shadow or a change of light,
    where the classifier's confidence and a grey template's correlation both fall.

    It keeps the first frame's filter, never trained again: the judge's memory of the target
    (``judge_memory``) reads its response on each frame (:meth:`first_peak_on`).
    """

    #: The core reads this cue's map at each candidate's centre, not its mean over the box.
    at_centre = True

    def __init__(self, settings: TemplateSettings) -> None:
        self.weight = settings.template_weight
        self.moves = settings.template_motion
        learning = FilterLearning.of(settings)
        self.learn_above = learning.above
        self.updates = SparseUpdates(settings.template_learning_rate, learning.every)
        self.reuse = learning.reuse
        self.pool_psr = settings.template_pool_psr
        self.pooled = False  # whether this frame's map is read pooled (see table())
        self.filter = CorrelationFilter(CorrelationSettings(
            template_area=settings.template_area, learning_rate=self.updates.rate,
            compressed=settings.template_channels, cell=settings.template_cell))
        self._searched: Location | None = None  # this frame's search, for table()
        self.confidence = math.nan
        # The first frame's filter, never trained again, and the frame the filter last searched.
        self._first: CorrelationFilter | None = None
        self._searched_frame: np.ndarray | None = None

    def start(self, frame: np.ndarray, box: IntBox) -> None:
        self.filter.init(frame, box)
        self._first = self.filter.copy()

    # -- motion model ---------------------------------------------------------------------
    def origin(self, box: IntBox, frame: np.ndarray | None = None) -> IntBox:
        """Search the filter around ``box``; the box moved to the response's peak with
        ``template_motion``, else ``box``. Without a frame (asked before the frame is known)
        the last box."""
        if frame is None:
            return box
        loc = self.filter.locate(frame, centre(box), (box[2], box[3]))
        self._searched = loc
        self._searched_frame = frame
        self.confidence = loc.peak
        if not self.moves:
            return box
        return centred(box, box[2], box[3], loc.dx, loc.dy)

    def first_peak_on(self, frame: np.ndarray) -> float:
        """The first frame's filter's response peak on ``frame``'s search sample, what the
        judge's memory reads; NaN when the filter did not search ``frame``."""
        if self._first is None or self._searched_frame is not frame:
            return math.nan
        return self._first.recall(self.filter)[0]

    def follow(self, previous: IntBox, box: IntBox, tracked: bool) -> None:
        """(Nothing to keep: the filter searches around the last box every frame.)"""

    # -- cue ------------------------------------------------------------------------------
    def table(self, frame: np.ndarray, region: tuple[int, int, int, int]
              ) -> tuple[np.ndarray, int, int]:
        """The filter's response at every pixel of ``region`` taken as a target centre
        (bilinear between the response's cells; the response wraps around), divided by its
        peak and clipped to [0, 1]; read pooled (:attr:`pooled`) on a frame whose response's
        PSR is at least ``template_pool_psr``."""
        if self._searched is None:  # not the motion model: search around the region's centre
            w, h = self.filter.size  # (the region of centres: its middle pixel's index)
            cx, cy = (region[0] + region[2] - 1) / 2.0, (region[1] + region[3] - 1) / 2.0
            self.origin((round(cx - w / 2.0), round(cy - h / 2.0), round(w), round(h)), frame)
        loc = self._searched
        assert loc is not None
        self._searched = None
        self.pooled = self.pool_psr > 0 and loc.psr >= self.pool_psr
        fh, fw = frame.shape[:2]
        x0, y0 = max(region[0], 0), max(region[1], 0)
        return loc.map((x0, y0, min(region[2], fw), min(region[3], fh))), x0, y0

    def learn(self, frame: np.ndarray, box: IntBox) -> None:
        if self.updates.due():
            self.filter.learn(frame, box, from_search=self.reuse)
