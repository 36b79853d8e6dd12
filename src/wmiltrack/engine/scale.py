"""The scale estimators: after the translation search, the box at neighbouring scales competes with
it. :class:`HaarScale` stretches the Haar rectangles to each tried size (their weights rescaled
by the areas), so no image pyramid is built and a scale costs what a translation candidate
costs; :class:`DSSTScale` is DSST's 1-D correlation filter over the sizes.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, Callable

import numpy as np

from .classifier import GaussianPool
from .correlation import ScaleFilter, ScaleFilterSettings, SparseUpdates
from .features import box_area_ok
from .frames import IntBox
from .geometry import centre, centred
from .settings import FilterLearning, ScaleSettings

if TYPE_CHECKING:
    from .appearance import HaarAppearance

__all__ = ["DSSTScale", "HaarScale", "dsst_filter", "dsst_min_side"]


def dsst_filter(samples: int, learning: FilterLearning) -> tuple[SparseUpdates, ScaleFilter]:
    """DSST's scale filter (``samples`` sizes over DSST's range) and its learning schedule
    (every ``learning.every``-th frame, at the rate that keeps DSST's memory), as the scale
    model and as the Haar scale search's vote both use them."""
    updates = SparseUpdates(ScaleFilterSettings().learning_rate, learning.every)
    return updates, ScaleFilter(ScaleFilterSettings.spanning(samples, updates.rate))


class HaarScale:
    """Scale by the appearance model's own features (``Params.scale_*``).

    The box is always the first box scaled by ``scale_factor ** index``. Scales are compared
    by the strong classifier's mean log ratio, by a slow generative model of all M features
    (its own target Gaussians, learnt with the appearance model's positives), or both; with a
    colour cue, also by the box's colour contrast. Boxes at wrong scales can be learnt as
    negatives.

    What it needs of the appearance model (the smallest box its features allow, how many
    features its target model holds) it reads from the model it is handed at each search and
    learning step.
    """

    def __init__(self, settings: ScaleSettings, base_wh: tuple[int, int],
                 frame_wh: tuple[int, int]) -> None:
        self.settings = settings
        self.base_wh = base_wh
        self.frame_wh = frame_wh
        self.index = 0
        self._sizes: dict[int, tuple[int, int]] = {}  # box_size's answers, by index
        self.tried: list[IntBox] = []  # the boxes tried at other scales in the last frame
        # its target model (not for "ratio"), made at the first learning step (its size is the
        # appearance model's feature count)
        self.pool: GaussianPool | None = None
        # DSST's vote on the size (scale_dsst), learnt as the translation filter
        learning = FilterLearning.of(settings)
        self.dsst_updates, dsst = dsst_filter(settings.scale_samples, learning)
        self.learn_above = learning.above
        self.dsst = dsst if settings.scale_dsst > 0 else None
        self._voted: IntBox | None = None  # the box DSST's last vote was taken around

    @property
    def scale(self) -> float:
        """The box size relative to the first box."""
        return float(self.settings.scale_factor ** self.index)

    def box_size(self, index: int) -> tuple[int, int]:
        """The first box's size scaled by ``scale_factor ** index`` (kept: a frame asks for
        about nine)."""
        size = self._sizes.get(index)
        if size is None:
            s = self.settings.scale_factor ** index
            size = self._sizes[index] = (max(1, round(self.base_wh[0] * s)),
                                         max(1, round(self.base_wh[1] * s)))
        return size

    def margin(self, box: IntBox) -> int:
        """Extra integral-image margin for the largest box tried or learnt around ``box``."""
        p = self.settings
        w, h = self.box_size(self.index + max(p.scale_steps, p.scale_negatives) + p.scale_steps)
        return (max(w - box[2], h - box[3]) + 1) // 2 + 1

    def allowed(self, index: int, model: HaarAppearance) -> bool:
        """Whether the scale ``index`` is within the limits, the frame and ``model``'s
        smallest box."""
        p = self.settings
        s = p.scale_factor ** index
        if not (p.scale_min - 1e-9 <= s <= p.scale_max + 1e-9):
            return False
        w, h = self.box_size(index)
        mw, mh = model.min_box
        return mw <= w <= self.frame_wh[0] and mh <= h <= self.frame_wh[1] and box_area_ok(w, h)

    def start(self, frame: np.ndarray, box: IntBox) -> None:
        """Start DSST's vote, if any (the Haar models learn with the appearance model)."""
        if self.dsst is not None:
            self.dsst.init(frame, box)

    def learn(self, frame: np.ndarray, box: IntBox) -> None:
        """Fold the frame's box into DSST's vote, if any (the Haar models learn with the
        appearance model's learning step: :meth:`learning_extras`)."""
        if self.dsst is not None and self.dsst_updates.due():
            # the vote's own samples when the box is the one they were taken around (the same
            # samples, so the same filter, without taking them again)
            self.dsst.learn(frame, (box[0] + box[2] / 2.0, box[1] + box[3] / 2.0), (box[2], box[3]),
                            from_estimate=box == self._voted)

    def _dsst_vote(self, frame: np.ndarray, box: IntBox) -> Callable[[IntBox], float] | None:
        """DSST's response (divided by its peak) at a tried box's size, around ``box``."""
        if self.dsst is None:
            return None
        self._voted = box
        est = self.dsst.estimate(frame, (box[0] + box[2] / 2.0, box[1] + box[3] / 2.0),
                                 (box[2], box[3]))
        r = est.response.astype(np.float64)
        peak = float(r.max())
        r = r / peak if peak > 0 else r
        half = (r.size - 1) / 2.0
        log_step = math.log(self.dsst.settings.step)
        area = box[2] * box[3]

        def vote(tried: IntBox) -> float:
            k = half + 0.5 * math.log(tried[2] * tried[3] / area) / log_step
            return float(np.interp(k, np.arange(r.size), r))

        return vote

    # -- estimating ----------------------------------------------------------------------------
    def search(self, model: HaarAppearance, frame: np.ndarray, box: IntBox, raw: float,
               contrast: Callable[[IntBox], float] | None) -> tuple[IntBox, float]:
        """The box at the best scale around ``box`` (found with raw score ``raw``) and the
        raw score to report. ``contrast``: the colour cue's box contrast, if any. (The
        features read the appearance model's integral image, not ``frame``.)"""
        self.tried = []
        if self.settings.scale_model == "likelihood":
            return self._by_likelihood(model, box), raw
        return self._by_ratio(model, box, raw, contrast, self._dsst_vote(frame, box))

    def _likelihood(self, model: HaarAppearance, box: IntBox) -> float:
        pool = self.pool
        assert pool is not None
        return model.template_fit(box, pool.mu1, pool.sigma1)

    def _by_ratio(self, model: HaarAppearance, box: IntBox, best: float,
                  contrast: Callable[[IntBox], float] | None,
                  vote: Callable[[IntBox], float] | None) -> tuple[IntBox, float]:
        """Try the other scales with the strong classifier; the chosen box and raw score."""
        p = self.settings
        k = model.k
        mix = p.scale_mix if p.scale_model == "both" else 0.0
        best_value = best / k
        if mix:
            best_value += mix * self._likelihood(model, box)
        cw = p.scale_contrast if contrast is not None else 0.0
        if cw:
            assert contrast is not None
            best_value += cw * contrast(box)
        if vote is not None:
            best_value += p.scale_dsst * vote(box)
        best_index, best_box = self.index, box
        for j in range(-p.scale_steps, p.scale_steps + 1):
            index = self.index + j
            if j == 0 or not self.allowed(index, model):
                continue
            w, h = self.box_size(index)
            candidate = centred(box, w, h)
            self.tried.append(candidate)
            dx, dy, score, n = model.grid(candidate, p.scale_radius, self.frame_wh)
            if n == 0:
                continue
            moved = (candidate[0] + dx, candidate[1] + dy, w, h)
            value = score / k - p.scale_penalty * abs(j)
            if mix:
                value += mix * self._likelihood(model, moved)
            if cw:
                assert contrast is not None
                value += cw * contrast(moved)
            if vote is not None:
                value += p.scale_dsst * vote(moved)
            if value > best_value:
                best_value = value
                best = score
                best_index = index
                best_box = moved
        self.index = best_index
        return best_box, best

    def _by_likelihood(self, model: HaarAppearance, box: IntBox) -> IntBox:
        """The scale whose box best fits the target model over all M features."""
        p = self.settings
        fw, fh = self.frame_wh
        best_value = -math.inf
        best_index, best_box = self.index, box
        for j in range(-p.scale_steps, p.scale_steps + 1):
            index = self.index + j
            if j != 0 and not self.allowed(index, model):
                continue
            w, h = self.box_size(index)
            candidate = box if j == 0 else centred(box, w, h)
            x, y = candidate[0], candidate[1]
            if x < 0 or y < 0 or x + w > fw or y + h > fh:
                continue
            if j != 0:
                self.tried.append(candidate)
            value = self._likelihood(model, candidate) - p.scale_penalty * abs(j)
            if value > best_value:
                best_value, best_index, best_box = value, index, candidate
        self.index = best_index
        return best_box

    # -- learning --------------------------------------------------------------------------------
    def learning_extras(self, model: HaarAppearance, box: IntBox
                        ) -> tuple[np.ndarray | None, int, tuple[Any, ...] | None]:
        """What this estimator adds to the appearance model's learning step at ``box``: the
        feature values of the box at wrong scales (more negatives), their count, and its own
        target model for the core to update from the same positives."""
        p = self.settings
        wrong = self._wrong_scale_values(model, box) if p.scale_negatives > 0 else []
        extra = np.concatenate(wrong, axis=1) if wrong else None
        if self.pool is None and p.scale_model != "ratio":
            self.pool = GaussianPool(model.num_features)
        pool = self.pool
        second = None if pool is None else (pool.mu1, pool.sigma1, p.scale_learning_rate,
                                            pool.first(1))
        return extra, len(wrong), second

    def take_learnt(self, learnt: tuple[Any, Any], n_pos: int) -> None:
        """Keep the target model that the learning step updated (see :meth:`learning_extras`)."""
        pool = self.pool
        if pool is not None:
            mu2, sigma2 = learnt
            pool.assign(mu2, sigma2, pool.mu0, pool.sigma0, n_pos > 0, False)

    def _wrong_scale_values(self, model: HaarAppearance, box: IntBox) -> list[np.ndarray]:
        """Feature values of the target's box shrunk and grown by ``scale_negatives`` steps."""
        p = self.settings
        out = []
        for j in (-p.scale_negatives, p.scale_negatives):
            index = self.index + j
            if not self.allowed(index, model):
                continue
            w, h = self.box_size(index)
            x, y, _, _ = centred(box, w, h)
            if x < 0 or y < 0 or x + w > self.frame_wh[0] or y + h > self.frame_wh[1]:
                continue
            out.append(model.project(w, h, np.array([[x, y]], dtype=np.int32)))
        return out


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
        factor = self.estimator.estimate(frame, centre(box), self.size).factor
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
            self.estimator.learn(frame, centre(box), self.size,
                                 from_estimate=self.reuse)
