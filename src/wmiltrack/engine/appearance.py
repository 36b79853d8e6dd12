"""The appearance model: a Haar feature bank, online Gaussian weak classifiers and the choice of
the strong classifier's features. This is what the six paper presets differ in.

One frame's work for it: an integral image of the target's neighbourhood (C++), the coarse
and fine candidate scoring (C++), the positive and negative bags around the new box (Python
or C++), their feature values, the Gaussian update and the feature selection (C++). A preset
made of nothing but this model runs all of that in one call to the core
(:meth:`HaarAppearance.fused_request`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .. import _core
from .classifier import ClassifierSettings, GaussianPool
from .features import (
    CHANNEL_IDS,
    EDGE_CHANNELS,
    BankArrays,
    FeatureSettings,
    available_channels,
    check_box_size,
    make_bank,
    min_box_size,
    rect_planes,
    scale_bank,
)
from .frames import IntBox
from .geometry import roi_around
from .requests import (
    Drawn,
    Learn,
    LearningRule,
    Learnt,
    Search,
    Step,
    Steps,
    as_drawn,
    as_learnt,
    learn_at_request,
    learn_request,
    search_request,
    step_request,
)
from .sampling import BagSampler, BagSettings
from .selection import milboost_select
from .settings import MAX_SEARCH_RADIUS, check_ints, need

__all__ = ["AppearanceSettings", "HaarAppearance", "SearchSettings"]


@dataclass(frozen=True)
class SearchSettings:
    """The translation search: a coarse grid, then an optional fine one around its winner.

    Attributes
    ----------
    coarse_radius, coarse_step : int
        Search grid: offsets (i, j) * step with |offset| < radius.
    fine_radius, fine_step : int
        Second, finer search around the coarse winner (``fine_radius=0``: none).
    """

    coarse_radius: int = 25
    coarse_step: int = 4
    fine_radius: int = 10
    fine_step: int = 1

    def __post_init__(self) -> None:
        SearchSettings.check(self)

    def check(self) -> None:
        """``ValueError`` naming the first setting out of range."""
        check_ints(self, "coarse_radius", "coarse_step", "fine_radius", "fine_step")
        need(self.coarse_radius >= 1 and self.coarse_step >= 1,
             f"coarse_radius and coarse_step must be >= 1, got {self.coarse_radius}, {self.coarse_step}")
        need(self.coarse_radius <= MAX_SEARCH_RADIUS and self.fine_radius <= MAX_SEARCH_RADIUS,
             f"coarse_radius and fine_radius must be <= {MAX_SEARCH_RADIUS}, got "
             f"{self.coarse_radius}, {self.fine_radius}")
        need(self.fine_radius >= 0 and self.fine_step >= 1,
             f"fine_radius must be >= 0 and fine_step >= 1, got {self.fine_radius}, {self.fine_step}")

    @property
    def stage_reach(self) -> int:
        """Largest distance in pixels that the coarse and fine grids move the box."""
        reach = self.coarse_radius - 1
        if self.fine_radius > 0:
            reach += self.fine_radius - 1
        return reach


@dataclass(frozen=True)
class AppearanceSettings(SearchSettings, ClassifierSettings, BagSettings, FeatureSettings):
    """The appearance model's settings (:class:`~wmiltrack.engine.appearance.HaarAppearance`):
    the feature bank, the bags, the weak classifiers and their selection, and the search; the
    four classes above at once (no field of its own)."""

    def __post_init__(self) -> None:
        AppearanceSettings.check(self)

    def check(self) -> None:
        """``ValueError`` naming the first setting out of range."""
        for part in (FeatureSettings, BagSettings, ClassifierSettings, SearchSettings):
            part.check(self)


_NO_CORNERS = np.zeros((0, 2), dtype=np.int32)  # a learning request whose boxes the core samples
_NO_CORNERS.setflags(write=False)


class HaarAppearance:
    """Haar features, their Gaussian weak classifiers and the selected strong classifier.

    Built by :meth:`start` on a tracker's first frame from its seed: the feature bank (and,
    with ``Params.channels``, each feature's image channel) is drawn from the tracker's own
    generator, which then draws every frame's negatives, so the same seed and frames give the
    same boxes.
    """

    def __init__(self, params: AppearanceSettings, seed: int, *, variant: str = "rcwmil") -> None:
        self.params = params
        self.seed = seed
        self.variant = variant  # the preset's name, for messages
        self.ii = _core.IntegralImage()
        # the learning step's fixed settings
        self._rule = LearningRule(lam=params.learning_rate,
                                  direct_first=params.first_update == "direct",
                                  mil=params.classifier == "mil", sigma_floor=params.sigma_floor,
                                  guard=params.guard, k=params.num_selected,
                                  code_gradient=params.gradient == "code")
        # the selection of a learning step on bags the core draws (the core drops WMIL if no
        # positive fits in the frame)
        self._core_select = self._select_kind(1)
        self.first_sampler = BagSampler(params, first_frame=True)
        self.sampler = BagSampler(params)
        self.bags: tuple[Any, ...] = ()
        self.chan_names: tuple[str, ...] | None = None

    # -- copies ----------------------------------------------------------------------------
    def __getstate__(self) -> dict[str, Any]:
        """What a copy or a pickle keeps: everything but what is rebuilt from it (the core's
        bag draws, which hold this model's generator, and the core's feature banks)."""
        state = self.__dict__.copy()
        state.pop("_bags_for", None)
        state.pop("_banks", None)
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state, _bags_for={})
        if "bank_arrays" in state:  # started: the base bank again (the others on demand)
            self.__dict__["_banks"] = {self.base_wh: self._core_bank(self.bank_arrays)}

    # -- state -----------------------------------------------------------------------------
    def start(self, img: np.ndarray, box: IntBox) -> None:
        """Draw the feature bank for ``box`` and start untrained classifiers (the first frame's
        learning is the tracker's next step)."""
        p = self.params
        w, h = box[2], box[3]
        check_box_size(p, w, h, self.variant)
        self.rng = np.random.default_rng(self.seed)
        self.bank_arrays: BankArrays = make_bank(p, w, h, self.rng)
        # Channels: each feature on one channel, drawn from its own stream; the integral image
        # holds one plane per channel and each rectangle reads its feature's.
        self.chan_names = None
        self.chan_ids: list[int] = []
        self.rect_planes: np.ndarray | None = None
        self.edge_rects: np.ndarray | None = None
        if p.channels:
            names = available_channels(p.channels, img)
            chan_rng = np.random.default_rng([self.seed, 1])
            self.feature_channel = chan_rng.integers(0, len(names), size=self.bank_arrays.size)
            self.chan_names = names
            self.chan_ids = [CHANNEL_IDS[c] for c in names]
            self.rect_planes = rect_planes(self.bank_arrays, self.feature_channel)
            edge_plane = np.array([c in EDGE_CHANNELS for c in names], dtype=bool)
            self.edge_rects = edge_plane[self.rect_planes]
        self.base_wh = (w, h)
        self._min_box = min_box_size(p)
        self._banks: dict[tuple[int, int], _core.FeatureBank] = {
            (w, h): self._core_bank(self.bank_arrays)}
        self.pool = GaussianPool(p)
        self.selected = np.arange(p.num_selected, dtype=np.int32)
        self.bags = ()
        self._bags_for: dict[str, _core.BagRequest] = {}  # the core's draws, by weights

    @property
    def k(self) -> int:
        """How many features the strong classifier sums (at least 1)."""
        return max(len(self.selected), 1)

    @property
    def can_fuse(self) -> bool:
        """Whether a whole frame step can run as one core call (:meth:`fused_request`): luma
        features only, and negatives the core can draw exactly as numpy would
        (:meth:`~wmiltrack.engine.sampling.BagSampler.drawn_in_core`)."""
        return self.chan_names is None and self.sampler.drawn_in_core()

    @property
    def num_features(self) -> int:
        """How many features the bank holds (M)."""
        return self.params.num_features

    @property
    def min_box(self) -> tuple[int, int]:
        """The smallest ``(w, h)`` box the features allow (found at :meth:`start`: the scale
        search asks it for every size it tries)."""
        return self._min_box

    @property
    def reach(self) -> int:
        """How far from the box the tracking bags reach."""
        return self.sampler.reach

    def bank(self, w: int, h: int) -> _core.FeatureBank:
        """The feature bank stretched to a ``w x h`` box (cached)."""
        bank = self._banks.get((w, h))
        if bank is None:
            arrays = scale_bank(self.bank_arrays, self.base_wh[0], self.base_wh[1], w, h,
                                self.edge_rects)
            bank = self._banks[(w, h)] = self._core_bank(arrays)
        return bank

    def _core_bank(self, arrays: BankArrays) -> _core.FeatureBank:
        return _core.FeatureBank(arrays.starts, arrays.rects, arrays.weights,
                                 channels=self.rect_planes)

    # -- the integral image ------------------------------------------------------------------
    def compute_integral(self, img: np.ndarray, box: IntBox, margin: int) -> None:
        """The integral image of ``box`` and ``margin`` pixels around it (every channel)."""
        roi = roi_around(box, margin)
        if self.chan_names is not None:
            if img.ndim == 2 or img.shape[2] == 1:
                if available_channels(self.chan_names, img) != self.chan_names:
                    raise ValueError("this tracker was started on a colour frame and uses colour "
                                     "channels; call init() to restart on gray frames")
            self.ii.compute_channels(img, roi, self.chan_ids)
        else:
            self.ii.compute(img, roi)

    def covered_by(self, ii: _core.IntegralImage, roi: IntBox, frame_wh: tuple[int, int]) -> bool:
        """Whether this model can read the luma integral image ``ii`` for ``roi`` clipped to
        a ``frame_wh`` frame (it uses no other channel and ``ii`` holds the region)."""
        if self.chan_names is not None:
            return False
        return (ii.num_channels == 1 and ii.channels == (_core.CH_LUMA,)
                and _holds(ii, roi, frame_wh))

    def holds(self, roi: IntBox, frame_wh: tuple[int, int]) -> bool:
        """Whether this model's own integral image holds ``roi`` clipped to a ``frame_wh``
        frame (learning there needs no new table)."""
        return _holds(self.ii, roi, frame_wh)

    # -- search ------------------------------------------------------------------------------
    def search_request(self, box: IntBox, stages: list[tuple[int, int]], frame_wh: tuple[int, int],
                       img: np.ndarray | None, roi: IntBox | None, cue: tuple[Any, ...] | None
                       ) -> Search:
        """The core's coarse-to-fine search from ``box``; with ``img`` and ``roi`` the core
        computes the luma integral image of ``roi`` first; ``cue`` is merged into each stage."""
        pool = self.pool
        return search_request(ii=self.ii, bank=self.bank(box[2], box[3]), selected=self.selected,
                              mu1=pool.mu1, sigma1=pool.sigma1, mu0=pool.mu0, sigma0=pool.sigma0,
                              guard=self.params.guard, box=box, stages=stages,
                              frame_size=frame_wh, frame=img, roi=roi, cues=cue)

    def prepare(self, img: np.ndarray | None, box: IntBox, margin: int
                ) -> tuple[np.ndarray | None, IntBox | None]:
        """Make ready the integral image that a search from ``box`` reads, ``margin`` pixels
        around it, before anything else of the frame (a frame the model cannot read is refused
        here): a several-channel model's is computed here; a luma model's is computed by the
        core in the search's own call, from the ``(frame, region)`` returned (pass them to
        :meth:`search_request`). ``img=None``: the integral image this model holds (one shared
        by several trackers); ``(None, None)`` is returned then and for a several-channel
        model."""
        if img is None:
            return None, None
        if self.chan_names is not None:
            self.compute_integral(img, box, margin)
            return None, None
        return img, roi_around(box, margin)

    def grid(self, box: IntBox, radius: int, frame_wh: tuple[int, int]) -> tuple[int, int, float, int]:
        """Best offset, its raw score and the candidate count of the step-1 grid of
        ``radius`` around ``box`` (one search stage, at ``box``'s size)."""
        request = self.search_request(box, [(radius, 1)], frame_wh, None, None, None)
        ((dx, dy, score, n),) = _core.search(request)
        return dx, dy, score, n

    def project(self, w: int, h: int, corners: np.ndarray) -> np.ndarray:
        """Feature values ``(M, n)`` of the ``w x h`` boxes with these top-left corners."""
        values: np.ndarray = _core.project(self.ii, self.bank(w, h), corners[:, 0], corners[:, 1])
        return values

    def template_fit(self, box: IntBox, mu: np.ndarray, sigma: np.ndarray) -> float:
        """Minus the mean log(1 + z^2) of all M features of ``box`` under ``N(mu, sigma)``."""
        return float(_core.template_fit(self.ii, self.bank(box[2], box[3]), box[0], box[1], mu,
                                        sigma))

    # -- learning ----------------------------------------------------------------------------
    def learn_steps(self, box: IntBox, frame_wh: tuple[int, int], sampler: BagSampler,
                    extra: np.ndarray | None = None, n_extra: int = 0,
                    second: tuple[Any, ...] | None = None) -> Steps:
        """Sample the bags around ``box``, update the Gaussians and reselect the features, as
        one core request (see :data:`~wmiltrack.engine.requests.Steps`): with the tracking
        sampler, where the core can draw as numpy would, the core samples the bags too.
        ``extra``: feature values of ``n_extra`` more negatives; ``second``: another target
        model the core updates from the same positives (``(mu, sigma, rate, first)``). Returns
        that model's ``(mu, sigma)`` (None without one)."""
        if sampler is self.sampler and self.sampler.drawn_in_core():
            # The core draws the bags (as the sampler would, from this model's generator) and
            # learns in the same call.
            request, bags = self._learning_on_core_bags(box, extra, second)
            answer, bags_drawn = yield learn_at_request(learn=request, bags=bags, box=box,
                                               frame_size=frame_wh)
            learnt = as_learnt(answer)
            self._take_core_bags(learnt, as_drawn(bags_drawn), n_extra)
            return learnt.second_mu, learnt.second_sigma
        fw, fh = frame_wh
        pos, dist = sampler.positives(box, fw, fh)
        neg = sampler.negatives(box, fw, fh, self.rng)
        self.bags = (pos, neg)
        select = self._select_kind(pos.shape[0])
        w = sampler.weights(dist, self.params.instance_weights) if select == "wmil" else None
        request = self._learn_request(box, np.concatenate((pos, neg)), pos.shape[0], select, w,
                                      extra, second)
        learnt = as_learnt((yield request))
        self._take_learnt(learnt, pos.shape[0], neg.shape[0] + n_extra)
        return learnt.second_mu, learnt.second_sigma

    def skip_learning(self) -> None:
        """Record that this frame was not learnt from (no bags)."""
        self.bags = (_NO_CORNERS, _NO_CORNERS)

    def fused_request(self, search: Search, frame_box: IntBox) -> Step:
        """The search, the bags and the learning as one core request: the core samples the
        bags where the search lands (drawing the negatives from this model's generator
        exactly as :class:`~wmiltrack.engine.sampling.BagSampler` would) and learns; its
        answer goes to :meth:`take_fused`. The same draws and state changes as a search then
        :meth:`learn_steps`."""
        request, bags = self._learning_on_core_bags(frame_box)
        return step_request(search=search, learn=request, bags=bags)

    def take_fused(self, answer: tuple[Any, Any, Any]) -> Any:
        """Keep what the core answered to a :meth:`fused_request` (the bags and the model);
        returns the search's per-stage results."""
        results, learnt, drawn = answer
        self._take_core_bags(as_learnt(learnt), as_drawn(drawn))
        return results

    def _learning_on_core_bags(self, box: IntBox, extra: np.ndarray | None = None,
                               second: tuple[Any, ...] | None = None
                               ) -> tuple[Learn, _core.BagRequest]:
        """A learning request whose bags the core draws (for ``box``'s size), and that draw."""
        select = self._core_select
        return (self._learn_request(box, _NO_CORNERS, 0, select, None, extra, second),
                self._bag_request(select))

    def _take_core_bags(self, learnt: Learnt, drawn: Drawn, n_extra: int = 0) -> None:
        """Keep what a learning step on bags the core drew returned: the bags ``(xs, ys,
        n_pos)`` (split by :meth:`corners` when asked) and the model."""
        self.bags = tuple(drawn)
        self._take_learnt(learnt, drawn.n_pos, drawn.xs.shape[0] - drawn.n_pos + n_extra)

    def _bag_request(self, select: str) -> _core.BagRequest:
        """The tracking bags' draw from this model's generator, for the core (made once)."""
        weights = self.params.instance_weights if select == "wmil" else "none"
        request = self._bags_for.get(weights)
        if request is None:
            request = self._bags_for[weights] = _core.BagRequest(self.rng,
                                                                 *self.sampler.core_spec(weights))
        return request

    def corners(self) -> tuple[np.ndarray, np.ndarray]:
        """Top-left corners of the last positive and negative bags learnt from."""
        if len(self.bags) == 3:  # (xs, ys, n_pos) from the core's frame step
            xs, ys, n_pos = self.bags
            corners = np.stack((xs, ys), axis=1)
            self.bags = (corners[:n_pos], corners[n_pos:])
        pos, neg = self.bags
        return pos, neg

    def _select_kind(self, n_pos: int) -> str:
        """The learning step's ``select``: WMIL in the core, the log ratios for a MILBoost
        selection here, or none (no selection, or no positive this frame)."""
        p = self.params
        if p.selection == "none" or n_pos == 0:
            return "none"
        return "wmil" if p.selection == "wmil" else "ratios"

    def _learn_request(self, box: IntBox, corners: np.ndarray, n_pos: int, select: str,
                       w: np.ndarray | None, extra: np.ndarray | None,
                       second: tuple[Any, ...] | None) -> Learn:
        """``_core.learn``'s arguments for the bags with these top-left ``corners`` (the
        ``n_pos`` positives, weighted ``w`` for WMIL, then the negatives) of ``box``'s size."""
        pool = self.pool
        return learn_request(ii=self.ii, bank=self.bank(box[2], box[3]), xs=corners[:, 0],
                             ys=corners[:, 1], n_pos=n_pos,
                             model=(pool.mu1, pool.sigma1, pool.mu0, pool.sigma0),
                             first=(pool.first(1), pool.first(0)), rule=self._rule,
                             select=select, w_pos=w, extra_neg=extra, second=second)

    def _take_learnt(self, learnt: Learnt, n_pos: int, n_neg: int) -> None:
        """Keep the model and the selection that a learning request returned."""
        self.pool.assign(learnt.mu1, learnt.sigma1, learnt.mu0, learnt.sigma0, n_pos > 0,
                         n_neg > 0)
        h = learnt.h
        if learnt.selected is not None:
            self.selected = learnt.selected
        elif h is not None:
            self.selected = milboost_select(h[:, :n_pos], h[:, n_pos:], self.params.num_selected,
                                            guard=self.params.guard)


def _holds(ii: _core.IntegralImage, roi: IntBox, frame_wh: tuple[int, int]) -> bool:
    """Whether the integral image ``ii`` holds ``roi`` clipped to a ``frame_wh`` frame."""
    x, y, w, h = roi
    x0, y0 = max(x, 0), max(y, 0)
    x1, y1 = min(x + w, frame_wh[0]), min(y + h, frame_wh[1])
    return ii.x0 <= x0 and ii.y0 <= y0 and ii.x0 + ii.width >= x1 and ii.y0 + ii.height >= y1
