"""The tracker: one engine, six variants (rcwmil, ct, fct, mil, wmil, osil).

One frame walks one way: frame -> integral image of the target's neighbourhood (C++) ->
coarse and fine candidate scoring (C++) -> new box -> positive and negative bags (Python)
-> feature values (C++) -> Gaussian update (numpy) -> feature selection (Cython).
"""

from __future__ import annotations

import functools
import math
import threading
from typing import Any, Callable, TypeVar

import numpy as np

from .. import _core
from .classifier import GaussianPool
from .features import BankArrays, check_box_size, make_bank
from .frames import IntBox, as_frame, clip_box, frame_size
from .params import Params
from .result import TrackResult
from .sampling import BagSampler, instance_weights
from .selection import milboost_select, wmil_select


class NotInitializedError(ValueError):
    """``update`` was called before ``init``."""


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


#: Offset of :func:`confidence`: the mean weak-classifier log ratio at which a frame is as
#: likely tracked (IoU > 0) as lost. A class-balanced logistic fit of "IoU > 0" on the mean
#: log ratio over 17 OTB sequences and 6 generated full-occlusion/vanishing sequences gave
#: offsets 1.25-1.63 and gains 0.8-1.1 for five variants (``scripts/score_study.py``).
CONFIDENCE_OFFSET = 1.4


def confidence(raw: float, k: int) -> float:
    """Confidence in [0, 1] of a frame from its best candidate's summed log ratio ``raw``.

    ``logistic(raw / k - CONFIDENCE_OFFSET)``: 0.5 at the point where, on the benchmark
    sequences, tracked and lost frames were equally likely; 0 when no candidate was scored.
    """
    if not math.isfinite(raw):
        return 0.0
    return _sigmoid(raw / max(k, 1) - CONFIDENCE_OFFSET)


class Tracker:
    """A single-object tracker.

    Parameters
    ----------
    variant : str
        ``"rcwmil"`` (default, the paper's tracker), ``"ct"``, ``"fct"``, ``"mil"``,
        ``"wmil"`` or ``"osil"``; see :func:`wmiltrack.variants`.
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
        self._bank = _core.FeatureBank(self._bank_arrays.starts, self._bank_arrays.rects,
                                       self._bank_arrays.weights)
        self._pool = GaussianPool(p)
        self._selected = np.arange(p.num_selected, dtype=np.int32)
        self._frame_wh = (fw, fh)
        self._box = b
        self._compute_integral(img, b, self._first.reach)
        self._learn(self._first)
        self._search_origins: list[IntBox] = []
        self._score = 1.0
        self._initialized = True

    reinit = init

    @_one_thread_at_a_time
    def update(self, frame: np.ndarray) -> TrackResult:
        """Locate the target in the next frame and learn from it.

        Returns
        -------
        TrackResult
            ``box`` (x, y, w, h), ``score`` (confidence in [0, 1]: see :func:`confidence`)
            and ``ok`` (score >= the variant's ``lost_threshold``; False suggests the
            target is lost or hidden).
        """
        self._require_init()
        img = as_frame(frame)
        wh = frame_size(img)
        if wh != self._frame_wh:
            raise ValueError(
                f"frame size changed from {self._frame_wh[0]}x{self._frame_wh[1]} to {wh[0]}x{wh[1]}; "
                "call init() to restart on frames of the new size"
            )
        p = self._params
        self._compute_integral(img, self._box, p.search_reach + self._track.reach)
        raw = self._detect()
        self._learn(self._track)
        self._score = confidence(raw, len(self._selected))
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
            from; ``"search"``: one ``(origin_box, radius, step)`` per search stage of the
            last ``update`` (coarse, then fine; empty after ``init``); ``"box"``: the box.
        """
        self._require_init()
        pos, neg = self._bags
        return {
            "positive": pos.copy(),
            "negative": neg.copy(),
            "search": [
                (origin, r, s)
                for origin, (r, s) in zip(
                    self._search_origins,
                    [(self._params.coarse_radius, self._params.coarse_step),
                     (self._params.fine_radius, self._params.fine_step)],
                )
            ],
            "box": self._box,
        }

    def __repr__(self) -> str:
        state = f"box={self._box}" if self._initialized else "not initialised"
        return f"Tracker({self._params.variant!r}, seed={self._seed}, {state})"

    # -- internals -------------------------------------------------------------------------
    def _require_init(self) -> None:
        if not self._initialized:
            raise NotInitializedError("call init(frame, box) before update(frame)")

    def _compute_integral(self, img: np.ndarray, box: IntBox, margin: int) -> None:
        x, y, w, h = box
        m = margin + 1
        self._ii.compute(img, (x - m, y - m, w + 2 * m, h + 2 * m))

    def _detect(self) -> float:
        """Coarse then fine search; moves ``self._box``; returns the best raw score."""
        p = self._params
        sel = self._selected
        pool = self._pool
        weak = (pool.mu1[sel], pool.sigma1[sel], pool.mu0[sel], pool.sigma0[sel])
        best = -math.inf
        stages = [(p.coarse_radius, p.coarse_step)]
        if p.fine_radius > 0:
            stages.append((p.fine_radius, p.fine_step))
        self._search_origins = []
        for radius, step in stages:
            self._search_origins.append(self._box)
            dx, dy, score, n = _core.score_grid(self._ii, self._bank, sel, *weak, p.guard, self._box,
                                                radius, step, self._frame_wh)
            if n > 0:
                x, y, w, h = self._box
                self._box = (x + dx, y + dy, w, h)
                best = score
        return best

    def _learn(self, sampler: BagSampler) -> None:
        """Sample the bags around the current box, update the Gaussians, reselect features."""
        p = self._params
        fw, fh = self._frame_wh
        pos, dist = sampler.positives(self._box, fw, fh)
        neg = sampler.negatives(self._box, fw, fh, self._rng)
        self._bags = (pos, neg)
        v_pos = _core.project(self._ii, self._bank, pos[:, 0], pos[:, 1])
        v_neg = _core.project(self._ii, self._bank, neg[:, 0], neg[:, 1])
        pool = self._pool
        pool.update(v_pos, v_neg)
        if p.selection == "none" or pos.shape[0] == 0:
            return
        h_pos = _core.log_ratio(v_pos, pool.mu1, pool.sigma1, pool.mu0, pool.sigma0, p.guard)
        h_neg = _core.log_ratio(v_neg, pool.mu1, pool.sigma1, pool.mu0, pool.sigma0, p.guard)
        if p.selection == "wmil":
            w = instance_weights(dist, p.instance_weights)
            self._selected = wmil_select(h_pos, h_neg, w, p.num_selected,
                                         code_gradient=p.gradient == "code")
        else:
            self._selected = milboost_select(h_pos, h_neg, p.num_selected, guard=p.guard)
