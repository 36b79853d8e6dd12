"""Feature banks: which rectangles, with which weights, make up each Haar-like feature.

A bank is drawn once per ``init`` from the tracker's seeded generator, relative to the
box's top-left corner, and handed to the C++ core as three flat arrays.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from .. import _core
from .settings import check_choices, check_ints, is_int, need

__all__ = ["CHANNELS", "CHANNEL_IDS", "COLOUR_CHANNELS", "EDGE_CHANNELS", "BankArrays", "FeatureSettings",
           "available_channels", "box_area_ok", "check_box_size", "make_bank", "min_box_size",
           "rect_planes", "scale_bank"]

#: The image channels a feature may read (``FeatureSettings.channels``).
CHANNELS = ("luma", "grad", "opp_rg", "opp_yb")


@dataclass(frozen=True)
class FeatureSettings:
    """The Haar-like feature bank and its classifier's size (the appearance model).

    Attributes
    ----------
    feature_kind : {"subregion", "random"}
        ``subregion``: rectangles drawn inside a grid of sub-regions of the box with size
        limits (rcwmil, OSIL). ``random``: rectangles anywhere in the box (CT, FCT, MIL, WMIL).
    num_features : int
        M, the size of the feature pool.
    num_selected : int
        K, how many features the strong classifier uses (== M when ``selection="none"``).
    rects_min, rects_max : int
        Rectangles per feature, drawn uniformly in ``rects_min..rects_max`` (inclusive).
    num_subregions : int
        Sub-regions for ``subregion`` features: 4 = 2x2 grid (``subregion_mode="grid"``).
    subregion_mode : {"grid", "random"}
        ``grid``: quadrant ``i mod 4`` for feature i; ``random``: a W/2 x H/2 window at a
        random place per feature (spec section 8 #3).
    positive_prob : float
        Probability of a +1 entry of the measurement matrix (0.78; -1 otherwise).
    rect_min_size : int
        Smallest rectangle side in pixels (w_min = h_min = 2).
    beta_min, beta_max : float
        Rectangle side limits as fractions of the sub-region side (0.2, 0.8).
    rect_bounds : tuple of 4 int
        For ``random`` features: ``(x_lo, x_hi_off, w_lo, w_end_off)``: a rectangle's x is
        drawn in ``x_lo .. W - x_hi_off`` and its width in ``w_lo .. W - x - w_end_off``
        (same for y and h), matching each reference implementation's ranges.
    weight_mode : {"sign", "sign_sqrt", "uniform"}
        Rectangle weights of ``random`` features: fair +-1, +-1/sqrt(#rects) (CT), U[-1, 1].
    area_normalize : bool
        Divide each rectangle's sum by its area (FCT eq. 8; rcwmil) or use raw sums.
    min_box_size : int
        Smallest box side accepted (after clipping to the frame).
    channels : tuple of str
        Image channels the features are drawn on, each feature on one: any of ``"luma"``,
        ``"grad"`` (gradient magnitude), ``"opp_rg"``, ``"opp_yb"`` (colour opponents; they
        drop out for gray frames). Empty (the paper): luma only, one integral image.
    """

    feature_kind: Literal["subregion", "random"] = "subregion"
    num_features: int = 100
    num_selected: int = 20
    rects_min: int = 2
    rects_max: int = 4
    num_subregions: int = 4
    subregion_mode: Literal["grid", "random"] = "grid"
    positive_prob: float = 0.78
    rect_min_size: int = 2
    beta_min: float = 0.2
    beta_max: float = 0.8
    rect_bounds: tuple[int, int, int, int] = (1, 6, 2, 3)
    weight_mode: Literal["sign", "sign_sqrt", "uniform"] = "sign"
    area_normalize: bool = True
    min_box_size: int = 4
    channels: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        FeatureSettings.check(self)

    def check(self) -> None:
        """``ValueError`` naming the first setting out of range."""
        check_choices(self, {"feature_kind": ("subregion", "random"),
                              "subregion_mode": ("grid", "random"),
                              "weight_mode": ("sign", "sign_sqrt", "uniform")})
        check_ints(self, "num_features", "num_selected", "rects_min", "rects_max",
                   "num_subregions", "rect_min_size", "min_box_size")
        need(self.num_features >= 1, f"num_features must be >= 1, got {self.num_features}")
        need(1 <= self.num_selected <= self.num_features,
             f"num_selected (K) must be in 1..num_features ({self.num_features}), got {self.num_selected}")
        need(1 <= self.rects_min <= self.rects_max,
             f"need 1 <= rects_min <= rects_max, got {self.rects_min}, {self.rects_max}")
        need(self.num_subregions in (1, 4, 9, 16) if self.subregion_mode == "grid"
             else self.num_subregions >= 1,
             f"num_subregions for a grid must be a square (1, 4, 9, 16), got {self.num_subregions}")
        need(0.0 <= self.positive_prob <= 1.0,
             f"positive_prob must be in [0, 1], got {self.positive_prob}")
        need(self.rect_min_size >= 1, f"rect_min_size must be >= 1, got {self.rect_min_size}")
        need(0.0 < self.beta_min <= self.beta_max <= 1.0,
             f"need 0 < beta_min <= beta_max <= 1, got {self.beta_min}, {self.beta_max}")
        need(len(self.rect_bounds) == 4 and all(is_int(v) and v >= 0 for v in self.rect_bounds),
             f"rect_bounds must be four ints >= 0, got {self.rect_bounds}")
        need(self.rect_bounds[2] >= 1, "rect_bounds[2] (smallest rectangle side) must be >= 1")
        # A rectangle starts at most rect_bounds[1] pixels before the box's far edge and is at
        # least rect_bounds[2] wide: it only stays inside the box if the latter fits.
        need(self.rect_bounds[2] <= self.rect_bounds[1],
             f"rect_bounds[2] (smallest rectangle side, {self.rect_bounds[2]}) must be <= "
             f"rect_bounds[1] (room left after a rectangle's start, {self.rect_bounds[1]})")
        need(self.min_box_size >= 2, f"min_box_size must be >= 2, got {self.min_box_size}")
        need(isinstance(self.channels, tuple) and all(c in CHANNELS for c in self.channels)
             and len(set(self.channels)) == len(self.channels),
             f"channels must be a tuple of distinct names from {', '.join(CHANNELS)}; "
             f"got {self.channels!r}")
        need(self.channels == () or any(c not in ("opp_rg", "opp_yb") for c in self.channels),
             "channels needs a gray channel: luma or grad (the colour channels drop out for "
             "gray frames)")


#: Channel names (``Params.channels``) and their ids in ``_core.IntegralImage.compute_channels``.
CHANNEL_IDS = {"luma": _core.CH_LUMA, "grad": _core.CH_GRAD, "opp_rg": _core.CH_OPP_RG,
               "opp_yb": _core.CH_OPP_YB}
#: Gradient channels: their values sit on edges, so a rectangle's sum grows with the edges'
#: length (see :func:`scale_bank`).
EDGE_CHANNELS = frozenset({"grad"})
#: Channels that need a colour (3- or 4-channel) frame.
COLOUR_CHANNELS = frozenset({"opp_rg", "opp_yb"})


def available_channels(wanted: tuple[str, ...], frame: np.ndarray) -> tuple[str, ...]:
    """The channels of ``wanted`` that ``frame`` can give (colour ones drop out for gray frames)."""
    colour = frame.ndim == 3 and frame.shape[2] in (3, 4)
    return tuple(c for c in wanted if colour or c not in COLOUR_CHANNELS)


def rect_planes(arrays: BankArrays, feature_plane: np.ndarray) -> np.ndarray:
    """The integral-image plane of each rectangle: every rectangle on its feature's plane."""
    counts = np.diff(arrays.starts)
    return np.repeat(np.asarray(feature_plane, dtype=np.int32), counts)


@dataclass(frozen=True)
class BankArrays:
    """Features in compressed form: feature f owns ``rects[starts[f]:starts[f + 1]]``.

    Attributes
    ----------
    starts : (M + 1,) int32
    rects : (R, 4) int32 of ``x, y, w, h`` relative to the box's top-left corner
    weights : (R,) float64
    subregion : (M,) int32, the sub-region of each feature (-1 for ``random`` features)
    """

    starts: np.ndarray
    rects: np.ndarray
    weights: np.ndarray
    subregion: np.ndarray

    @property
    def size(self) -> int:
        """Number of features M."""
        return int(self.starts.size - 1)


def min_box_size(params: FeatureSettings) -> tuple[int, int]:
    """Smallest ``(w, h)`` a box may have for this variant's features."""
    if params.feature_kind == "subregion":
        side = int(math.isqrt(params.num_subregions)) if params.subregion_mode == "grid" else 1
        need = max(2 * side, params.min_box_size)
    else:
        x_lo, x_hi_off, w_lo, w_end_off = params.rect_bounds
        # the widest x range must be non-empty and leave room for the narrowest rectangle
        need = max(x_lo + x_hi_off, x_lo + w_lo + w_end_off, params.min_box_size)
    return need, need


def box_area_ok(w: int, h: int) -> bool:
    """Whether a ``w x h`` box is within the core's largest exact rectangle sum
    (``_core.MAX_RECT_AREA`` pixels, about 4100 x 4100: the integral image sums in 32 bits)."""
    return w * h <= _core.MAX_RECT_AREA


def check_box_size(params: FeatureSettings, w: int, h: int, variant: str | None = None) -> None:
    """Raise ``ValueError`` when a ``w x h`` box is too small for the variant's features, or
    too large for the core's 32-bit sums. ``variant``: the variant's name for the message."""
    who = f"variant {variant!r}" if variant is not None else "the box"
    mw, mh = min_box_size(params)
    if w < mw or h < mh:
        raise ValueError(
            f"box is {w}x{h} pixels (after clipping to the frame); {who} "
            f"needs at least {mw}x{mh}"
        )
    if not box_area_ok(w, h):
        raise ValueError(
            f"box is {w}x{h} = {w * h} pixels (after clipping to the frame); at most "
            f"{_core.MAX_RECT_AREA} (the integral image sums in 32 bits): track on a downscaled video"
        )


def _subregions(params: FeatureSettings, w: int, h: int, rng: np.random.Generator
                ) -> list[tuple[int, int, int, int]]:
    """Origin and size of the sub-region of each feature."""
    m = params.num_features
    if params.subregion_mode == "grid":
        side = math.isqrt(params.num_subregions)
        xs = [w * i // side for i in range(side + 1)]
        ys = [h * i // side for i in range(side + 1)]
        cells = [(xs[i], ys[j], xs[i + 1] - xs[i], ys[j + 1] - ys[j])
                 for j in range(side) for i in range(side)]
        return [cells[f % len(cells)] for f in range(m)]
    sw, sh = max(w // 2, 1), max(h // 2, 1)
    return [(int(rng.integers(0, w - sw + 1)), int(rng.integers(0, h - sh + 1)), sw, sh) for _ in range(m)]


def _side_range(params: FeatureSettings, size: int) -> tuple[int, int]:
    """Allowed rectangle side within a sub-region side of ``size`` (spec section 7)."""
    lo = min(size, max(params.rect_min_size, math.ceil(params.beta_min * size)))
    hi = max(lo, min(size, math.floor(params.beta_max * size)))
    return lo, hi


def make_bank(params: FeatureSettings, w: int, h: int, rng: np.random.Generator) -> BankArrays:
    """Draw the variant's feature bank for a ``w x h`` box."""
    check_box_size(params, w, h)
    m = params.num_features
    counts = rng.integers(params.rects_min, params.rects_max + 1, size=m)
    starts = np.zeros(m + 1, dtype=np.int32)
    np.cumsum(counts, out=starts[1:])
    n_rects = int(starts[-1])
    rects = np.empty((n_rects, 4), dtype=np.int32)
    weights = np.empty(n_rects, dtype=np.float64)
    subregion = np.full(m, -1, dtype=np.int32)

    if params.feature_kind == "subregion":
        regions = _subregions(params, w, h, rng)
        for f in range(m):
            ox, oy, sw, sh = regions[f]
            subregion[f] = f % params.num_subregions if params.subregion_mode == "grid" else -1
            wlo, whi = _side_range(params, sw)
            hlo, hhi = _side_range(params, sh)
            for r in range(starts[f], starts[f + 1]):
                rw = int(rng.integers(wlo, whi + 1))
                rh = int(rng.integers(hlo, hhi + 1))
                rx = int(rng.integers(0, sw - rw + 1))
                ry = int(rng.integers(0, sh - rh + 1))
                sign = 1.0 if rng.random() < params.positive_prob else -1.0
                rects[r] = (ox + rx, oy + ry, rw, rh)
                weights[r] = sign / (rw * rh) if params.area_normalize else sign
    else:
        x_lo, x_hi_off, w_lo, w_end_off = params.rect_bounds
        for f in range(m):
            n = int(counts[f])
            for r in range(starts[f], starts[f + 1]):
                rx = int(rng.integers(x_lo, w - x_hi_off + 1))
                ry = int(rng.integers(x_lo, h - x_hi_off + 1))
                rw = int(rng.integers(w_lo, max(w_lo, w - rx - w_end_off) + 1))
                rh = int(rng.integers(w_lo, max(w_lo, h - ry - w_end_off) + 1))
                if params.weight_mode == "uniform":
                    weight = float(rng.uniform(-1.0, 1.0))
                else:
                    weight = 1.0 if rng.random() < 0.5 else -1.0
                    if params.weight_mode == "sign_sqrt":
                        weight /= math.sqrt(n)
                if params.area_normalize:
                    weight /= rw * rh
                rects[r] = (rx, ry, rw, rh)
                weights[r] = weight
    # Every rectangle must stay inside the box.
    assert np.all(rects[:, 0] + rects[:, 2] <= w) and np.all(rects[:, 1] + rects[:, 3] <= h)
    return BankArrays(starts=starts, rects=rects, weights=weights, subregion=subregion)


def scale_bank(base: BankArrays, base_w: int, base_h: int, w: int, h: int,
               edge: np.ndarray | None = None) -> BankArrays:
    """The bank drawn for a ``base_w x base_h`` box, stretched to a ``w x h`` box.

    Each rectangle's edges are scaled and rounded (sides at least 1 pixel, kept inside the
    box) and its weight is multiplied by ``old area / new area``: an area-normalised feature
    stays a signed sum of mean intensities, so the learnt Gaussians remain valid at every
    scale (and raw-sum features keep their expected value).

    ``edge`` (one bool per rectangle) marks rectangles on the gradient channel (``grad``).
    Their sums count edge pixels: when the target appears ``s`` times larger, its edges are
    ``s`` times longer but no stronger (the gradient summed across an edge is its contrast),
    so a rectangle's sum grows as ``s``, not ``s^2``. Their weights are multiplied by
    ``sqrt(old area / new area)`` instead, which keeps the feature's expected value at every
    scale (with the area ratio, the mean gradient of a smaller box would be higher and the
    scale search would favour shrinking).
    """
    if (w, h) == (base_w, base_h):
        return base
    sx, sy = w / base_w, h / base_h
    r = base.rects.astype(np.float64)
    x0 = np.rint(r[:, 0] * sx)
    y0 = np.rint(r[:, 1] * sy)
    rw = np.maximum(np.rint((r[:, 0] + r[:, 2]) * sx) - x0, 1.0)
    rh = np.maximum(np.rint((r[:, 1] + r[:, 3]) * sy) - y0, 1.0)
    rw = np.minimum(rw, float(w))
    rh = np.minimum(rh, float(h))
    x0 = np.clip(x0, 0.0, w - rw)
    y0 = np.clip(y0, 0.0, h - rh)
    rects = np.stack([x0, y0, rw, rh], axis=1).astype(np.int32)
    ratio = (r[:, 2] * r[:, 3]) / (rw * rh)
    if edge is not None:
        ratio = np.where(edge, np.sqrt(ratio), ratio)
    weights = base.weights * ratio
    return BankArrays(starts=base.starts, rects=rects, weights=weights, subregion=base.subregion)
