"""Box files: one ``x,y,w,h`` line per frame, the format of OTB ground truth and of results."""

from __future__ import annotations

import math
import os
import re
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["format_box", "read_boxes", "write_boxes"]

_SPLIT = re.compile(r"[,\t ;]+")


def _as_box_array(boxes: ArrayLike | Iterable[Any]) -> NDArray[np.float64]:
    """Coerce boxes (array-like or objects with a ``box`` attribute) to an ``(n, 4)`` array."""
    if not isinstance(boxes, np.ndarray):
        items = list(boxes)  # type: ignore[arg-type]
        rows = [getattr(b, "box", b) for b in items]
        arr = np.asarray(rows, dtype=np.float64) if rows else np.zeros((0, 4))
    else:
        arr = np.asarray(boxes, dtype=np.float64)
    if arr.ndim == 1 and arr.size == 4:
        arr = arr.reshape(1, 4)
    if arr.ndim != 2 or arr.shape[1] != 4:
        raise ValueError(f"boxes must have shape (n, 4), got {arr.shape}")
    return arr


def read_boxes(path: str | os.PathLike[str]) -> NDArray[np.float64]:
    """Read one ``x,y,w,h`` box per line.

    Parameters
    ----------
    path:
        Text file. Values may be separated by commas, tabs, spaces or semicolons (mixed is
        fine); blank lines are skipped; ``NaN`` is kept as ``nan``.

    Returns
    -------
    numpy.ndarray
        ``(n, 4)`` float64 array, exactly the numbers written in the file.

    Raises
    ------
    FileNotFoundError
        If the file does not exist.
    ValueError
        If a line does not hold exactly four numbers.
    """
    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"box file not found: {p}")
    rows: list[list[float]] = []
    with p.open(encoding="utf-8-sig") as fh:
        for lineno, line in enumerate(fh, start=1):
            text = line.strip()
            if not text:
                continue
            fields = [f for f in _SPLIT.split(text) if f]
            if len(fields) != 4:
                raise ValueError(
                    f"{p}:{lineno}: expected 4 values (x, y, w, h), got {len(fields)}: {text!r}"
                )
            try:
                rows.append([float(f) for f in fields])
            except ValueError:
                raise ValueError(f"{p}:{lineno}: not a number in {text!r}") from None
    if not rows:
        return np.zeros((0, 4), dtype=np.float64)
    return np.asarray(rows, dtype=np.float64)


def _fmt(value: float) -> str:
    if math.isnan(value):
        return "NaN"
    if math.isfinite(value) and value.is_integer():
        return str(int(value))
    return repr(value)


def format_box(box: Iterable[float]) -> str:
    """One box as its ``x,y,w,h`` line (no newline), exactly as :func:`write_boxes` writes it:
    integral values without a decimal point, others in full precision, ``NaN`` for missing."""
    return ",".join(_fmt(float(v)) for v in box)


def write_boxes(path: str | os.PathLike[str], boxes: ArrayLike | Iterable[Any]) -> None:
    """Write one ``x,y,w,h`` line per box (comma separated, ``NaN`` for missing boxes).

    Parameters
    ----------
    path:
        Destination file; its parent folders are created.
    boxes:
        ``(n, 4)`` array-like, or an iterable of objects with a ``box`` attribute
        (such as :class:`wmiltrack.TrackResult`). Integral values are written without a
        decimal point, others with full precision, so :func:`read_boxes` gives them back exactly.
    """
    arr = _as_box_array(boxes)
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    lines = [format_box(row) for row in arr]
    p.write_text("".join(line + "\n" for line in lines), encoding="utf-8")
