"""Several image channels, each with its own integral image, for Haar features on one channel each.

``rcwmil-plus`` draws each feature on one channel: luma, gradient magnitude or one of two
colour-opponent channels. The channels are computed only over the search region (a crop of
the frame), so the per-frame cost stays proportional to that region, not to the frame.
Weak-classifier log ratios add over features, so a frame's candidate scores are the sum of
one :func:`wmiltrack._core.score_grid` grid per channel.

Coordinates: the integral images are built over the crop, so boxes and corners are shifted
by the crop's origin before they reach the core; candidates outside the crop are exactly
those outside the frame (the crop is the search region clipped to the frame).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import cast

import cv2
import numpy as np

from .. import _core
from .features import BankArrays

#: Channel names in the order of their ids.
CHANNELS = ("luma", "grad", "opp_rg", "opp_yb")
#: Channels that need a colour (3- or 4-channel) frame.
COLOUR_CHANNELS = frozenset({"opp_rg", "opp_yb"})


def available_channels(wanted: tuple[str, ...], frame: np.ndarray) -> tuple[str, ...]:
    """The channels of ``wanted`` that ``frame`` can give (colour ones drop out for gray frames)."""
    colour = frame.ndim == 3 and frame.shape[2] in (3, 4)
    return tuple(c for c in wanted if colour or c not in COLOUR_CHANNELS)


def _planes(crop: np.ndarray, names: tuple[str, ...]) -> list[np.ndarray]:
    """The uint8 planes of ``names`` for a crop (gray ``H x W`` or BGR(A) ``H x W x C``)."""
    gray_input = crop.ndim == 2 or crop.shape[2] == 1
    out: list[np.ndarray] = []
    gray: np.ndarray | None = None
    for name in names:
        if name == "luma":
            out.append(crop)  # the core converts BGR(A) to luma itself, as in the paper path
            continue
        if name == "grad":
            if gray is None:
                if gray_input:
                    gray = np.ascontiguousarray(crop.reshape(crop.shape[0], crop.shape[1]))
                else:
                    gray = cv2.cvtColor(np.ascontiguousarray(crop[:, :, :3]), cv2.COLOR_BGR2GRAY)
            gx = cv2.Sobel(gray, cv2.CV_32F, 1, 0, ksize=3)
            gy = cv2.Sobel(gray, cv2.CV_32F, 0, 1, ksize=3)
            mag = cv2.magnitude(gx, gy)
            out.append(np.clip(mag * 0.25, 0, 255).astype(np.uint8))
            continue
        b = crop[:, :, 0].astype(np.int16)
        g = crop[:, :, 1].astype(np.int16)
        r = crop[:, :, 2].astype(np.int16)
        if name == "opp_rg":
            out.append(((r - g) // 2 + 128).astype(np.uint8))
        else:  # opp_yb
            out.append(((r + g - 2 * b) // 4 + 128).astype(np.uint8))
    return out


@dataclass
class ChannelBank:
    """A bank split by channel: ``features[c]`` are the bank's features on channel ``c``."""

    features: list[np.ndarray]
    banks: list[_core.FeatureBank | None]
    local: np.ndarray  # (M,) index of each feature within its channel's bank

    @classmethod
    def build(cls, arrays: BankArrays, channel: np.ndarray, n_channels: int) -> ChannelBank:
        features: list[np.ndarray] = []
        banks: list[_core.FeatureBank | None] = []
        local = np.zeros(arrays.size, dtype=np.int32)
        for c in range(n_channels):
            idx = np.flatnonzero(channel == c).astype(np.int32)
            features.append(idx)
            local[idx] = np.arange(idx.size, dtype=np.int32)
            if idx.size == 0:
                banks.append(None)
                continue
            counts = arrays.starts[idx + 1] - arrays.starts[idx]
            starts = np.zeros(idx.size + 1, dtype=np.int32)
            np.cumsum(counts, out=starts[1:])
            rows = np.concatenate([np.arange(arrays.starts[f], arrays.starts[f + 1]) for f in idx])
            banks.append(_core.FeatureBank(starts, np.ascontiguousarray(arrays.rects[rows]),
                                           np.ascontiguousarray(arrays.weights[rows])))
        return cls(features=features, banks=banks, local=local)


class ChannelImages:
    """Integral images of several channels over one crop of the frame."""

    def __init__(self, names: tuple[str, ...]) -> None:
        self.names = names
        self._ii = [_core.IntegralImage() for _ in names]
        self.origin = (0, 0)
        self.size = (0, 0)

    def compute(self, frame: np.ndarray, roi: tuple[int, int, int, int]) -> None:
        """Build every channel's integral image over ``roi`` clipped to the frame."""
        fh, fw = frame.shape[:2]
        x, y, w, h = roi
        x0, y0 = max(x, 0), max(y, 0)
        x1, y1 = min(x + w, fw), min(y + h, fh)
        if x1 <= x0 or y1 <= y0:
            raise ValueError("the search region does not meet the frame")
        crop = frame[y0:y1, x0:x1]
        self.origin = (x0, y0)
        self.size = (x1 - x0, y1 - y0)
        for ii, plane in zip(self._ii, _planes(crop, self.names)):
            ii.compute(plane, (0, 0, x1 - x0, y1 - y0))

    def _local_box(self, box: tuple[int, int, int, int]) -> tuple[int, int, int, int]:
        return box[0] - self.origin[0], box[1] - self.origin[1], box[2], box[3]

    def score_grid(self, bank: ChannelBank, selected: np.ndarray, mu1: np.ndarray,
                   sigma1: np.ndarray, mu0: np.ndarray, sigma0: np.ndarray, guard: float,
                   box: tuple[int, int, int, int], radius: int,
                   step: int) -> tuple[int, int, float, int]:
        """As :func:`wmiltrack._core.score_grid`, summing the per-channel grids.

        ``mu1`` .. ``sigma0`` hold one entry per selected feature (as for the core).
        """
        total = self.grid(bank, selected, mu1, sigma1, mu0, sigma0, guard, box, radius, step)
        if total is None:
            return 0, 0, -np.inf, 0
        finite = np.isfinite(total)
        n = int(np.count_nonzero(finite))
        if n == 0:
            return 0, 0, -np.inf, 0
        flat = np.where(finite, total, -np.inf).ravel()
        best = int(np.argmax(flat))  # the first maximum in row-major order, as the core
        side = total.shape[0]
        half = (side - 1) // 2
        row, col = divmod(best, side)
        return (col - half) * step, (row - half) * step, float(flat[best]), n

    def grid(self, bank: ChannelBank, selected: np.ndarray, mu1: np.ndarray, sigma1: np.ndarray,
             mu0: np.ndarray, sigma0: np.ndarray, guard: float, box: tuple[int, int, int, int],
             radius: int, step: int) -> np.ndarray | None:
        """The summed raw-score grid (``-inf``: not a candidate); ``None`` if nothing is scored."""
        total: np.ndarray | None = None
        local_box = self._local_box(box)
        for c, ii in enumerate(self._ii):
            sub_bank = bank.banks[c]
            on_c = np.flatnonzero(np.isin(selected, bank.features[c]))
            if sub_bank is None or on_c.size == 0:
                continue
            feats = selected[on_c]
            out = _core.score_grid(ii, sub_bank, bank.local[feats], mu1[on_c], sigma1[on_c],
                                   mu0[on_c], sigma0[on_c], guard, local_box, radius, step,
                                   self.size, True)
            grid = cast(tuple[int, int, float, int, np.ndarray], out)[4]
            total = grid if total is None else total + grid
        return total

    def project(self, bank: ChannelBank, xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
        """Feature values ``(M, n)`` of the boxes with top-left corners ``(xs, ys)``."""
        m = bank.local.size
        out = np.zeros((m, xs.size))
        lx = (xs - self.origin[0]).astype(np.int32)
        ly = (ys - self.origin[1]).astype(np.int32)
        for c, ii in enumerate(self._ii):
            sub_bank = bank.banks[c]
            if sub_bank is None:
                continue
            out[bank.features[c]] = _core.project(ii, sub_bank, lx, ly)
        return out
