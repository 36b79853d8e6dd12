"""The tracker: one engine, six variants (rcwmil, ct, fct, mil, wmil, osil).

One frame walks one way: frame -> integral image of the target's neighbourhood (C++) ->
coarse and fine candidate scoring (C++) -> new box -> positive and negative bags (Python)
-> feature values (C++) -> Gaussian update (numpy) -> feature selection (Cython).
"""

from __future__ import annotations

import functools
import math
import threading
from collections.abc import Generator
from typing import Any, Callable, TypeVar

import numpy as np

from .. import _core
from .classifier import GaussianPool
from .colour import ColourModel, box_contrast
from .features import (
    CHANNEL_IDS,
    EDGE_CHANNELS,
    BankArrays,
    available_channels,
    box_area_ok,
    check_box_size,
    make_bank,
    min_box_size,
    rect_planes,
    scale_bank,
    zero_dc_bank,
)
from .frames import IntBox, as_frame, clip_box, frame_size
from .params import CONFIDENCE_OFFSET, Params
from .result import TrackResult
from .sampling import BagSampler, core_draws_match_numpy
from .selection import milboost_select


class _Search(tuple):  # type: ignore[type-arg]
    """A request for the core's search (``_core.search``'s arguments, in order)."""


class _Learn(tuple):  # type: ignore[type-arg]
    """A request for the core's learning step (``_core.learn``'s arguments, in order)."""


class _Step(tuple):  # type: ignore[type-arg]
    """A request for a whole frame step in one core call (``_core.frame_step``'s arguments:
    a search, a learning step, and the bag sampler whose bags the core draws where the
    search lands)."""


_NO_CORNERS = np.zeros((0, 2), dtype=np.int32)  # a learning request whose boxes the core samples
_NO_CORNERS.setflags(write=False)

_LEARN_KEYS = ("lam", "first_pos", "first_neg", "direct_first", "mil", "sigma_floor", "guard",
               "select", "w_pos", "k", "code_gradient", "extra_neg", "second")

Steps = Generator[tuple[Any, ...], Any, Any]
"""A frame step written as a generator: it yields requests for the core (:class:`_Search`,
:class:`_Learn`, or a fused :class:`_Step`) and receives their results, so that one tracker
runs them one by one (:func:`_drive`) and :func:`update_many` runs those of many trackers in
parallel."""


def _run(request: tuple[Any, ...]) -> Any:
    if isinstance(request, _Search):
        return _core.search(*request)
    if isinstance(request, _Step):
        return _core.frame_step(*request)
    return _core.learn(*request[:9], **dict(zip(_LEARN_KEYS, request[9:])))


def _drive(steps: Steps) -> Any:
    """Run a frame step's core requests one by one; its return value."""
    try:
        request = next(steps)
        while True:
            request = steps.send(_run(request))
    except StopIteration as stop:
        return stop.value


class NotInitializedError(ValueError):
    """``update`` was called before ``init``."""


def _covers(ii: _core.IntegralImage, roi: IntBox, frame_wh: tuple[int, int]) -> bool:
    """Whether a luma integral image holds ``roi`` clipped to a ``frame_wh`` frame."""
    x, y, w, h = roi
    x0, y0 = max(x, 0), max(y, 0)
    x1, y1 = min(x + w, frame_wh[0]), min(y + h, frame_wh[1])
    return (ii.num_channels == 1 and ii.channels == (_core.CH_LUMA,) and ii.x0 <= x0 and ii.y0 <= y0
            and ii.x0 + ii.width >= x1 and ii.y0 + ii.height >= y1)


_F = TypeVar("_F", bound=Callable[..., Any])


def _one_thread_at_a_time(method: _F) -> _F:
    """RuntimeError when another thread is inside a guarded method of the same tracker."""
    @functools.wraps(method)
    def guarded(self: Tracker, *args: Any, **kwargs: Any) -> Any:
        if not self._busy.acquire(blocking=False):
            raise RuntimeError(
                "this Tracker is in use by another thread: a Tracker may be used by one thread "
                "at a time (use one Tracker per thread)")
        try:
            return method(self, *args, **kwargs)
        finally:
            self._busy.release()
    return guarded  # type: ignore[return-value]


def _sigmoid(z: float) -> float:
    if z >= 0:
        return 1.0 / (1.0 + math.exp(-z))
    e = math.exp(z)
    return e / (1.0 + e)



def confidence(raw: float, k: int, offset: float = CONFIDENCE_OFFSET) -> float:
    """Confidence in [0, 1] of a frame from its best candidate's summed log ratio ``raw``.

    ``logistic(raw / k - offset)`` (``offset``: ``Params.confidence_offset``, by default
    :data:`CONFIDENCE_OFFSET`): 0.5 at the point where, on the benchmark sequences, tracked
    and lost frames were equally likely; 0 when no candidate was scored.

    This is ``TrackResult.score`` of the six paper variants. With ``Params.score_colour`` or
    ``Params.score_luma`` (rcwmil-plus) the reported score is a weighted mean of it and the
    box's colour / intensity contrasts (each ``clip(0.5 + contrast, 0, 1)``), still in [0, 1]
    with 0.5 as the tracked/lost boundary; the tracker's own decisions (motion, gating,
    recovery) keep reading this confidence.
    """
    if not math.isfinite(raw):
        return 0.0
    return _sigmoid(raw / max(k, 1) - offset)


class Tracker:
    """A single-object tracker.

    Parameters
    ----------
    variant : str
        ``"rcwmil"`` (default, the paper's tracker), ``"ct"``, ``"fct"``, ``"mil"``,
        ``"wmil"``, ``"osil"`` or ``"rcwmil-plus"``; see :func:`wmiltrack.variants`.
    seed : int
        Seed of the random feature bank and negative sampling. The same seed and the same
        frames give identical boxes.
    params : Params, optional
        Start from these parameters instead of the variant's defaults.
    **overrides
        Any :class:`~wmiltrack.Params` field, e.g. ``num_selected=30``.

    Threads: a Tracker holds one target's state, so it may be used by one thread at a time;
    ``init``/``update`` called while another thread is inside one of them raise
    ``RuntimeError`` (nothing is changed). Different trackers may run in different threads
    at once (the compiled core releases the GIL and shares no state between them).

    Examples
    --------
    >>> t = Tracker("rcwmil", seed=0)            # doctest: +SKIP
    >>> t.init(frame0, (x, y, w, h))             # doctest: +SKIP
    >>> r = t.update(frame1); r.box, r.score     # doctest: +SKIP
    """

    def __init__(self, variant: str = "rcwmil", *, seed: int = 0, params: Params | None = None,
                 **overrides: Any) -> None:
        if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
            raise ValueError(f"seed must be a non-negative int, got {seed!r}")
        if params is None:
            params = Params.for_variant(variant, **overrides)
        elif overrides:
            params = params.replace(**overrides)
        self._params = params
        self._seed = int(seed)
        self._ii = _core.IntegralImage()
        self._busy = threading.Lock()
        self._initialized = False
        self._frame_wh = (0, 0)
        self._box: IntBox = (0, 0, 0, 0)
        self._score = math.nan
        self._first = BagSampler(params, first_frame=True)
        self._track = BagSampler(params)

    # -- public API ------------------------------------------------------------------------
    @property
    def params(self) -> Params:
        """The parameters in force (frozen)."""
        return self._params

    @property
    def variant(self) -> str:
        """Name of the variant the parameters started from (``"rcwmil"``, ``"ct"``, ...)."""
        return self._params.variant

    @property
    def initialized(self) -> bool:
        """Whether ``init`` has been called, so that ``update`` may be."""
        return self._initialized

    @property
    def box(self) -> tuple[float, float, float, float]:
        """The current box ``(x, y, w, h)``."""
        self._require_init()
        x, y, w, h = self._box
        return float(x), float(y), float(w), float(h)

    @_one_thread_at_a_time
    def init(self, frame: np.ndarray, box: Any) -> None:
        """Start tracking the object in ``box = (x, y, w, h)`` of ``frame``.

        The box is rounded to whole pixels and clipped to the frame; a box wholly outside
        the frame, with non-finite values, non-positive size, or smaller than the variant's
        features need after clipping is a ``ValueError``. Calling ``init`` again restarts
        the tracker (same seed: same result).
        """
        img = as_frame(frame)
        fw, fh = frame_size(img)
        b = clip_box(box, fw, fh)
        check_box_size(self._params, b[2], b[3])
        p = self._params
        self._rng = np.random.default_rng(self._seed)
        self._bank_arrays: BankArrays = make_bank(p, b[2], b[3], self._rng)
        # Channels (rcwmil-plus): each feature on one channel, drawn from its own stream; the
        # integral image holds one plane per channel and each rectangle reads its feature's.
        self._chan_names: tuple[str, ...] | None = None
        self._chan_ids: list[int] = []
        self._rect_planes: np.ndarray | None = None
        self._edge_rects: np.ndarray | None = None
        # Frames without colour (gray, or BGR with equal channels) may use other channels and
        # another anchor (Params.gray_channels, gray_anchor_weight).
        gray = not ColourModel.usable(img)
        channels = p.gray_channels if gray and p.gray_channels else p.channels
        self._anchor_weight = (p.gray_anchor_weight if gray and p.gray_anchor_weight is not None
                               else p.anchor_weight)
        if p.zero_dc != "none" and not channels:
            self._bank_arrays = zero_dc_bank(p, self._bank_arrays, b[2], b[3])
        if channels:
            names = available_channels(channels, img)
            chan_rng = np.random.default_rng([self._seed, 1])
            self._feature_channel = chan_rng.integers(0, len(names), size=self._bank_arrays.size)
            if p.zero_dc != "none":
                which = np.array([not p.zero_dc_channels or c in p.zero_dc_channels
                                  for c in names], dtype=bool)[self._feature_channel]
                self._bank_arrays = zero_dc_bank(p, self._bank_arrays, b[2], b[3], which)
            self._chan_names = names
            self._chan_ids = [CHANNEL_IDS[c] for c in names]
            self._rect_planes = rect_planes(self._bank_arrays, self._feature_channel)
            edge_plane = np.array([c in EDGE_CHANNELS for c in names], dtype=bool)
            self._edge_rects = edge_plane[self._rect_planes]
        self._bank = self._make_core_bank(self._bank_arrays)
        # Scale state (rcwmil-plus): the box is the first box scaled by scale_factor ** index.
        self._base_wh = (b[2], b[3])
        self._scale_index = 0
        self._banks: dict[int, tuple[_core.FeatureBank, BankArrays]] = {
            0: (self._bank, self._bank_arrays)}
        # Motion and recovery state (rcwmil-plus).
        self._velocity = (0.0, 0.0)
        self._last_good: IntBox = b
        self._lost = False
        self._level = math.nan  # running mean of raw / K over the frames learnt from
        self._scale_boxes: list[IntBox] = []
        self._cue_table: tuple[np.ndarray, int, int] | None = None
        self._pool = GaussianPool(p)
        self._anchor: tuple[np.ndarray, np.ndarray] | None = None
        self._scale_pool = (GaussianPool(p.replace(learning_rate=p.scale_learning_rate))
                            if p.scale_steps > 0 and p.scale_model != "ratio" else None)
        self._selected = np.arange(p.num_selected, dtype=np.int32)
        self._frame_wh = (fw, fh)
        self._box = b
        self._colour: ColourModel | None = None
        if p.colour_weight > 0 and (p.gray_colour or not gray):
            self._colour = ColourModel(learning_rate=p.colour_learning_rate, intensity=gray,
                                       sample=p.colour_sample)
            self._colour.learn(img, b)
        # The first frame's colour histograms, kept unchanged for the reported score.
        self._first_colour: ColourModel | None = None
        if self._colour is not None and p.score_colour > 0 and p.score_colour_model == "first":
            self._first_colour = self._colour.copy()
        # The first frame's intensity histograms (any frame), for the reported score.
        self._first_luma: ColourModel | None = None
        if p.score_luma > 0:
            self._first_luma = ColourModel(intensity=True, sample=p.colour_sample)
            self._first_luma.learn(img, b)
        # The last bags learnt from: (positives, negatives) corners, or (xs, ys, n_pos) as the
        # core's frame step returns them (samples() splits them when asked).
        self._bags: tuple[Any, ...] = ()
        self._compute_integral(img, b, self._first.reach)
        self._learn(self._first)
        self._search_origins: list[IntBox] = []
        self._search_stages: list[tuple[int, int]] = []
        self._score = 1.0
        # A paper-family step: luma only, no colour, scale, motion, recovery or anchor, and it
        # learns from every frame at the full rate, so the step can be fused into one call
        # (with the bags drawn in the core, where the core's draws match this numpy's).
        self._plain = (core_draws_match_numpy() and self._track.drawn_in_core()
                       and self._chan_names is None and self._colour is None
                       and self._scale_pool is None
                       and self._first_luma is None and p.scale_steps == 0 and p.scale_negatives == 0
                       and p.motion == "none" and p.recovery_radius == 0 and self._anchor_weight == 0
                       and p.gate_threshold <= 0.0 and p.gate_drop <= 0.0
                       and p.gate_learning_rate is None)
        self._initialized = True

    reinit = init

    def search_region(self) -> tuple[int, int, int, int]:
        """The frame region ``(x, y, w, h)`` that the next :meth:`update` reads: its integral
        image covers this rectangle clipped to the frame (what :class:`~wmiltrack.MultiTracker`
        needs to prepare one integral image for several targets)."""
        self._require_init()
        origin, _ = self._search_origin()
        margin = self._params.search_reach + self._track.reach + self._scale_margin()
        return self._roi(origin, margin)

    @property
    def uses_channels(self) -> bool:
        """Whether this tracker's features read other channels than luma (``Params.channels``)."""
        return self._chan_names is not None

    @_one_thread_at_a_time
    def update(self, frame: np.ndarray, *, integral: _core.IntegralImage | None = None) -> TrackResult:
        """Locate the target in the next frame and learn from it.

        ``integral`` (advanced): a luma integral image of this same frame that covers
        :meth:`search_region` (clipped to the frame), computed once for several trackers; the
        tracker reads it instead of building its own, with the same result. It is ignored when
        it does not cover the region or the tracker uses other channels.

        Returns
        -------
        TrackResult
            ``box`` (x, y, w, h), ``score`` (confidence in [0, 1]: see :func:`confidence`;
            rcwmil-plus also counts the box's contrast under the first frame's colour and
            intensity histograms, ``Params.score_colour`` / ``score_luma``) and ``ok``
            (score >= the variant's ``lost_threshold``; False suggests the target is lost or
            hidden).
        """
        self._require_init()
        img = as_frame(frame)
        result: TrackResult = _drive(self._update_steps(img, integral))
        return result

    def _check_frame(self, img: np.ndarray) -> None:
        wh = frame_size(img)
        if wh != self._frame_wh:
            raise ValueError(
                f"frame size changed from {self._frame_wh[0]}x{self._frame_wh[1]} to {wh[0]}x{wh[1]}; "
                "call init() to restart on frames of the new size"
            )

    def _update_steps(self, img: np.ndarray, integral: _core.IntegralImage | None) -> Steps:
        """:meth:`update` on a checked frame, as a generator of core requests (see ``Steps``).

        A paper preset makes one request for the whole step (:meth:`_fused_step`): the same
        random draws in the same order as the separate requests, so the same boxes, with one
        crossing into the core."""
        self._check_frame(img)
        wh = self._frame_wh
        p = self._params
        previous = self._box
        origin, coarse = self._search_origin()
        margin = p.search_reach + self._track.reach + self._scale_margin()
        own = self._ii
        roi = self._roi(origin, margin)
        shared = integral is not None and self._chan_names is None and _covers(integral, roi, wh)
        # Luma-only trackers compute their integral image in the search's call to the core;
        # several channels are computed here first.
        direct = self._chan_names is None and not shared
        if shared:
            assert integral is not None
            self._ii = integral
        elif not direct:
            self._compute_integral(img, origin, margin)
        try:
            cue = None
            if self._colour is not None:  # its table covers the search's candidates
                x, y, w, h = origin
                m = p.search_reach + 1
                table = self._colour.integral(img, (x - m, y - m, x + w + m, y + h + m))
                rel = p.colour_relative
                offset = p.confidence_offset if rel is None else -rel
                cue = (*table, p.colour_weight, offset, rel is not None)
            self._box = origin
            stages = self._stages(coarse)
            pool = self._pool
            search = (self._ii, self._bank_at(self._scale_index)[0], self._selected,
                      pool.mu1, pool.sigma1, pool.mu0, pool.sigma0, p.guard,
                      self._box, stages, wh, img if direct else None,
                      roi if direct else None, cue)
            # A paper preset's search, bags and learning in one core call (then nothing below
            # learns: such a preset always passes the gates), on its own integral image or on
            # the shared one.
            fused = self._plain and (direct or shared)
            if fused:
                raw = yield from self._fused_step(search, stages)
            else:
                raw = self._apply_search(stages, (yield _Search(search)))
            self._scale_boxes = []
            if p.scale_steps > 0 and math.isfinite(raw):
                self._cue_table = None if cue is None else cue[:3]
                raw = self._scale_search(raw)
                self._cue_table = None
            score = confidence(raw, len(self._selected), p.confidence_offset)
            report = score
            if (p.score_colour > 0 and self._colour is not None) or p.score_luma > 0:
                report = self._colour_score(score, img)
            # What the lost state, the gates, motion and recovery read (Params.lost_signal).
            signal = report if p.lost_signal == "score" else score
            tracked = signal >= p.lost_threshold
            k = max(len(self._selected), 1)
            if not fused:  # (the fused step has learnt already)
                if signal >= p.gate_threshold and self._level_ok(raw / k):
                    slow = not tracked and p.gate_learning_rate is not None
                    yield from self._learn_steps(self._track,
                                                 p.gate_learning_rate if slow else None)
                else:
                    self._bags = (_NO_CORNERS, _NO_CORNERS)
            self._score = report
            if self._colour is not None:
                self._colour.learn(img, self._box)
            self._follow(previous, tracked)
        finally:
            self._ii = own  # a shared table is only borrowed for this frame
        x, y, w, h = self._box
        return TrackResult((float(x), float(y), float(w), float(h)), self._score,
                           self._score >= p.lost_threshold)

    def track(self, frames: Any, box: Any) -> np.ndarray:
        """Run over an iterable of frames starting with ``box`` on the first; (n, 4) boxes."""
        out = []
        for i, frame in enumerate(frames):
            if i == 0:
                self.init(frame, box)
                out.append(self.box)
            else:
                out.append(self.update(frame).box)
        return np.array(out, dtype=np.float64).reshape(-1, 4)

    def samples(self) -> dict[str, Any]:
        """What the last ``init``/``update`` looked at (read-only copies, for drawing).

        Returns
        -------
        dict
            ``"positive"``, ``"negative"``: top-left corners ``(n, 2)`` of the bags learnt
            from (empty when the update was gated off); ``"search"``: one
            ``(origin_box, radius, step)`` per search stage of the last ``update`` (coarse,
            then fine; empty after ``init``); ``"scales"``: the boxes searched at the other
            scales (empty without scale search); ``"box"``: the box.
        """
        self._require_init()
        if len(self._bags) == 3:  # (xs, ys, n_pos) from the core's frame step
            xs, ys, n_pos = self._bags
            corners = np.stack((xs, ys), axis=1)
            self._bags = (corners[:n_pos], corners[n_pos:])
        pos, neg = self._bags
        return {
            "positive": pos.copy(),
            "negative": neg.copy(),
            "search": [(origin, r, s) for origin, (r, s) in zip(self._search_origins, self._search_stages)],
            "scales": list(self._scale_boxes),
            "box": self._box,
        }

    @property
    def scale(self) -> float:
        """The current box size relative to the first box (1.0 without scale search)."""
        self._require_init()
        return float(self._params.scale_factor ** self._scale_index)

    def __repr__(self) -> str:
        state = f"box={self._box}" if self._initialized else "not initialised"
        return f"Tracker({self._params.variant!r}, seed={self._seed}, {state})"

    # -- internals -------------------------------------------------------------------------
    def _require_init(self) -> None:
        if not self._initialized:
            raise NotInitializedError("call init(frame, box) before update(frame)")

    @staticmethod
    def _roi(box: IntBox, margin: int) -> IntBox:
        """The integral image's region around ``box``: ``margin`` pixels and one more."""
        x, y, w, h = box
        m = margin + 1
        return x - m, y - m, w + 2 * m, h + 2 * m

    def _compute_integral(self, img: np.ndarray, box: IntBox, margin: int) -> None:
        roi = self._roi(box, margin)
        if self._chan_names is not None:
            if img.ndim == 2 or img.shape[2] == 1:
                if available_channels(self._chan_names, img) != self._chan_names:
                    raise ValueError("this tracker was started on a colour frame and uses colour "
                                     "channels; call init() to restart on gray frames")
            self._ii.compute_channels(img, roi, self._chan_ids)
        else:
            self._ii.compute(img, roi)

    def _grid(self, index: int, box: IntBox, radius: int) -> tuple[int, int, float, int]:
        """Best offset, its raw score and the candidate count of the step-1 grid around
        ``box`` at scale ``index`` (the translation search's core call, one stage)."""
        pool = self._pool
        ((dx, dy, score, n),) = _core.search(self._ii, self._bank_at(index)[0], self._selected,
                                              pool.mu1, pool.sigma1, pool.mu0, pool.sigma0,
                                              self._params.guard, box, [(radius, 1)],
                                              self._frame_wh)
        return dx, dy, score, n

    def _project(self, index: int, corners: np.ndarray) -> np.ndarray:
        """Feature values ``(M, n)`` of the boxes at scale ``index`` with these top-left corners."""
        values: np.ndarray = _core.project(self._ii, self._bank_at(index)[0], corners[:, 0],
                                           corners[:, 1])
        return values

    def _make_core_bank(self, arrays: BankArrays) -> _core.FeatureBank:
        """The core's bank of ``arrays``, each rectangle on its feature's channel plane."""
        return _core.FeatureBank(arrays.starts, arrays.rects, arrays.weights,
                                 channels=self._rect_planes)

    def _scale_margin(self) -> int:
        """Extra integral-image margin for the largest scale searched around the box."""
        p = self._params
        if p.scale_steps == 0:
            return 0
        w, h = self._box_size(self._scale_index + max(p.scale_steps, p.scale_negatives) + p.scale_steps)
        return (max(w - self._box[2], h - self._box[3]) + 1) // 2 + 1

    def _box_size(self, index: int) -> tuple[int, int]:
        s = self._params.scale_factor ** index
        return max(1, round(self._base_wh[0] * s)), max(1, round(self._base_wh[1] * s))

    def _bank_at(self, index: int) -> tuple[_core.FeatureBank, BankArrays]:
        """The feature bank stretched to the box size of scale ``index`` (cached)."""
        cached = self._banks.get(index)
        if cached is None:
            w, h = self._box_size(index)
            arrays = scale_bank(self._bank_arrays, self._base_wh[0], self._base_wh[1], w, h,
                                self._edge_rects)
            cached = (self._make_core_bank(arrays), arrays)
            self._banks[index] = cached
        return cached

    def _scale_allowed(self, index: int) -> bool:
        p = self._params
        s = p.scale_factor ** index
        if not (p.scale_min - 1e-9 <= s <= p.scale_max + 1e-9):
            return False
        w, h = self._box_size(index)
        mw, mh = min_box_size(p)
        return mw <= w <= self._frame_wh[0] and mh <= h <= self._frame_wh[1] and box_area_ok(w, h)

    @staticmethod
    def _centred(box: IntBox, w: int, h: int, dx: float = 0.0, dy: float = 0.0) -> IntBox:
        """A ``w x h`` box with the centre of ``box`` moved by ``(dx, dy)``."""
        cx = box[0] + box[2] / 2.0 + dx
        cy = box[1] + box[3] / 2.0 + dy
        return int(math.floor(cx - w / 2.0 + 0.5)), int(math.floor(cy - h / 2.0 + 0.5)), w, h

    def _search_origin(self) -> tuple[IntBox, tuple[int, int]]:
        """Where the coarse search is centred, and its (radius, step)."""
        p = self._params
        coarse = (p.coarse_radius, p.coarse_step)
        if self._lost and p.recovery_radius > 0:
            x, y, w, h = self._box
            return self._centred(self._last_good, w, h), (p.recovery_radius, p.recovery_step)
        if p.motion == "velocity" and not self._lost:
            vx, vy = self._velocity
            x, y, w, h = self._box
            return self._centred(self._box, w, h, vx, vy), coarse
        return self._box, coarse

    def _level_ok(self, mean_k: float) -> bool:
        """Whether a frame's mean log ratio passes the relative gate (and track the level)."""
        drop = self._params.gate_drop
        if drop <= 0.0:
            return True
        if not math.isfinite(mean_k):
            return False
        if math.isfinite(self._level) and mean_k < self._level - drop:
            return False
        self._level = mean_k if not math.isfinite(self._level) else 0.9 * self._level + 0.1 * mean_k
        return True

    def _follow(self, previous: IntBox, tracked: bool) -> None:
        """Update the velocity estimate and the lost / last-confident state after a frame."""
        p = self._params
        self._lost = not tracked
        if tracked:
            self._last_good = self._box
        if p.motion != "velocity":
            return
        if not tracked:
            self._velocity = (0.0, 0.0)
            return
        px = previous[0] + previous[2] / 2.0
        py = previous[1] + previous[3] / 2.0
        mx = self._box[0] + self._box[2] / 2.0 - px
        my = self._box[1] + self._box[3] / 2.0 - py
        a = p.motion_smoothing
        vx = a * self._velocity[0] + (1.0 - a) * mx
        vy = a * self._velocity[1] + (1.0 - a) * my
        speed = math.hypot(vx, vy)
        if speed > p.motion_max:
            vx, vy = vx * p.motion_max / speed, vy * p.motion_max / speed
        self._velocity = (vx, vy)

    def _stages(self, coarse: tuple[int, int]) -> list[tuple[int, int]]:
        """The search's (radius, step) stages: the coarse grid, then the fine one if any."""
        p = self._params
        return [coarse, (p.fine_radius, p.fine_step)] if p.fine_radius > 0 else [coarse]

    def _move(self, found: tuple[int, int, float, int], best: float) -> float:
        """Move the box by one stage's ``(dx, dy, score, n)``; the best raw score so far."""
        dx, dy, score, n = found
        if n == 0:  # no candidate fitted in the frame: stay
            return best
        x, y, w, h = self._box
        self._box = (x + dx, y + dy, w, h)
        return score

    def _apply_search(self, stages: list[tuple[int, int]],
                      results: tuple[tuple[int, int, float, int], ...]) -> float:
        """Move the box by the results of a whole search made in one core call."""
        best = -math.inf
        self._search_origins = []
        self._search_stages = stages
        for found in results:
            self._search_origins.append(self._box)
            best = self._move(found, best)
        return best

    def _scale_search(self, raw: float) -> float:
        """Try the other scales around the searched box; moves it; returns the chosen raw score."""
        p = self._params
        if p.scale_model == "likelihood":
            self._scale_by_likelihood()
            return raw
        return self._scale_by_ratio(raw)

    def _colour_score(self, conf: float, img: np.ndarray) -> float:
        """``(1 - w - v) conf + w clip(0.5 + colour contrast, 0, 1) + v clip(0.5 + luma
        contrast, 0, 1)`` of the box (``w``: ``score_colour``, its contrast under the current or
        the first frame's colours, ``score_colour_model``; ``v``: ``score_luma``, the first
        frame's intensities). Without colour the colour term reads the luma contrast, or is
        left out (``v = 0``: the classifier's confidence alone)."""
        p = self._params
        w, v = p.score_colour, p.score_luma
        luma = 0.0
        if self._first_luma is not None:
            luma = min(max(0.5 + self._first_luma.contrast(img, self._box), 0.0), 1.0)
        if self._colour is None:  # no colour in this video
            return (1.0 - w - v) * conf + (w + v) * luma if v > 0 else conf
        # Before this frame's learning: the current model is the one the search used.
        contrast = (self._first_colour or self._colour).contrast(img, self._box)
        return (1.0 - w - v) * conf + w * min(max(0.5 + contrast, 0.0), 1.0) + v * luma

    def _colour_contrast(self, box: IntBox) -> float:
        """The box's colour contrast (:func:`~wmiltrack.engine.colour.colour_contrast`) read from
        the search's likelihood table (the box and its ring clipped to the table's region)."""
        assert self._cue_table is not None
        table, x0, y0 = self._cue_table
        return box_contrast(table, x0, y0, box)

    def _likelihood(self, index: int, box: IntBox) -> float:
        """Minus the mean log(1 + z^2) of all M features of ``box`` under the scale model."""
        pool = self._scale_pool
        assert pool is not None
        return _core.template_fit(self._ii, self._bank_at(index)[0], box[0], box[1], pool.mu1,
                                  pool.sigma1)

    def _scale_by_ratio(self, best: float) -> float:
        """Try the other scales with the strong classifier; returns the chosen raw score."""
        p = self._params
        k = max(len(self._selected), 1)
        mix = p.scale_mix if p.scale_model == "both" else 0.0
        best_value = best / k
        if mix:
            best_value += mix * self._likelihood(self._scale_index, self._box)
        cw = p.scale_contrast if self._cue_table is not None else 0.0
        if cw:
            best_value += cw * self._colour_contrast(self._box)
        best_index, best_box = self._scale_index, self._box
        for j in range(-p.scale_steps, p.scale_steps + 1):
            index = self._scale_index + j
            if j == 0 or not self._scale_allowed(index):
                continue
            w, h = self._box_size(index)
            candidate = self._centred(self._box, w, h)
            self._scale_boxes.append(candidate)
            dx, dy, score, n = self._grid(index, candidate, p.scale_radius)
            if n == 0:
                continue
            moved = (candidate[0] + dx, candidate[1] + dy, w, h)
            value = score / k - p.scale_penalty * abs(j)
            if mix:
                value += mix * self._likelihood(index, moved)
            if cw:
                value += cw * self._colour_contrast(moved)
            if value > best_value:
                best_value = value
                best = score
                best_index = index
                best_box = moved
        self._scale_index, self._box = best_index, best_box
        return best

    def _scale_by_likelihood(self) -> None:
        """Pick the scale whose box best fits the target model over all M features."""
        p = self._params
        fw, fh = self._frame_wh
        best_value = -math.inf
        best_index, best_box = self._scale_index, self._box
        for j in range(-p.scale_steps, p.scale_steps + 1):
            index = self._scale_index + j
            if j != 0 and not self._scale_allowed(index):
                continue
            w, h = self._box_size(index)
            candidate = self._box if j == 0 else self._centred(self._box, w, h)
            x, y = candidate[0], candidate[1]
            if x < 0 or y < 0 or x + w > fw or y + h > fh:
                continue
            if j != 0:
                self._scale_boxes.append(candidate)
            value = self._likelihood(index, candidate) - p.scale_penalty * abs(j)
            if value > best_value:
                best_value, best_index, best_box = value, index, candidate
        self._scale_index, self._box = best_index, best_box

    def _wrong_scale_values(self) -> list[np.ndarray]:
        """Feature values of the target's box shrunk and grown by ``scale_negatives`` steps."""
        p = self._params
        out = []
        for j in (-p.scale_negatives, p.scale_negatives):
            index = self._scale_index + j
            if not self._scale_allowed(index):
                continue
            w, h = self._box_size(index)
            x, y, _, _ = self._centred(self._box, w, h)
            if x < 0 or y < 0 or x + w > self._frame_wh[0] or y + h > self._frame_wh[1]:
                continue
            out.append(self._project(index, np.array([[x, y]], dtype=np.int32)))
        return out

    def _learn(self, sampler: BagSampler, learning_rate: float | None = None) -> None:
        """Sample the bags around the current box, update the Gaussians, reselect features."""
        _drive(self._learn_steps(sampler, learning_rate))

    def _learn_steps(self, sampler: BagSampler, learning_rate: float | None) -> Steps:
        """:meth:`_learn` as a generator of core requests (see ``Steps``): after sampling, one
        request (``_core.learn``: projection, Gaussian updates, log ratios and WMIL selection
        in the order of separate calls, so the same bits, crossing into the core once)."""
        p = self._params
        fw, fh = self._frame_wh
        pos, dist = sampler.positives(self._box, fw, fh)
        neg = sampler.negatives(self._box, fw, fh, self._rng)
        self._bags = (pos, neg)
        # rcwmil-plus: the box at wrong scales as more negatives, and the scale model.
        wrong = self._wrong_scale_values() if p.scale_negatives > 0 else []
        extra = np.concatenate(wrong, axis=1) if wrong else None
        select = self._select_kind(pos.shape[0])
        w = sampler.weights(dist, p.instance_weights) if select == "wmil" else None
        request = self._learn_request(np.concatenate((pos, neg)), pos.shape[0], select, w,
                                      learning_rate, extra)
        self._take_learnt((yield _Learn(request)), pos.shape[0], neg.shape[0] + len(wrong))

    def _select_kind(self, n_pos: int) -> str:
        """The learning step's ``select``: WMIL in the core, the log ratios for a MILBoost
        selection here, or none (no selection, or no positive this frame)."""
        p = self._params
        if p.selection == "none" or n_pos == 0:
            return "none"
        return "wmil" if p.selection == "wmil" else "ratios"

    def _learn_request(self, corners: np.ndarray, n_pos: int, select: str, w: np.ndarray | None,
                       learning_rate: float | None, extra: np.ndarray | None) -> tuple[Any, ...]:
        """``_core.learn``'s arguments for the bags with these top-left ``corners`` (the
        ``n_pos`` positives, weighted ``w`` for WMIL, then the negatives)."""
        p = self._params
        pool = self._pool
        scale_pool = self._scale_pool
        second = None if scale_pool is None else (scale_pool.mu1, scale_pool.sigma1,
                                                  p.scale_learning_rate, scale_pool.first(1))
        mu1_in, sigma1_in = pool.mu1, pool.sigma1
        if self._anchor is not None:  # pull the target model towards the first frame's
            a = self._anchor_weight
            mu1_in = (1.0 - a) * pool.mu1 + a * self._anchor[0]
            sigma1_in = (1.0 - a) * pool.sigma1 + a * self._anchor[1]
        return (self._ii, self._bank_at(self._scale_index)[0], corners[:, 0], corners[:, 1], n_pos,
                mu1_in, sigma1_in, pool.mu0, pool.sigma0,
                p.learning_rate if learning_rate is None else learning_rate,
                pool.first(1), pool.first(0), p.first_update == "direct", p.classifier == "mil",
                p.sigma_floor, p.guard, select, w, p.num_selected, p.gradient == "code", extra,
                second)

    def _take_learnt(self, learnt: tuple[Any, ...], n_pos: int, n_neg: int) -> None:
        """Keep the model and the selection that a learning request returned."""
        p = self._params
        pool = self._pool
        mu1, sigma1, mu0, sigma0, selected, h, mu2, sigma2 = learnt
        pool.assign(mu1, sigma1, mu0, sigma0, n_pos > 0, n_neg > 0)
        if self._anchor_weight > 0 and n_pos > 0 and self._anchor is None:
            self._anchor = (mu1.copy(), sigma1.copy())
        scale_pool = self._scale_pool
        if scale_pool is not None:
            scale_pool.assign(mu2, sigma2, scale_pool.mu0, scale_pool.sigma0, n_pos > 0, False)
        if selected is not None:
            self._selected = selected
        elif h is not None:
            self._selected = milboost_select(h[:, :n_pos], h[:, n_pos:], p.num_selected,
                                             guard=p.guard)

    def _fused_step(self, search: tuple[Any, ...], stages: list[tuple[int, int]]) -> Steps:
        """The search, the bags and the learning of a paper preset (:attr:`_plain`) as one core
        request: the core samples the bags where the search landed (drawing the negatives from
        this tracker's generator exactly as :class:`BagSampler` would) and learns. The same
        draws and state changes as the separate requests; returns the search's raw score."""
        p = self._params
        select = self._select_kind(1)  # the core drops WMIL if no positive fits in the frame
        weights = p.instance_weights if select == "wmil" else "none"
        bags = (self._rng, *self._track.core_spec(weights))
        request = self._learn_request(_NO_CORNERS, 0, select, None, None, None)
        results, learnt, (xs, ys, n_pos) = yield _Step((search, request, bags))
        self._bags = (xs, ys, n_pos)  # split by samples() when asked
        self._take_learnt(learnt, n_pos, xs.shape[0] - n_pos)
        return self._apply_search(stages, results)


def update_many(trackers: list[Tracker], frame: np.ndarray, *,
                integral: _core.IntegralImage | None = None,
                threads: int = 1) -> list[TrackResult | Exception]:
    """:meth:`Tracker.update` of several trackers on one frame, their core work in parallel.

    Every tracker runs its own frame step, unchanged (the same boxes as ``update``), but the
    requests they make to the core at the same point of the step (a paper preset's whole step;
    for the others the integral image and search, then the learning step) go to the core
    together and run on up to ``threads`` threads with the GIL released, instead of once per
    tracker and call. ``integral``: as for :meth:`Tracker.update`, a luma table of this frame
    the trackers may borrow. Returns, in order, each tracker's :class:`TrackResult` or the
    ``ValueError``/``TypeError`` its update raised (the others are not affected); a tracker in
    use by another thread gets a ``RuntimeError``.
    """
    img = as_frame(frame)
    out: list[TrackResult | Exception | None] = [None] * len(trackers)
    locked: list[Tracker] = []
    active: dict[int, tuple[Steps, tuple[Any, ...]]] = {}

    def advance(i: int, steps: Steps, value: Any, first: bool = False) -> None:
        try:
            request = next(steps) if first else steps.send(value)
            active[i] = (steps, request)
        except StopIteration as stop:
            out[i] = stop.value
            active.pop(i, None)
        except (ValueError, TypeError) as exc:
            out[i] = exc
            active.pop(i, None)

    try:
        for i, t in enumerate(trackers):
            if not t._busy.acquire(blocking=False):
                out[i] = RuntimeError("this Tracker is in use by another thread")
                continue
            locked.append(t)
            try:
                t._require_init()
            except NotInitializedError as exc:
                out[i] = exc
                continue
            advance(i, t._update_steps(img, integral), None, first=True)
        while active:
            order = list(active)
            results: dict[int, Any] = {}
            for kind, run_many in ((_Step, _core.frame_step_many), (_Search, _core.search_many),
                                   (_Learn, _core.learn_many)):
                batch = [i for i in order if isinstance(active[i][1], kind)]
                if batch:
                    results.update(zip(batch, run_many([tuple(active[i][1]) for i in batch],
                                                       threads)))
            for i in order:
                advance(i, active[i][0], results[i])
    finally:
        for t in locked:
            t._busy.release()
    return [r if r is not None else RuntimeError("no result") for r in out]
