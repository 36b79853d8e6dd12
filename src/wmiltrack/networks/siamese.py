"""What a Siamese tracker network is to wmiltrack, and what every such network's step shares.

A Siamese tracker (SiamFC's descendants: NanoTrack, LightTrack, FEAR, VitTrack) keeps a template
taken from a box of the first frame and searches a window around a box of each new frame for
it. To the engine it is a :class:`SiameseStep`: *template from a box; search from a box ->
the candidate with its scores; likeness of a box to the memory*. A family's module
(:mod:`wmiltrack.networks.nanotrack`) implements it with its own crop sizes, answer grid and
post-processing, and :func:`wmiltrack.networks.families.load_siamese` builds it from a model
set's name; another family is another module and another model set
(:data:`wmiltrack.networks.files.MODELS`), not a change to the engine.

The networks read BGR images (:func:`as_bgr`) cropped around the target with some context
(:func:`context_side`, :func:`crop`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np

__all__ = ["CONTEXT", "Candidate", "FloatBox", "SiameseStep", "as_bgr", "box_centre", "context_side",
           "crop"]

FloatBox = tuple[float, float, float, float]

CONTEXT = 0.5
"""The context around the target in a template crop, as a share of its perimeter's half
(SiamFC's: the crop's side is ``sqrt((w + p)(h + p))``, ``p = CONTEXT (w + h)``)."""


@dataclass(frozen=True)
class Candidate:
    """One search of the network: the box it chose ``(x, y, w, h)``, its score there (the
    network's own confidence at that place, before the step's penalties) and the best
    penalised score."""

    box: FloatBox
    score: float
    pscore: float


class SiameseStep(Protocol):
    """A Siamese network's tracking step, as the engine uses it.

    The template is taken by :meth:`start` and kept: :meth:`recentre` moves the state without
    touching it. ``size`` is the state's target size ``(w, h)``.
    """

    size: tuple[float, float]

    def start(self, frame: np.ndarray, box: FloatBox) -> None:
        """Take the template from the BGR ``frame`` at ``box``."""
        ...

    def locate(self, frame: np.ndarray, *, narrow: bool = False) -> Candidate:
        """One tracking step on ``frame`` from the current state; the state follows.
        ``narrow``: over the step's narrow search window (a smaller crop at the same scale,
        for a target that moved little; the published window where the step has none)."""
        ...

    def search_at(self, frame: np.ndarray, centre: tuple[float, float],
                  size: tuple[float, float], *, window: bool, narrow: bool = False) -> Candidate:
        """The step's choice in a search window centred at ``centre`` for a target of ``size``
        (``window``: with the step's motion prior, as in tracking; ``narrow``: the narrow
        window); the state does not change."""
        ...

    def recentre(self, box: FloatBox) -> None:
        """Move the state to ``box`` (the template is kept)."""
        ...

    def likeness(self, frame: np.ndarray, box: FloatBox) -> float:
        """How alike the target at ``box`` is to the template's (1: the same appearance)."""
        ...

    def search_side(self, size: tuple[float, float]) -> float:
        """The side, in frame pixels, of the search window for a target of ``size``."""
        ...


def box_centre(box: FloatBox) -> tuple[float, float]:
    """The centre ``(x + w / 2, y + h / 2)`` of ``box``."""
    return box[0] + box[2] / 2.0, box[1] + box[3] / 2.0


def context_side(w: float, h: float) -> float:
    """The template crop's side in frame pixels for a target of ``w x h`` (:data:`CONTEXT`)."""
    pad = CONTEXT * (w + h)
    return math.sqrt((w + pad) * (h + pad))


def crop(frame: np.ndarray, cx: float, cy: float, side: float, out: int,
         fill: tuple[float, float, float]) -> np.ndarray:
    """The square of ``side`` frame pixels (rounded) centred at ``(cx, cy)``, resized to
    ``out`` x ``out``; beyond the frame, ``fill``. The published step's window (SiamRPN's
    ``get_subwindow``: the integer square, padded with the fill where it leaves the frame,
    resized bilinearly), padded only as far as the window leaves the frame: 2-3 times faster
    than one ``warpAffine`` of the whole frame, and its edges as the network was trained."""
    import cv2

    n = max(1, int(round(side)))
    x0 = math.floor(cx - (n + 1) / 2 + 0.5)
    y0 = math.floor(cy - (n + 1) / 2 + 0.5)
    fh, fw = frame.shape[:2]
    left, top = max(0, -x0), max(0, -y0)
    right, bottom = max(0, x0 + n - fw), max(0, y0 + n - fh)
    if left + right >= n or top + bottom >= n:  # (the window is wholly outside the frame)
        return np.full((out, out, frame.shape[2]), np.round(fill), dtype=frame.dtype)
    window = frame[y0 + top:y0 + n - bottom, x0 + left:x0 + n - right]
    if left or top or right or bottom:
        window = cv2.copyMakeBorder(window, top, bottom, left, right, cv2.BORDER_CONSTANT,
                                    value=fill)
    if n == out:  # (a copy: a window inside the frame is a view of it)
        return window.copy()
    patch: np.ndarray = cv2.resize(window, (out, out), interpolation=cv2.INTER_LINEAR)
    return patch


def as_bgr(frame: np.ndarray) -> np.ndarray:
    """A uint8 frame as BGR, what the networks read: grey (``H x W`` or ``H x W x 1``)
    repeated over three channels, BGRA's alpha dropped, BGR as it is."""
    import cv2

    channels = 1 if frame.ndim == 2 else frame.shape[2]
    if channels == 3:
        return frame
    code = cv2.COLOR_GRAY2BGR if channels == 1 else cv2.COLOR_BGRA2BGR
    out: np.ndarray = cv2.cvtColor(np.ascontiguousarray(frame), code)
    return out
