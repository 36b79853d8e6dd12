"""The scale estimators: after the translation search, the box at neighbouring scales competes with
it. :class:`HaarScale` stretches the Haar rectangles to each tried size (their weights rescaled
by the areas), so no image pyramid is built and a scale costs what a translation candidate
costs; :class:`DSSTScale` is DSST's 1-D correlation filter over the sizes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable, Literal

import numpy as np

from .classifier import GaussianPool
from .correlation import FilterLearning, ScaleFilter, ScaleFilterSettings, SparseUpdates
from .features import box_area_ok
from .frames import IntBox
from .geometry import centre, centred
from .settings import check_choices, check_ints, check_numbers, is_int, is_number, need

if TYPE_CHECKING:
    from .appearance import HaarAppearance

__all__ = ["DSSTScale", "HaarScale", "ScaleSettings", "dsst_filter", "dsst_min_side"]


@dataclass(frozen=True)
class ScaleSettings:
    """The scale estimator (:mod:`wmiltrack.engine.scale`): Haar rectangles scaled, not the image.

    Attributes
    ----------
    scale_steps : int
        After the translation search, also try the box scaled by ``scale_factor ** j`` for
        ``j = -scale_steps..scale_steps`` (0: no scale estimator; the box keeps its first size).
    scale_factor : float
        Ratio between neighbouring scales (> 1).
    scale_model : {"ratio", "likelihood", "both", "dsst"}
        ``dsst``: a separate 1-D correlation filter along 33 scales 1.02 apart on fHOG
        (DSST; :class:`wmiltrack.engine.scale.DSSTScale`), run after the translation
        search; ``scale_steps`` must be > 0 to switch it on, and the other ``scale_*``
        settings but ``scale_min``/``scale_max`` do not apply. Otherwise scales are compared
        by Haar features: ``ratio``, the strong classifier's mean log ratio (best of a
        ``scale_radius`` translation search at each scale); ``likelihood``, how well all M
        features of the box at each scale fit the target's Gaussians: minus the mean of
        ``log(1 + z^2)`` with ``z = (value - mu1) / sigma1`` (a generative template over the
        whole pool, which the background model cannot bias), with a target model of its
        own updated at ``scale_learning_rate``; ``both``: the sum of the two, the
        likelihood weighted by ``scale_mix`` (the classifier alone favours smaller boxes,
        the likelihood alone larger ones).
    scale_mix : float
        Weight of the likelihood term for ``scale_model="both"``.
    scale_learning_rate : float
        lambda of the ``likelihood`` scale model (slow, as DSST's 0.025 update: 0.975).
    scale_penalty : float
        Subtracted from a scale's mean weak-classifier log ratio per step away from the
        current scale (favours the current scale, as KCF's 0.95 factor does).
    scale_radius : int
        Translation search radius (step 1) at each tried scale other than the current one.
    scale_min, scale_max : float
        Limits of the scale relative to the first box.
    scale_negatives : int
        Also learn, as negatives, the box centred on the target but scaled by
        ``scale_factor ** +-scale_negatives`` (so the classifier learns what a wrong size
        looks like; 0: none).
    scale_contrast : float
        With a colour cue (``colour_weight > 0``) and ``scale_model`` ``"ratio"`` or
        ``"both"``: add this weight times each tried box's colour contrast
        (:func:`wmiltrack.engine.colour.colour_contrast`: the mean ``P(target | colour)``
        inside the box minus that over a ring around it, read from the search's likelihood
        table) to that scale's value (0: off). The classifier prefers smaller boxes and the
        target likelihood larger ones; the contrast is largest for the box that holds the
        target's colours and no more. A contrast changes by about 0.01 between neighbouring
        scales, so a weight of 20 makes it count about as much as one step's
        ``scale_penalty`` (0.2).
    scale_samples : int
        DSST's scale samples (``scale_model="dsst"`` and ``scale_dsst``), odd, always over
        DSST's range of sizes (33 samples 1.02 apart) with a label as wide: fewer cost less
        (fDSST uses 17).
    scale_veto : bool
        With ``scale_model="dsst"`` and a colour cue: the size DSST prefers is taken only if
        its box's colour contrast (as for ``scale_contrast``) is at least the current box's,
        else the size is kept. DSST's fHOG scale samples cannot tell a low-textured or
        deforming target from its surroundings and let the box grow into them (a bag on a
        street: 0.70 -> 0.24 AUC); the colour contrast falls as soon as background enters.
    template_gate, template_every, template_reuse
        Shared with :class:`~wmiltrack.engine.template.TemplateSettings`: the DSST scale
        filters (``scale_model="dsst"`` and ``scale_dsst``'s vote) learn on the translation
        filter's schedule.
    min_box_size
        Shared with :class:`~wmiltrack.engine.features.FeatureSettings`: DSST gives no box
        side below it (nor below 4).
    """

    scale_steps: int = 0
    scale_factor: float = 1.03
    scale_model: Literal["ratio", "likelihood", "both", "dsst"] = "ratio"
    scale_learning_rate: float = 0.975
    scale_mix: float = 1.0
    scale_penalty: float = 0.0
    scale_radius: int = 2
    scale_min: float = 0.2
    scale_max: float = 5.0
    scale_negatives: int = 0
    scale_contrast: float = 0.0
    scale_dsst: float = 0.0
    scale_samples: int = 33
    scale_veto: bool = False
    template_gate: float = 0.0
    template_every: int = 1
    template_reuse: bool = False
    min_box_size: int = 4

    def __post_init__(self) -> None:
        ScaleSettings.check(self)

    def check(self) -> None:
        """``ValueError`` naming the first setting out of range."""
        check_choices(self, {"scale_model": ("ratio", "likelihood", "both", "dsst")})
        check_ints(self, "scale_steps", "scale_radius", "scale_negatives")
        check_numbers(self, "scale_factor", "scale_penalty", "scale_min", "scale_max", "scale_mix",
                      "scale_contrast", "scale_dsst")
        need(self.scale_dsst >= 0, f"scale_dsst must be >= 0, got {self.scale_dsst}")
        need(is_int(self.scale_samples) and 3 <= self.scale_samples <= 65
             and self.scale_samples % 2 == 1,
             f"scale_samples must be an odd int in 3..65, got {self.scale_samples!r}")
        need(isinstance(self.scale_veto, bool),
             f"scale_veto must be True or False, got {self.scale_veto!r}")
        need(0 <= self.scale_steps <= 10, f"scale_steps must be in 0..10, got {self.scale_steps}")
        need(is_number(self.scale_learning_rate) and 0.0 <= self.scale_learning_rate < 1.0,
             f"scale_learning_rate must be in [0, 1), got {self.scale_learning_rate}")
        need(0 <= self.scale_negatives <= 20,
             f"scale_negatives must be in 0..20, got {self.scale_negatives}")
        need(self.scale_negatives == 0 or self.scale_steps > 0,
             "scale_negatives needs the scale search (scale_steps > 0)")
        need(1.0 < self.scale_factor <= 2.0, f"scale_factor must be in (1, 2], got {self.scale_factor}")
        need(self.scale_penalty >= 0, f"scale_penalty must be >= 0, got {self.scale_penalty}")
        need(self.scale_contrast >= 0, f"scale_contrast must be >= 0, got {self.scale_contrast}")
        need(1 <= self.scale_radius <= 50, f"scale_radius must be in 1..50, got {self.scale_radius}")
        need(0 < self.scale_min <= 1.0 <= self.scale_max <= 100.0,
             f"need 0 < scale_min <= 1 <= scale_max <= 100, got {self.scale_min}, {self.scale_max}")


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
    (:class:`~wmiltrack.engine.features.FeatureSettings`)."""
    return max(min_box_size, 4)


class DSSTScale:
    """DSST's scale filter as the scale estimator (``scale_model="dsst"``): after the translation
    search, the best of 33 sizes 1.02 apart by a 1-D correlation filter on fHOG, within
    ``scale_min``..``scale_max`` of the first box and the frame, no side below
    :func:`dsst_min_side`. It learns as the translation filter does (the ``template_*``
    learning settings it shares: :class:`~wmiltrack.engine.correlation.FilterLearning`)."""

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
