"""Box geometry that several parts share: a box's centre, a box of another size on the same
centre, two boxes' overlap, a box cut to the frame, and the region an integral image must hold
around a box, a box moved to another's centre. (No part needs to import another part for these.)"""

from __future__ import annotations

import math
from collections.abc import Sequence

from .frames import IntBox

__all__ = ["centre", "centred", "overlap", "placed_at", "roi_around", "within"]

#: A box ``(x, y, w, h)`` of whole or fractional pixels.
AnyBox = Sequence[float]


def centre(box: AnyBox) -> tuple[float, float]:
    """The centre ``(x + w / 2, y + h / 2)`` of ``box``."""
    return box[0] + box[2] / 2.0, box[1] + box[3] / 2.0


def centred(box: IntBox, w: int, h: int, dx: float = 0.0, dy: float = 0.0) -> IntBox:
    """A ``w x h`` box with the centre of ``box`` moved by ``(dx, dy)``."""
    cx = box[0] + box[2] / 2.0 + dx
    cy = box[1] + box[3] / 2.0 + dy
    return int(math.floor(cx - w / 2.0 + 0.5)), int(math.floor(cy - h / 2.0 + 0.5)), w, h


def roi_around(box: IntBox, margin: int) -> IntBox:
    """The integral image's region around ``box``: ``margin`` pixels and one more."""
    x, y, w, h = box
    m = margin + 1
    return x - m, y - m, w + 2 * m, h + 2 * m


def overlap(a: AnyBox, b: AnyBox) -> float:
    """The intersection over union of two boxes (0 for boxes without area)."""
    iw = max(0.0, min(a[0] + a[2], b[0] + b[2]) - max(a[0], b[0]))
    ih = max(0.0, min(a[1] + a[3], b[1] + b[3]) - max(a[1], b[1]))
    inter = iw * ih
    union = a[2] * a[3] + b[2] * b[3] - inter
    return inter / union if union > 0 else 0.0


def within(box: AnyBox, frame_w: int, frame_h: int) -> tuple[float, float, float, float]:
    """``box`` cut to a ``frame_w x frame_h`` frame, at least one pixel wide and high."""
    x, y, w, h = box
    x0, y0 = min(max(x, 0.0), frame_w - 1.0), min(max(y, 0.0), frame_h - 1.0)
    x1 = min(max(x + w, x0 + 1.0), float(frame_w))
    y1 = min(max(y + h, y0 + 1.0), float(frame_h))
    return x0, y0, x1 - x0, y1 - y0


def placed_at(box: IntBox, other: AnyBox, frame_w: int, frame_h: int) -> IntBox:
    """``box`` (whole pixels) moved to the centre of ``other`` at its own size, rounded and
    kept inside a ``frame_w x frame_h`` frame: a tracker handed the target by another expert."""
    x, y, w, h = (float(v) for v in other)
    _, _, bw, bh = box
    nx = min(max(int(round(x + w / 2 - bw / 2)), 0), max(frame_w - bw, 0))
    ny = min(max(int(round(y + h / 2 - bh / 2)), 0), max(frame_h - bh, 0))
    return nx, ny, bw, bh
