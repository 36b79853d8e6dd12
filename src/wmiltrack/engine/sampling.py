"""Bag sampling: positive offsets in a disc, negative offsets in an annulus (spec section 0).

Offsets are integer ``(dx, dy)`` displacements of the box's top-left corner; sets are
enumerated in row-major order (dy outer, dx inner) so that results are reproducible.
"""

from __future__ import annotations

import math

import numpy as np

from .params import Params


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

    def __init__(self, params: Params, *, first_frame: bool = False) -> None:
        p = params
        pos_r = p.init_pos_radius if first_frame and p.init_pos_radius is not None else p.pos_radius
        inner = p.init_neg_inner if first_frame and p.init_neg_inner is not None else p.neg_inner
        outer = p.init_neg_outer if first_frame and p.init_neg_outer is not None else p.neg_outer
        count = p.init_neg_count if first_frame and p.init_neg_count is not None else p.neg_count
        self.pos_offsets = disc_offsets(pos_r)
        self.pos_dist = np.hypot(self.pos_offsets[:, 0], self.pos_offsets[:, 1])
        self.pos_dist.setflags(write=False)  # handed out as is by positives()
        self._full_weights: dict[str, np.ndarray] = {}
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

    def inside_anywhere(self, box: tuple[int, int, int, int], reach: int, frame_w: int,
                        frame_h: int) -> bool:
        """Whether both bags stay inside the frame around every box within ``reach`` pixels of
        ``box``: then the bags' offsets, and the random draw of the negatives, do not depend
        on where a search from ``box`` lands (so the draw may come before the search)."""
        return self._all_inside(max(self._pos_reach, self._neg_reach) + reach, box, frame_w, frame_h)


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
