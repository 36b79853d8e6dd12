"""Checking and converting what users pass as frames and boxes."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

IntBox = tuple[int, int, int, int]


def _check_shape(frame: np.ndarray) -> None:
    """A ``ValueError`` unless ``frame`` is ``H x W`` or ``H x W x C`` (C 1, 3 or 4), not empty."""
    shape = frame.shape  # (read once: each read of an array's shape makes a new tuple)
    if len(shape) not in (2, 3):
        raise ValueError(f"frame must be H x W or H x W x C, got shape {shape}")
    if len(shape) == 3 and shape[2] not in (1, 3, 4):
        raise ValueError(
            f"frame must have 1, 3 (BGR) or 4 (BGRA) channels, got {shape[2]} (shape {shape})"
        )
    if shape[0] == 0 or shape[1] == 0:
        raise ValueError(f"frame is empty (shape {shape})")


def as_frame(frame: Any) -> np.ndarray:
    """Validate a frame and return it as a uint8 array the core can read without copying.

    Accepted: ``H x W`` gray, ``H x W x 1``, ``H x W x 3`` (BGR, as OpenCV reads) and
    ``H x W x 4`` (BGRA; alpha ignored), any memory layout, read-only or not. A frame whose
    rows are contiguous (C order, or a crop of such a frame) is used without copying; another
    layout (Fortran order, a transposed or reversed view, every other column) is copied into C
    order once, because OpenCV, which some cues use, refuses such arrays. An ndarray subclass
    (``np.matrix``, a masked array: its data, the mask ignored) is read as a plain array.

    * uint8: used as is.
    * other integer dtypes: accepted when every value is in 0..255 (the 8-bit scale),
      otherwise ``ValueError`` (scale 16-bit images yourself, e.g. ``frame >> 8``).
    * float16/32/64: read on the 0..255 scale (as ``frame.astype(float)`` of an 8-bit
      image gives) and rounded; NaN, infinity or values outside [0, 255] are a ``ValueError``,
      and so is a frame whose values all lie in (0, 1]: that is ambiguous (most likely a
      [0, 1] image, which would silently read as black), so scale it first.
    * bool, complex, object and other dtypes: ``TypeError``.
    """
    if not isinstance(frame, np.ndarray):
        raise TypeError(f"frame must be a numpy array, got {type(frame).__name__}")
    if type(frame) is not np.ndarray:  # a subclass (np.matrix, a masked array): its plain data,
        frame = np.asarray(frame)      # which numpy's and OpenCV's functions read as expected
    _check_shape(frame)
    if frame.dtype == np.uint8:  # (the usual frame: nothing else to look at)
        return _rows_contiguous(frame)
    kind = frame.dtype.kind
    lo: float  # value range, for the messages below (int for integer frames)
    hi: float
    if kind in "ui":
        lo, hi = int(frame.min()), int(frame.max())
        if lo < 0 or hi > 255:
            raise ValueError(
                f"{frame.dtype} frame has values in [{lo}, {hi}]; wmiltrack reads integer frames on "
                "the 8-bit scale 0..255 (convert it first, e.g. (frame >> 8).astype(np.uint8) for 16-bit)"
            )
        converted: np.ndarray = frame.astype(np.uint8, order="C")
        return converted
    if kind == "f":
        lo, hi = float(np.min(frame)), float(np.max(frame))
        if not (math.isfinite(lo) and math.isfinite(hi)):
            raise ValueError("float frame contains NaN or infinity")
        if lo < 0.0 or hi > 255.0:
            raise ValueError(
                f"float frame has values in [{lo:g}, {hi:g}]; wmiltrack reads float frames on the "
                "0..255 scale (multiply a [0, 1] image by 255 first)"
            )
        if 0.0 < hi <= 1.0:
            raise ValueError(
                f"float frame has values in [{lo:g}, {hi:g}]: ambiguous, a [0, 1] image would read "
                "as black on wmiltrack's 0..255 float scale; pass (frame * 255) or a uint8 frame"
            )
        rounded: np.ndarray = np.rint(frame).astype(np.uint8, order="C")
        return rounded
    raise TypeError(f"frame dtype {frame.dtype} is not supported: pass uint8 (or 0..255 ints/floats)")


def _rows_contiguous(frame: np.ndarray) -> np.ndarray:
    """``frame`` itself when each row's pixels are contiguous and rows go forward in memory (as
    OpenCV's functions need), else a C-ordered copy."""
    item, shape, strides = frame.itemsize, frame.shape, frame.strides
    pixel = item * (shape[2] if len(shape) == 3 else 1)
    rows_ok = strides[1] == pixel and (len(shape) == 2 or strides[2] == item)
    if rows_ok and strides[0] >= pixel * shape[1]:
        return frame
    return np.ascontiguousarray(frame)


def frame_size(frame: np.ndarray) -> tuple[int, int]:
    """``(width, height)``."""
    shape = frame.shape
    return int(shape[1]), int(shape[0])


def clip_box(box: Any, frame_w: int, frame_h: int) -> IntBox:
    """Round a user box ``(x, y, w, h)`` to whole pixels and clip it to the frame.

    Raises ``TypeError`` for something that is not four real numbers and ``ValueError`` for
    non-finite values, non-positive sizes or a box wholly outside the frame.
    """
    try:
        if isinstance(box, (str, bytes)):  # "1234" would otherwise read as (1, 2, 3, 4)
            raise TypeError
        items = list(box)
        if any(isinstance(v, (str, bytes, np.str_, np.bytes_)) for v in items):
            raise TypeError
        values = [float(v) for v in items]
    except (TypeError, ValueError):
        raise TypeError(f"box must be four numbers (x, y, w, h), got {box!r}") from None
    if len(values) != 4:
        raise TypeError(f"box must be four numbers (x, y, w, h), got {len(values)}: {box!r}")
    if not all(math.isfinite(v) for v in values):
        raise ValueError(f"box has NaN or infinite values: {tuple(values)}")
    x, y, w, h = values
    if w <= 0 or h <= 0:
        raise ValueError(f"box must have positive width and height, got w={w:g}, h={h:g}")
    x0, y0 = max(x, 0.0), max(y, 0.0)
    x1, y1 = min(x + w, float(frame_w)), min(y + h, float(frame_h))
    if x1 <= x0 or y1 <= y0:
        raise ValueError(
            f"box {tuple(values)} lies wholly outside the {frame_w}x{frame_h} frame"
        )
    xi, yi = int(round(x0)), int(round(y0))
    xe, ye = int(round(x1)), int(round(y1))
    xi, yi = min(xi, frame_w - 1), min(yi, frame_h - 1)
    return xi, yi, max(xe - xi, 1), max(ye - yi, 1)
