"""Drawing tracker output on frames (OpenCV)."""

from __future__ import annotations

import math
from collections.abc import Sequence

import cv2
import numpy as np


def draw_result(frame: np.ndarray, box: Sequence[float], *, index: int | None = None,
                score: float | None = None, color: tuple[int, int, int] = (0, 255, 0)) -> np.ndarray:
    """A BGR copy of ``frame`` with ``box`` drawn, and the frame number and score written."""
    out = np.array(frame, dtype=np.uint8, copy=True)
    if out.ndim == 2:
        out = cv2.cvtColor(out, cv2.COLOR_GRAY2BGR)
    x, y, w, h = (float(v) for v in box)
    if all(math.isfinite(v) for v in (x, y, w, h)):
        cv2.rectangle(out, (round(x), round(y)), (round(x + w) - 1, round(y + h) - 1), color, 2)
    parts = []
    if index is not None:
        parts.append(f"#{index}")
    if score is not None and math.isfinite(score):
        parts.append(f"score {score:.2f}")
    if parts:
        text = "  ".join(parts)
        cv2.putText(out, text, (6, 18), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (0, 0, 0), 3, cv2.LINE_AA)
        cv2.putText(out, text, (6, 18), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (255, 255, 255), 1, cv2.LINE_AA)
    return out
