"""Box geometry that several parts share: a box of another size on the same centre, and the region
an integral image must hold around a box. (No part needs to import another part for these.)"""

from __future__ import annotations

import math

from .frames import IntBox

__all__ = ["centred", "roi_around"]


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
