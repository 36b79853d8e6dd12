"""Bag sampling: positive offsets in a disc, negative offsets in an annulus (spec section 0).

Offsets are integer ``(dx, dy)`` displacements of the box's top-left corner; sets are
enumerated in row-major order (dy outer, dx inner) so that results are reproducible.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from .. import _core
from .settings import check_choices, check_ints, check_numbers, is_int, is_number, need

__all__ = ["MAX_NEG_RADIUS", "MAX_POS_RADIUS", "BagSampler", "BagSettings", "annulus_offsets",
           "core_draws_match_numpy", "disc_offsets", "instance_weights"]

MAX_POS_RADIUS = 100
"""Largest positive-bag radius (``pos_radius``, ``init_pos_radius``): ~31 000 positives."""
MAX_NEG_RADIUS = 500
"""Largest outer negative radius (``neg_outer``, ``init_neg_outer``)."""


@dataclass(frozen=True)
class BagSettings:
    """Where the positive and negative bags are sampled around the box (spec section 0).

    Attributes
    ----------
    pos_radius : float
        alpha: positives are every offset with d < alpha (45 for 4).
    neg_inner, neg_outer : float
        zeta, beta: negatives come from the annulus zeta <= d < beta.
    neg_count : int
        Number of negatives (exact draw without replacement, or the Bernoulli maximum).
    neg_sampling : {"exact", "bernoulli"}
        ``exact``: exactly ``neg_count`` distinct offsets; ``bernoulli``: the references'
        thinning with keep probability ``neg_count / (2 floor(beta) + 1)^2``, truncated.
    init_pos_radius, init_neg_inner, init_neg_outer, init_neg_count : float or None
        The first frame's bags when they differ from tracking (MIL, WMIL); ``None`` = same.
    """

    pos_radius: float = 4.0
    neg_inner: float = 8.0
    neg_outer: float = 22.0
    neg_count: int = 50
    neg_sampling: Literal["exact", "bernoulli"] = "exact"
    init_pos_radius: float | None = None
    init_neg_inner: float | None = None
    init_neg_outer: float | None = None
    init_neg_count: int | None = None

    def __post_init__(self) -> None:
        BagSettings.check(self)

    def check(self) -> None:
        """``ValueError`` naming the first setting out of range."""
        check_choices(self, {"neg_sampling": ("exact", "bernoulli")})
        check_ints(self, "neg_count")
        check_numbers(self, "pos_radius", "neg_inner", "neg_outer")
        need(self.pos_radius > 0, f"pos_radius must be > 0, got {self.pos_radius}")
        need(0 <= self.neg_inner < self.neg_outer,
             f"need 0 <= neg_inner < neg_outer, got {self.neg_inner}, {self.neg_outer}")
        need(self.neg_count >= 0, f"neg_count must be >= 0, got {self.neg_count}")
        for name in ("init_pos_radius", "init_neg_inner", "init_neg_outer"):
            v = getattr(self, name)
            need(v is None or is_number(v), f"{name} must be None or a finite number, got {v!r}")
        if self.init_pos_radius is not None:
            need(self.init_pos_radius > 0, "init_pos_radius must be > 0")
        # Upper limits keep the enumerated offsets (and the memory they take) bounded.
        for name in ("pos_radius", "init_pos_radius"):
            v = getattr(self, name)
            need(v is None or v <= MAX_POS_RADIUS, f"{name} must be <= {MAX_POS_RADIUS}, got {v}")
        for name in ("neg_outer", "init_neg_outer"):
            v = getattr(self, name)
            need(v is None or v <= MAX_NEG_RADIUS, f"{name} must be <= {MAX_NEG_RADIUS}, got {v}")
        inner = self.neg_inner if self.init_neg_inner is None else self.init_neg_inner
        outer = self.neg_outer if self.init_neg_outer is None else self.init_neg_outer
        need(0 <= inner < outer, f"need 0 <= init_neg_inner < init_neg_outer, got {inner}, {outer}")
        if self.init_neg_count is not None:
            need(is_int(self.init_neg_count) and self.init_neg_count >= 0,
                 "init_neg_count must be an int >= 0")


@functools.cache
def core_draws_match_numpy() -> bool:
    """Whether the core's copies of numpy's draws (``_core.frame_step`` samples the bags in
    C++) give the installed numpy's numbers and leave its generator in the same state. numpy
    does not promise that ``Generator.choice`` keeps its algorithm across versions; where it
    differs, trackers sample in Python (two core calls a frame, the same boxes)."""
    for seed in (0, 1, 2):
        a, b = np.random.default_rng(seed), np.random.default_rng(seed)
        a.integers(0, 7, size=seed)
        b.integers(0, 7, size=seed)
        picks = sorted(a.choice(1320, size=50, replace=False).tolist())
        if _core.numpy_choice_sorted(b, 1320, 50) != picks:
            return False
        kept = np.flatnonzero(a.random(2616) < 0.0133)[:50].tolist()
        if _core.numpy_bernoulli_first(b, 2616, 0.0133, 50) != kept:
            return False
        if a.bit_generator.state != b.bit_generator.state:
            return False
    return True


def disc_offsets(radius: float) -> np.ndarray:
    """Every integer offset with ``dx^2 + dy^2 < radius^2`` as an (n, 2) int32 array."""
    return annulus_offsets(0.0, radius)


def annulus_offsets(inner: float, outer: float) -> np.ndarray:
    """Every integer offset with ``inner^2 <= dx^2 + dy^2 < outer^2`` (inner bound inclusive)."""
    n = math.ceil(outer)
    d = np.arange(-n, n + 1)
    dy, dx = np.meshgrid(d, d, indexing="ij")
    d2 = dx * dx + dy * dy
    keep = (d2 >= inner * inner) & (d2 < outer * outer)
    return np.stack([dx[keep], dy[keep]], axis=1).astype(np.int32)


class BagSampler:
    """Positive and negative bags around a box, for the first frame or for tracking."""

    def __init__(self, params: BagSettings, *, first_frame: bool = False) -> None:
        p = params
        pos_r = p.init_pos_radius if first_frame and p.init_pos_radius is not None else p.pos_radius
        inner = p.init_neg_inner if first_frame and p.init_neg_inner is not None else p.neg_inner
        outer = p.init_neg_outer if first_frame and p.init_neg_outer is not None else p.neg_outer
        count = p.init_neg_count if first_frame and p.init_neg_count is not None else p.neg_count
        self.pos_offsets = disc_offsets(pos_r)
        self.pos_dist = np.hypot(self.pos_offsets[:, 0], self.pos_offsets[:, 1])
        self.pos_dist.setflags(write=False)  # handed out as is by positives()
        self._full_weights: dict[str, np.ndarray] = {}
        self._core_specs: dict[str, tuple[Any, ...]] = {}
        self.neg_offsets = annulus_offsets(inner, outer)
        self.neg_count = count
        self.mode = p.neg_sampling
        # The references keep each annulus point with probability max / bounding-square area.
        self.keep_prob = min(1.0, count / float((2 * math.floor(outer) + 1) ** 2))
        self.reach = math.ceil(max(pos_r, outer))
        # Largest |dx|, |dy| of each offset set: a box at least this far from every frame edge
        # keeps all its offsets inside, and the masks below can be skipped (same result).
        self._pos_reach = int(np.abs(self.pos_offsets).max(initial=0))
        self._neg_reach = int(np.abs(self.neg_offsets).max(initial=0))

    @staticmethod
    def _inside(offsets: np.ndarray, box: tuple[int, int, int, int], frame_w: int,
                frame_h: int) -> np.ndarray:
        x, y, w, h = box
        xs = x + offsets[:, 0]
        ys = y + offsets[:, 1]
        return (xs >= 0) & (ys >= 0) & (xs + w <= frame_w) & (ys + h <= frame_h)

    @staticmethod
    def _all_inside(reach: int, box: tuple[int, int, int, int], frame_w: int, frame_h: int) -> bool:
        x, y, w, h = box
        return x - reach >= 0 and y - reach >= 0 and x + reach + w <= frame_w and y + reach + h <= frame_h

    def positives(self, box: tuple[int, int, int, int], frame_w: int,
                  frame_h: int) -> tuple[np.ndarray, np.ndarray]:
        """Top-left corners ``(n, 2)`` of the positive bag inside the frame, and their distances."""
        origin = np.array(box[:2], dtype=np.int32)
        if self._all_inside(self._pos_reach, box, frame_w, frame_h):
            return self.pos_offsets + origin, self.pos_dist
        keep = self._inside(self.pos_offsets, box, frame_w, frame_h)
        return self.pos_offsets[keep] + origin, self.pos_dist[keep]

    def weights(self, distances: np.ndarray, mode: str) -> np.ndarray:
        """:func:`instance_weights` of a positive bag from :meth:`positives`; computed once for
        the whole bag (the usual case: the box away from the frame's edges), read-only."""
        if distances is not self.pos_dist:
            return instance_weights(distances, mode)
        w = self._full_weights.get(mode)
        if w is None:
            w = instance_weights(distances, mode)
            w.setflags(write=False)
            self._full_weights[mode] = w
        return w

    def negatives(self, box: tuple[int, int, int, int], frame_w: int, frame_h: int,
                  rng: np.random.Generator) -> np.ndarray:
        """Top-left corners ``(n, 2)`` of the negatives inside the frame."""
        if self._all_inside(self._neg_reach, box, frame_w, frame_h):
            candidates = self.neg_offsets
        else:
            candidates = self.neg_offsets[self._inside(self.neg_offsets, box, frame_w, frame_h)]
        out: np.ndarray = self.draw(candidates, rng) + np.array(box[:2], dtype=np.int32)
        return out

    def draw(self, candidates: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """The negatives' offsets drawn from ``candidates`` (rows of ``neg_offsets``), in order."""
        if self.mode == "exact":
            if candidates.shape[0] > self.neg_count:
                pick = rng.choice(candidates.shape[0], size=self.neg_count, replace=False)
                candidates = candidates[np.sort(pick)]
            return candidates
        kept: np.ndarray = candidates[rng.random(candidates.shape[0]) < self.keep_prob][: self.neg_count]
        return kept

    def drawn_in_core(self) -> bool:
        """Whether the core can draw this sampler's negatives as numpy would: a Bernoulli draw,
        or an exact one from at most 10 000 offsets (numpy's ``choice`` then always takes
        Floyd's algorithm, which the core repeats; above that it may shuffle instead), and
        the core's copies of those draws match the installed numpy
        (:func:`core_draws_match_numpy`)."""
        small = self.mode != "exact" or self.neg_offsets.shape[0] <= 10_000
        return small and core_draws_match_numpy()

    def core_spec(self, weights: str) -> tuple[Any, ...]:
        """This sampler for the core's ``frame_step`` (``bags`` without its leading ``rng``):
        the offsets, the positives' weight terms for ``weights`` (an ``instance_weights``
        mode, or ``"none"``: no weights), and the negatives' draw."""
        spec = self._core_specs.get(weights)
        if spec is None:
            terms = None
            if weights == "exp":  # instance_weights' terms, before the division by their sum
                terms = np.exp(-self.pos_dist)
            elif weights == "exp_sq":
                terms = np.exp(-(self.pos_dist**2))
            spec = (self.pos_offsets, terms, weights, self.neg_offsets, self.mode == "exact",
                    self.neg_count, self.keep_prob)
            self._core_specs[weights] = spec
        return spec


def instance_weights(distances: np.ndarray, mode: str) -> np.ndarray:
    """Weights of the positive instances: exp(-d)/sum (paper), exp(-d^2) (reference code), equal."""
    if distances.size == 0:
        return np.zeros(0)
    if mode == "exp":
        w: np.ndarray = np.exp(-distances)
        normalised: np.ndarray = w / w.sum()
        return normalised
    if mode == "exp_sq":
        sq: np.ndarray = np.exp(-(distances**2))
        return sq
    return np.full(distances.shape, 1.0 / distances.size)
