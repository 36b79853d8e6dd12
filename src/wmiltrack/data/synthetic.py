"""Generated tracking sequences with exact ground truth, so demos and tests need no downloads.

A textured target moves on a smooth random path over a cluttered textured background.
Optional nuisances: a bar sliding over part of the target (occlusion), a global brightness
ramp plus a moving shadow band (illumination), and moving distractor patches (clutter).
Every frame gets Gaussian noise. The result is a :class:`wmiltrack.data.sequences.Sequence` backed
by in-memory BGR ``uint8`` frames whose ground truth is the exact ``(x, y, w, h)`` of the
rendered target (sub-pixel positions are rendered with bilinear interpolation).

Each ingredient draws from its own random stream derived from ``seed``, so switching one
nuisance on or off leaves everything else (path, textures, noise) unchanged.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import cv2
import numpy as np
from numpy.typing import NDArray

from .sequences import Sequence

__all__ = ["PRESETS", "make_preset", "make_sequence"]

F32 = NDArray[np.float32]
F64 = NDArray[np.float64]

PRESETS: dict[str, dict[str, Any]] = {
    "easy": {
        "occlusion": False,
        "illumination": False,
        "clutter": False,
        "max_speed": 2.0,
        "noise": 2.0,
    },
    "occlusion": {"occlusion": True, "illumination": False, "clutter": False},
    "illumination": {"occlusion": False, "illumination": True, "clutter": False},
    "clutter": {"occlusion": False, "illumination": False, "clutter": True},
    "fast": {"occlusion": False, "illumination": False, "clutter": False, "max_speed": 8.0},
    "all": {"occlusion": True, "illumination": True, "clutter": True},
}
"""Keyword arguments of :func:`make_sequence` for named scenarios; ``"all"`` is the demo one."""

_N_DISTRACTORS = 3
_STREAMS = ("background", "target", "path", "occlusion", "illumination", "clutter", "noise",
            "hidden")  # (a new stream goes last: the others keep their seeds)


# ---------------------------------------------------------------------- textures
def _octave_noise(
    rng: np.random.Generator, h: int, w: int, cells: list[float], weights: list[float]
) -> F32:
    """Sum of bicubic-upsampled random grids (``cells``: grid spacings in pixels), in [0, 1]."""
    out = np.zeros((h, w), np.float32)
    for cell, weight in zip(cells, weights):
        gh = max(2, math.ceil(h / cell) + 2)
        gw = max(2, math.ceil(w / cell) + 2)
        grid = rng.random((gh, gw), dtype=np.float32)
        big = cv2.resize(grid, (round(gw * cell), round(gh * cell)), interpolation=cv2.INTER_CUBIC)
        out += weight * big[:h, :w]
    return _normalize(out)


def _normalize(img: NDArray[Any]) -> F32:
    """Stretch to [0, 1] as float32."""
    lo, hi = float(img.min()), float(img.max())
    return np.asarray((img - lo) / max(hi - lo, 1e-6), dtype=np.float32)


def _shapes(rng: np.random.Generator, img: F32, count: int, size: float) -> None:
    """Draw ``count`` random filled rectangles/ellipses of gray level in [0, 1] onto ``img``."""
    h, w = img.shape
    for _ in range(count):
        cx, cy = int(rng.integers(0, w)), int(rng.integers(0, h))
        a = max(1, int(size * rng.uniform(0.3, 1.0)))
        b = max(1, int(size * rng.uniform(0.3, 1.0)))
        level = float(rng.random())
        if rng.random() < 0.5:
            cv2.rectangle(img, (cx - a, cy - b), (cx + a, cy + b), level, -1)
        else:
            angle = float(rng.uniform(0, 180))
            cv2.ellipse(img, (cx, cy), (a, b), angle, 0, 360, level, -1, cv2.LINE_AA)


def _colorize(gray: F32, c0: F64, c1: F64, rng: np.random.Generator, jitter: float) -> F32:
    """Blend two BGR colors by ``gray`` and add a little independent per-channel texture."""
    h, w = gray.shape
    g = gray[:, :, None]
    img = (1.0 - g) * c0.astype(np.float32) + g * c1.astype(np.float32)
    if jitter > 0:
        extra = _octave_noise(rng, h, w, [max(2.0, min(h, w) / 6)], [1.0]) - 0.5
        tint = rng.uniform(-1, 1, 3).astype(np.float32) * jitter
        img += extra[:, :, None] * tint
    return np.asarray(np.clip(img, 0, 255), dtype=np.float32)


def _target_texture(rng: np.random.Generator, w: int, h: int) -> F32:
    """Strongly structured object texture: blobs + shapes + grain, two-color palette."""
    gray = _octave_noise(rng, h, w, [max(3.0, min(w, h) / 3), 5.0, 2.0], [1.0, 0.6, 0.25])
    _shapes(rng, gray, count=int(rng.integers(3, 6)), size=min(w, h) / 4)
    gray = _normalize(cv2.GaussianBlur(gray, (0, 0), 0.7))
    c0 = rng.uniform(10, 110, 3)
    c1 = rng.uniform(150, 250, 3)
    return _colorize(gray, c0, c1, rng, jitter=40.0)


def _background_texture(rng: np.random.Generator, h: int, w: int) -> F32:
    """Cluttered scene texture: large soft regions, medium blobs, lines, fine grain."""
    gray = _octave_noise(rng, h, w, [80.0, 24.0, 7.0, 2.5], [1.0, 0.7, 0.35, 0.15])
    _shapes(rng, gray, count=max(4, h * w // 6000), size=min(h, w) / 12)
    for _ in range(max(3, (h + w) // 80)):
        p0 = (int(rng.integers(0, w)), int(rng.integers(0, h)))
        p1 = (int(rng.integers(0, w)), int(rng.integers(0, h)))
        cv2.line(gray, p0, p1, float(rng.random()), int(rng.integers(1, 4)), cv2.LINE_AA)
    gray = _normalize(cv2.GaussianBlur(gray, (0, 0), 1.0))
    c0 = rng.uniform(20, 90, 3)
    c1 = rng.uniform(140, 230, 3)
    return _colorize(gray, c0, c1, rng, jitter=60.0)


def _occluder_texture(rng: np.random.Generator, h: int, w: int) -> F32:
    """Dark striped bar with some grain, clearly not the target."""
    xs = np.arange(w, dtype=np.float32)
    period = float(rng.uniform(5, 9))
    stripes = 0.5 + 0.5 * np.sin(2 * np.pi * xs / period)
    gray = np.repeat(stripes[None, :], h, axis=0) * 0.6
    gray += 0.4 * _octave_noise(rng, h, w, [4.0], [1.0])
    c0 = rng.uniform(15, 40, 3)
    c1 = rng.uniform(70, 120, 3)
    return _colorize(gray.astype(np.float32), c0, c1, rng, jitter=0.0)


# ---------------------------------------------------------------------- motion
def _path(
    rng: np.random.Generator,
    n: int,
    lo: F64,
    hi: F64,
    max_speed: float,
) -> F64:
    """Smooth random path: bounded acceleration, speed <= max_speed, bounces off [lo, hi]."""
    pos = np.empty((n, 2), np.float64)
    p = lo + (hi - lo) * rng.uniform(0.25, 0.75, 2)
    angle = rng.uniform(0, 2 * np.pi)
    v = 0.6 * max_speed * np.array([np.cos(angle), np.sin(angle)])
    accel = 0.2 * max_speed
    for t in range(n):
        pos[t] = p
        a = rng.normal(0.0, accel / 2, 2)
        norm_a = float(np.hypot(*a))
        if norm_a > accel:
            a *= accel / norm_a
        v = v + a
        speed = float(np.hypot(*v))
        if speed > max_speed:
            v *= max_speed / speed
        q = p + v
        for k in range(2):
            # reflect off the walls: the displacement never exceeds |v| per axis
            for _ in range(4):
                if q[k] < lo[k]:
                    q[k] = 2 * lo[k] - q[k]
                    v[k] = -v[k]
                elif q[k] > hi[k]:
                    q[k] = 2 * hi[k] - q[k]
                    v[k] = -v[k]
                else:
                    break
            q[k] = min(max(q[k], lo[k]), hi[k])
        p = q
    return pos


def _paste(frame: F32, patch: F32, alpha: F32, x: float, y: float) -> None:
    """Alpha-composite ``patch`` with its top-left corner at sub-pixel ``(x, y)``.

    ``frame`` must have room for ``patch`` plus one pixel right and below.
    """
    ph, pw = patch.shape[:2]
    ix, iy = math.floor(x), math.floor(y)
    m = np.array([[1.0, 0.0, x - ix], [0.0, 1.0, y - iy]], np.float64)
    size = (pw + 1, ph + 1)
    warped = cv2.warpAffine(patch, m, size, flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT)
    a = cv2.warpAffine(alpha, m, size, flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT)
    roi = frame[iy : iy + ph + 1, ix : ix + pw + 1]
    roi *= 1.0 - a[:, :, None]
    roi += warped  # premultiplied: the patch fades to 0 exactly where alpha does


def _smoothstep_curve(u: F64, knots_u: list[float], knots_v: list[float]) -> F64:
    """Piecewise cosine interpolation through (knots_u, knots_v)."""
    out = np.empty_like(u)
    for i, ui in enumerate(u):
        k = int(np.searchsorted(knots_u, ui, side="right")) - 1
        k = min(max(k, 0), len(knots_u) - 2)
        s = (ui - knots_u[k]) / (knots_u[k + 1] - knots_u[k])
        s = 0.5 - 0.5 * math.cos(math.pi * min(max(s, 0.0), 1.0))
        out[i] = knots_v[k] + (knots_v[k + 1] - knots_v[k]) * s
    return out


def _occlusion_schedule(rng: np.random.Generator, n: int) -> tuple[F64, str]:
    """Nominal covered fraction of the target per frame (trapezoid) and the side it comes from."""
    frac = np.zeros(n, np.float64)
    side = str(rng.choice(["left", "right", "top", "bottom"]))
    peak = float(rng.uniform(0.4, 0.5))
    length = max(3, round(0.2 * n))
    if n < 6 or length >= n:
        return frac, side
    lo = max(1, round(0.25 * n))
    hi = max(lo + 1, min(round(0.55 * n), n - length))
    t0 = int(rng.integers(lo, hi))
    ramp = max(1.0, length / 3)
    for t in range(t0, min(n, t0 + length)):
        frac[t] = peak * min(1.0, (t - t0 + 1) / ramp, (t0 + length - t) / ramp)
    return frac, side


def _occluder_rect(
    x: float, y: float, w: int, h: int, c: float, side: str, width: int, height: int
) -> tuple[int, int, int, int]:
    """Integer rectangle [x0, x1) x [y0, y1) covering fraction ``c`` of the box from ``side``."""
    if side in ("left", "right"):
        y0, y1 = math.floor(y - 0.15 * h), math.ceil(y + 1.15 * h)
        if side == "right":
            x0, x1 = round(x + w * (1 - c)), math.ceil(x + w + 0.4 * w)
        else:
            x0, x1 = math.floor(x - 0.4 * w), round(x + w * c)
    else:
        x0, x1 = math.floor(x - 0.15 * w), math.ceil(x + 1.15 * w)
        if side == "bottom":
            y0, y1 = round(y + h * (1 - c)), math.ceil(y + h + 0.4 * h)
        else:
            y0, y1 = math.floor(y - 0.4 * h), round(y + h * c)
    return max(0, x0), max(0, y0), min(width, x1), min(height, y1)


def _overlap_fraction(
    rect: tuple[int, int, int, int], box: tuple[float, float, float, float]
) -> float:
    x0, y0, x1, y1 = rect
    bx, by, bw, bh = box
    ow = max(0.0, min(x1, bx + bw) - max(x0, bx))
    oh = max(0.0, min(y1, by + bh) - max(y0, by))
    return ow * oh / (bw * bh)


# ---------------------------------------------------------------------- public API
def make_sequence(
    n_frames: int = 150,
    *,
    size: tuple[int, int] = (240, 320),
    target_size: tuple[int, int] = (48, 40),
    seed: int = 0,
    occlusion: bool = True,
    illumination: bool = True,
    clutter: bool = True,
    max_speed: float = 3.0,
    noise: float = 4.0,
    full_occlusion: tuple[int, int] | None = None,
    out_of_view: tuple[int, int] | None = None,
    name: str | None = None,
) -> Sequence:
    """Generate a synthetic tracking sequence with exact ground truth.

    Parameters
    ----------
    n_frames:
        Number of frames (>= 1).
    size:
        Frame ``(height, width)``.
    target_size:
        Target ``(width, height)`` in pixels; constant over the sequence.
    seed:
        Random seed; the same arguments always give identical frames.
    occlusion:
        Slide a striped bar over up to ~50 % of the target during about a fifth of the frames
        (somewhere between 25 % and 75 % of the sequence).
    illumination:
        Global gain ramp 1.0 -> 0.6 -> 1.3 -> 1.05 with a small offset, and a soft shadow band
        sweeping across the frame from left to right.
    clutter:
        Three moving distractor patches (textures from the same family as the target, but
        different), drawn behind the target.
    max_speed:
        Upper bound of the target's displacement per frame, in pixels.
    noise:
        Standard deviation of the per-frame Gaussian pixel noise (0 for none).
    full_occlusion:
        ``(first, count)``: frames ``first .. first + count - 1`` (0-based) have the target
        wholly hidden behind an opaque textured block a quarter larger than its box on every
        side; the ground truth keeps the target's box there.
    out_of_view:
        ``(first, count)``: the target is out of the picture in those frames (not drawn; its
        ground truth is ``NaN``, an absent frame) and comes back where its path has taken it.
    name:
        Sequence name; default ``"synthetic-s<seed>"``.

    Returns
    -------
    wmiltrack.data.sequences.Sequence
        In-memory BGR ``uint8`` frames, ``groundtruth`` of shape ``(n_frames, 4)`` (float
        ``x, y, w, h``; the box always lies inside the frame; ``NaN`` rows for ``out_of_view``),
        ``fps`` 30 and ``meta`` with per-frame arrays ``"visible"`` (the target can be seen:
        False while fully occluded or out of view), ``"occlusion"`` (fraction of the target
        box covered), ``"gain"``
        (global illumination gain) and ``"distractors"`` (``(n_frames, k, 4)`` boxes), plus
        the generation arguments under ``"params"``.

    Raises
    ------
    ValueError
        For a non-positive frame count, a target that does not fit the frame, or negative
        speed/noise.
    """
    height, width = (int(v) for v in size)
    tw, th = (int(v) for v in target_size)
    _check_arguments(n_frames, width, height, tw, th, max_speed, noise, target_size)
    streams = dict(
        zip(
            _STREAMS,
            (np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(len(_STREAMS))),
        )
    )
    scene = _scene(streams, n_frames, (width, height), (tw, th), float(max_speed), clutter,
                   illumination, full_occlusion, _hidden_frames(n_frames, full_occlusion,
                                                                out_of_view))
    frames: list[NDArray[np.uint8]] = []
    covered = np.zeros(n_frames, np.float64)
    for t in range(n_frames):
        f, covered[t] = _draw(scene, t, occlusion)
        frames.append(_finish(f, scene.light, t, streams["noise"], noise))
    gt = np.column_stack([scene.path, np.full(n_frames, float(tw)), np.full(n_frames, float(th))])
    gt[scene.hidden == "out"] = np.nan
    meta: dict[str, Any] = {
        "visible": scene.hidden == "",
        "occlusion": covered,
        "gain": np.asarray(scene.light.gain, np.float64),
        "distractors": scene.dboxes,
        "params": {
            "n_frames": n_frames, "size": (height, width), "target_size": (tw, th), "seed": seed,
            "occlusion": occlusion, "illumination": illumination, "clutter": clutter,
            "max_speed": max_speed, "noise": noise, "full_occlusion": full_occlusion,
            "out_of_view": out_of_view,
        },
    }
    return Sequence(name=name if name is not None else f"synthetic-s{seed}", groundtruth=gt,
                    fps=30.0, frames=frames, meta=meta)


class _Scene(NamedTuple):
    """Everything a sequence's frames are drawn from, made once from the generation streams."""

    size: tuple[int, int]  # (width, height)
    target_size: tuple[int, int]  # (w, h)
    background: F32
    target: F32
    path: F64
    distractors: list[Any]
    dboxes: NDArray[np.float64]
    hidden: NDArray[np.str_]
    occ_frac: F64
    occ_side: str
    occ_tex: F32
    light: _Lighting
    block: F32 | None


def _scene(streams: dict[str, np.random.Generator], n_frames: int, size: tuple[int, int],
           target_size: tuple[int, int], max_speed: float, clutter: bool, illumination: bool,
           full_occlusion: tuple[int, int] | None, hidden: NDArray[np.str_]) -> _Scene:
    """The sequence's layers: background, target, its path, distractors, the occluder's schedule
    and texture, the lighting and the full occlusion's block (each from its own stream)."""
    width, height = size
    tw, th = target_size
    background = _background_texture(streams["background"], height, width)
    target = _target_texture(streams["target"], tw, th)
    # the pasted patch needs one spare pixel right/below; keep a 1 px margin on the other sides
    lo = np.array([1.0, 1.0])
    hi = np.array([width - tw - 2.0, height - th - 2.0])
    path = _path(streams["path"], n_frames, lo, hi, max_speed)
    distractors, dboxes = _distractors(streams["clutter"], n_frames, width, height, tw, th,
                                       max_speed) if clutter else ([], np.zeros((n_frames, 0, 4)))
    occ_frac, occ_side = _occlusion_schedule(streams["occlusion"], n_frames)
    occ_tex = _occluder_texture(streams["occlusion"], height, width)
    light = _Lighting(streams["illumination"], n_frames, width, illumination)
    block = (_target_texture(streams["hidden"], height, width) * np.float32(0.5)
             if full_occlusion is not None else None)  # a texture unlike the target's
    return _Scene(size, target_size, background, target, path, distractors, dboxes, hidden,
                  occ_frac, occ_side, occ_tex, light, block)


def _draw(scene: _Scene, t: int, occlusion: bool) -> tuple[F32, float]:
    """Frame ``t`` before lighting and noise, and the fraction of the target's box covered."""
    (width, height), (tw, th) = scene.size, scene.target_size
    f = scene.background.copy()
    for tex, alpha, dpath in scene.distractors:
        _paste(f, tex, alpha, float(dpath[t, 0]), float(dpath[t, 1]))
    x, y = float(scene.path[t, 0]), float(scene.path[t, 1])
    hidden = scene.hidden[t]
    if hidden != "out":
        _paste(f, scene.target, np.ones((th, tw), np.float32), x, y)
    if hidden == "occluded":
        assert scene.block is not None
        x0, y0 = max(int(x - 0.25 * tw), 0), max(int(y - 0.25 * th), 0)
        x1, y1 = min(int(x + 1.25 * tw) + 1, width), min(int(y + 1.25 * th) + 1, height)
        f[y0:y1, x0:x1] = scene.block[y0:y1, x0:x1]
        return f, 1.0
    if occlusion and scene.occ_frac[t] > 0:
        x0, y0, x1, y1 = _occluder_rect(x, y, tw, th, float(scene.occ_frac[t]), scene.occ_side,
                                        width, height)
        if x1 > x0 and y1 > y0:
            f[y0:y1, x0:x1] = scene.occ_tex[y0:y1, x0:x1]
            return f, _overlap_fraction((x0, y0, x1, y1), (x, y, float(tw), float(th)))
    return f, 0.0


def _check_arguments(n_frames: int, width: int, height: int, tw: int, th: int, max_speed: float,
                     noise: float, target_size: tuple[int, int]) -> None:
    if n_frames < 1:
        raise ValueError(f"n_frames must be >= 1, got {n_frames}")
    if tw < 4 or th < 4:
        raise ValueError(f"target_size must be at least 4x4, got {target_size}")
    if width < tw + 8 or height < th + 8:
        raise ValueError(f"target {tw}x{th} does not fit a {width}x{height} frame with margin")
    if max_speed < 0 or noise < 0:
        raise ValueError("max_speed and noise must be >= 0")


def _hidden_frames(n_frames: int, full_occlusion: tuple[int, int] | None,
                   out_of_view: tuple[int, int] | None) -> NDArray[np.str_]:
    """Per frame: ``"occluded"``, ``"out"`` (of view) or ``""`` (visible); ``ValueError`` for a
    window that is empty, starts on the first frame (the tracker starts there) or overlaps the
    other."""
    hidden = np.full(n_frames, "", dtype="<U8")
    for label, window in (("occluded", full_occlusion), ("out", out_of_view)):
        if window is None:
            continue
        first, count = (int(v) for v in window)
        if first < 1 or count < 1 or first + count > n_frames:
            raise ValueError(f"{'full_occlusion' if label == 'occluded' else 'out_of_view'} must be "
                             f"(first >= 1, count >= 1) within {n_frames} frames, got {window!r}")
        if np.any(hidden[first:first + count] != ""):
            raise ValueError("full_occlusion and out_of_view must not overlap")
        hidden[first:first + count] = label
    return hidden


def _distractors(rng: np.random.Generator, n_frames: int, width: int, height: int, tw: int, th: int,
                 max_speed: float) -> tuple[list[tuple[F32, F32, F64]], F64]:
    """Moving patches of the target's texture family: (texture, alpha, path) each, and their
    boxes ``(n_frames, k, 4)``."""
    distractors: list[tuple[F32, F32, F64]] = []
    dboxes = np.zeros((n_frames, _N_DISTRACTORS, 4), np.float64)
    for k in range(_N_DISTRACTORS):
        dw = int(min(width - 8, max(6, round(tw * rng.uniform(0.7, 1.2)))))
        dh = int(min(height - 8, max(6, round(th * rng.uniform(0.7, 1.2)))))
        tex = _target_texture(rng, dw, dh)
        speed = max(0.5, max_speed * rng.uniform(0.5, 1.0))
        dpath = _path(rng, n_frames, np.array([1.0, 1.0]),
                      np.array([width - dw - 2.0, height - dh - 2.0]), speed)
        distractors.append((tex, np.ones((dh, dw), np.float32), dpath))
        dboxes[:, k, :2] = dpath
        dboxes[:, k, 2:] = (dw, dh)
    return distractors, dboxes


class _Lighting:
    """A global gain ramp 1.0 -> 0.6 -> 1.3 -> 1.05 with a small offset, and a soft shadow band
    sweeping across the frame from left to right (or none)."""

    def __init__(self, rng: np.random.Generator, n_frames: int, width: int, on: bool) -> None:
        self.on = on
        u = np.linspace(0.0, 1.0, n_frames) if n_frames > 1 else np.zeros(1)
        if not on:
            self.gain = np.ones(n_frames)
            return
        self.gain = _smoothstep_curve(u, [0.0, 0.3, 0.7, 1.0], [1.0, 0.6, 1.3, 1.05])
        offset = 6.0 * np.sin(2 * np.pi * u + rng.uniform(0, 2 * np.pi))
        self.offset = offset - offset[0]
        self.xs = np.arange(width, dtype=np.float64)
        self.band = rng.uniform(0.12, 0.2) * width
        self.depth = rng.uniform(0.3, 0.45)
        self.centers = -0.3 * width + u * 1.6 * width

    def apply(self, f: F32, t: int) -> None:
        """Light frame ``t`` in place (with the 0.5 that rounds the uint8 conversion)."""
        if not self.on:
            f += np.float32(0.5)
            return
        shade = 1.0 - self.depth * np.exp(-(((self.xs - self.centers[t]) / self.band) ** 2))
        f *= (self.gain[t] * shade).astype(np.float32)[None, :, None]
        f += np.float32(self.offset[t] + 0.5)


def _finish(f: F32, light: _Lighting, t: int, rng: np.random.Generator, noise: float
            ) -> NDArray[np.uint8]:
    """Frame ``t`` lit, with sensor noise, as uint8."""
    light.apply(f, t)
    if noise > 0:
        f += rng.standard_normal(f.shape, dtype=np.float32) * np.float32(noise)
    np.clip(f, 0, 255, out=f)
    return f.astype(np.uint8)


def make_preset(preset: str, /, seed: int = 0, n_frames: int = 150, **overrides: Any) -> Sequence:
    """Generate the named scenario from :data:`PRESETS`.

    Parameters
    ----------
    preset:
        One of ``PRESETS`` (``"easy"``, ``"occlusion"``, ``"illumination"``, ``"clutter"``,
        ``"fast"``, ``"all"``).
    seed:
        Random seed.
    n_frames:
        Number of frames.
    **overrides:
        Further :func:`make_sequence` keyword arguments, applied over the preset.

    Returns
    -------
    wmiltrack.data.sequences.Sequence
        Named ``"synthetic-<preset>-s<seed>"`` unless ``name`` is given in ``overrides``.

    Raises
    ------
    ValueError
        If the preset is unknown.
    """
    if preset not in PRESETS:
        raise ValueError(f"unknown preset {preset!r}; choose from {', '.join(PRESETS)}")
    kwargs: dict[str, Any] = {**PRESETS[preset], **overrides}
    kwargs.setdefault("name", f"synthetic-{preset}-s{seed}")
    return make_sequence(n_frames, seed=seed, **kwargs)
