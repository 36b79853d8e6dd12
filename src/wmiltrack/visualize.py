"""Drawing tracker output on frames (OpenCV)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import cv2
import numpy as np


def draw_result(frame: np.ndarray, box: Sequence[float], *, index: int | None = None,
                score: float | None = None, color: tuple[int, int, int] = (0, 255, 0)) -> np.ndarray:
    """A BGR copy of ``frame`` with ``box`` drawn, and the frame number and score written
    (``index`` is shown as ``#index``: pass the frame's number counted from 1, as the command
    line's output, warnings and MOT lines count them)."""
    out: np.ndarray[Any, Any] = np.array(frame, dtype=np.uint8, copy=True)
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


def grid_offsets(radius: int, step: int) -> np.ndarray:
    """The search grid of one stage: offsets ``(i*step, j*step)`` with norm < ``radius``.

    Parameters
    ----------
    radius, step : int
        Stage radius and step (``Params.coarse_radius``/``coarse_step`` or the fine ones).

    Returns
    -------
    numpy.ndarray
        ``(n, 2)`` int offsets ``(dx, dy)``.
    """
    half = (radius - 1) // step
    d = np.arange(-half, half + 1) * step
    dy, dx = np.meshgrid(d, d, indexing="ij")
    keep = dx * dx + dy * dy < radius * radius
    return np.stack([dx[keep], dy[keep]], axis=1).astype(np.int32)


def draw_samples(frame: np.ndarray, samples: dict[str, Any], *, scale: int = 3,
                 margin: int = 40) -> np.ndarray:
    """Draw the bags and the search grids of one tracker step, cropped around the target.

    Parameters
    ----------
    frame : numpy.ndarray
        The frame the step ran on (BGR or gray).
    samples : dict
        :meth:`wmiltrack.Tracker.samples` after that step.
    scale : int
        Enlargement of the crop (nearest neighbour), so that single pixels show.
    margin : int
        Pixels kept around the outermost drawn point.

    Returns
    -------
    numpy.ndarray
        BGR image: box centres of the positive bag (green), the negative bag (red), the
        coarse search grid (blue, around the previous box) and the fine grid (yellow, around
        the coarse winner); the boxes of the other scales searched (magenta, when the
        tracker searches scales: ``samples["scales"]``); the final box in white; a legend
        at the bottom.
    """
    img: np.ndarray[Any, Any] = np.array(frame, dtype=np.uint8, copy=True)
    if img.ndim == 2:
        img = cv2.cvtColor(img, cv2.COLOR_GRAY2BGR)
    x, y, w, h = samples["box"]
    cx, cy = w / 2.0, h / 2.0
    layers: list[tuple[np.ndarray, tuple[int, int, int], int]] = []
    colors = [(255, 128, 0), (0, 220, 255)]
    for k, (origin, radius, step) in enumerate(samples["search"]):
        if radius <= 0:
            continue
        pts = grid_offsets(radius, step) + np.array(origin[:2])
        layers.append((pts, colors[min(k, 1)], 1))
    layers.append((np.asarray(samples["negative"]), (0, 0, 255), 2))
    layers.append((np.asarray(samples["positive"]), (0, 200, 0), 1))
    scale_boxes = [tuple(int(v) for v in b) for b in samples.get("scales", [])]
    allpts = np.concatenate([p for p, _, _ in layers] + [np.array([[x, y]])], axis=0)
    x0 = int(max(allpts[:, 0].min() + cx - margin, 0))
    y0 = int(max(allpts[:, 1].min() + cy - margin, 0))
    x1 = int(min(allpts[:, 0].max() + cx + margin, img.shape[1]))
    y1 = int(min(allpts[:, 1].max() + cy + margin, img.shape[0]))
    x0, y0 = min(x0, int(x)), min(y0, int(y))
    x1, y1 = max(x1, min(int(x + w) + 1, img.shape[1])), max(y1, min(int(y + h) + 1, img.shape[0]))
    for bx, by, bw, bh in scale_boxes:
        x0, y0 = max(min(x0, bx), 0), max(min(y0, by), 0)
        x1, y1 = min(max(x1, bx + bw + 1), img.shape[1]), min(max(y1, by + bh + 1), img.shape[0])
    crop = cv2.resize(img[y0:y1, x0:x1], None, fx=scale, fy=scale, interpolation=cv2.INTER_NEAREST)
    crop = (crop.astype(np.float32) * 0.75).astype(np.uint8)  # dim so the marks stand out

    def at(px: float, py: float) -> tuple[int, int]:
        return int(round((px - x0 + 0.5) * scale)), int(round((py - y0 + 0.5) * scale))

    for pts, color, radius in layers:
        for px, py in pts:
            cv2.circle(crop, at(px + cx, py + cy), radius, color, -1, cv2.LINE_AA)
    magenta = (255, 0, 255)
    for bx, by, bw, bh in scale_boxes:
        cv2.rectangle(crop, at(bx, by), at(bx + bw - 1, by + bh - 1), magenta, 1, cv2.LINE_AA)
    cv2.rectangle(crop, at(x, y), at(x + w - 1, y + h - 1), (255, 255, 255), 1, cv2.LINE_AA)
    legend = [("positive bag", (0, 200, 0)), ("negative bag", (0, 0, 255)),
              ("coarse grid", colors[0]), ("fine grid", colors[1])]
    if scale_boxes:
        legend.append(("scales", magenta))
    bar = np.full((22, crop.shape[1], 3), 32, np.uint8)
    xpos = 6
    for text, color in legend:
        cv2.circle(bar, (xpos + 4, 11), 4, color, -1, cv2.LINE_AA)
        cv2.putText(bar, text, (xpos + 12, 15), cv2.FONT_HERSHEY_SIMPLEX, 0.4, (230, 230, 230), 1,
                    cv2.LINE_AA)
        xpos += 22 + 7 * len(text)
    return np.concatenate([crop, bar], axis=0)
