"""The correlation-filter template as tracker parts: a cue (and optionally the motion model) from
a translation filter on fHOG, and DSST's 1-D scale filter as the scale estimator.

Haar features on luma and colour histograms say little about a target whose lighting changes
(a shadow, a tunnel); HOG's block-normalised gradients do (Staple, CSR-DCF, ECO). The filter
is trained and applied in the Fourier domain by the core (:mod:`wmiltrack.engine.correlation`);
these classes fit it into the engine of parts.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, Callable

import numpy as np

from .correlation import CorrelationFilter, CorrelationSettings, Location, SparseUpdates
from .frames import IntBox
from .scale import centred, dsst_filter
from .settings import FilterLearning, ScaleSettings, TemplateSettings

if TYPE_CHECKING:
    from .appearance import HaarAppearance

__all__ = ["CorrelationTemplate", "DSSTScale", "dsst_min_side"]


def _centre(box: IntBox) -> tuple[float, float]:
    return box[0] + box[2] / 2.0, box[1] + box[3] / 2.0


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
        loc = self.filter.locate(frame, _centre(box), (box[2], box[3]))
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


def dsst_min_side(min_box_size: int) -> int:
    """The smallest side of a box DSST's scale filter gives, for the features' ``min_box_size``
    (:class:`~wmiltrack.engine.settings.FeatureSettings`)."""
    return max(min_box_size, 4)


class DSSTScale:
    """DSST's scale filter as the scale estimator (``scale_model="dsst"``): after the translation
    search, the best of 33 sizes 1.02 apart by a 1-D correlation filter on fHOG, within
    ``scale_min``..``scale_max`` of the first box and the frame, no side below
    :func:`dsst_min_side`. It learns as the translation filter does (the ``template_*``
    learning settings it shares: :class:`~wmiltrack.engine.settings.FilterLearning`)."""

    def __init__(self, settings: ScaleSettings, base_wh: tuple[int, int],
                 frame_wh: tuple[int, int]) -> None:
        self.settings = settings
        self.base_wh = base_wh
        self.frame_wh = frame_wh
        self.min_side = dsst_min_side(settings.min_box_size)
        learning = FilterLearning.of(settings)
        self.reuse = learning.reuse
        self.updates, self.estimator = dsst_filter(settings.scale_samples, learning)
        self.learn_above = learning.above
        self.size = (float(base_wh[0]), float(base_wh[1]))  # continuous; the box is rounded
        self.given = base_wh  # the size of the box this part last gave
        self.tried: list[IntBox] = []

    @property
    def scale(self) -> float:
        """The box size relative to the first box."""
        return math.sqrt(self.size[0] * self.size[1] / (self.base_wh[0] * self.base_wh[1]))

    def start(self, frame: np.ndarray, box: IntBox) -> None:
        self.estimator.init(frame, box)

    def margin(self, box: IntBox) -> int:
        """Extra integral-image margin for the largest box the filter may choose around
        ``box`` (the appearance model learns at it)."""
        s = self.estimator.settings
        largest = s.step ** ((s.num_scales - 1) // 2)
        return math.ceil((largest - 1.0) * max(box[2], box[3]) / 2.0) + 1

    def search(self, model: HaarAppearance, frame: np.ndarray, box: IntBox, raw: float,
               contrast: Callable[[IntBox], float] | None) -> tuple[IntBox, float]:
        """The box at the size the filter prefers, centred where the search put it. With
        ``scale_veto`` and a colour cue (``contrast``), a new size whose box has less colour
        contrast than the current one is refused."""
        p = self.settings
        if (box[2], box[3]) != self.given:  # another part sized the box (a re-detection)
            self.size = (float(box[2]), float(box[3]))
        factor = self.estimator.estimate(frame, _centre(box), self.size).factor
        w, h = self.size[0] * factor, self.size[1] * factor
        s = math.sqrt(w * h / (self.base_wh[0] * self.base_wh[1]))
        s_ok = min(max(s, p.scale_min), p.scale_max)
        w, h = w * s_ok / s, h * s_ok / s
        min_side = self.min_side
        fw, fh = self.frame_wh
        shrink = min(1.0, fw / w, fh / h)
        grow = max(1.0, min_side / (w * shrink), min_side / (h * shrink))
        size = (w * shrink * grow, h * shrink * grow)
        iw, ih = max(min_side, round(size[0])), max(min_side, round(size[1]))
        out = centred(box, min(iw, fw), min(ih, fh))
        if (p.scale_veto and contrast is not None and (out[2], out[3]) != (box[2], box[3])
                and contrast(out) < contrast(box)):
            out = box
        else:
            self.size = size
        self.given = (out[2], out[3])
        return out, raw

    def learning_extras(self, model: HaarAppearance, box: IntBox) -> tuple[None, int, None]:
        """(Nothing for the appearance model's learning step.)"""
        return None, 0, None

    def take_learnt(self, learnt: tuple[Any, Any], n_pos: int) -> None:
        """(No model in the appearance model's learning step.)"""

    def learn(self, frame: np.ndarray, box: IntBox) -> None:
        """Fold in the scale samples around the frame's final box (every ``template_every``-th
        frame)."""
        if self.updates.due():
            self.estimator.learn(frame, _centre(box), self.size,
                                 from_estimate=self.reuse)
