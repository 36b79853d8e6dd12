"""Reliability: bad input gets a clear error, edge geometry stays inside the frame.

Every case below is one test. The cases that touch the compiled core run in a child
interpreter (one process for all of them, restarted after the case that crashed, if any),
so that a crash in the core fails that case instead of aborting the test run. The child
prints ``START <i>`` before case ``i`` and one JSON line after it; the parent turns those
into per-case verdicts. ``scripts/sanitize.sh python`` runs the same cases in a sanitized
interpreter through :func:`run_cases_in_process`.

Each case is ``(name, action, expected)``: the action builds its own frames (no data
files), and either returns ``None`` (all checks passed) or a message saying what was
wrong; ``expected`` is ``None`` (must succeed) or ``(exception type, regex of message)``.
"""

from __future__ import annotations

import json
import math
import os
import re
import subprocess
import sys
import tracemalloc
import warnings
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import wmiltrack
from wmiltrack.engine.features import min_box_size
from wmiltrack.engine.params import Params
from wmiltrack.engine.tracker import NotInitializedError

VARIANTS: list[str] = sorted(wmiltrack.variants())
HERE = Path(__file__).resolve().parent

Frame = np.ndarray
Box = tuple[float, float, float, float]
Check = Callable[[], "str | None"]


def _as_matrix(a: np.ndarray) -> np.ndarray:
    """``a`` as an ``np.matrix`` (numpy warns that the subclass is not recommended: users still
    hand them in)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PendingDeprecationWarning)
        return np.asmatrix(a)


# ------------------------------------------------------------------------------ scenes
def _blocky(rng: np.random.Generator, h: int, w: int, cell: int) -> np.ndarray:
    """Random blocks of ``cell`` pixels plus fine noise, as uint8 BGR."""
    gh, gw = -(-h // cell), -(-w // cell)
    blocks = rng.integers(0, 256, size=(gh, gw, 3)).astype(np.int16)
    img = np.repeat(np.repeat(blocks, cell, axis=0), cell, axis=1)[:h, :w]
    img = img + rng.integers(-12, 13, size=img.shape)
    return np.clip(img, 0, 255).astype(np.uint8)


def scene(path: Sequence[tuple[int, int]], target: tuple[int, int], size: tuple[int, int] = (120, 160),
          seed: int = 0) -> list[Frame]:
    """Frames of a textured ``target = (w, h)`` at top-left corners ``path`` over clutter.

    Parameters
    ----------
    path : sequence of (x, y)
        The target's top-left corner per frame; it may lie partly or wholly off the frame
        (the target is then cut or absent).
    target : (w, h)
        Target size in pixels.
    size : (h, w)
        Frame size.
    seed : int
        Seed of the textures.

    Returns
    -------
    list of (h, w, 3) uint8 arrays
    """
    rng = np.random.default_rng(seed)
    fh, fw = size
    tw, th = target
    background = _blocky(rng, fh, fw, 6)
    patch = _blocky(rng, th, tw, 3)
    patch[th // 3: th // 3 + max(th // 4, 1), :] = 250  # a bright band makes it distinctive
    frames = []
    for x, y in path:
        f = background.copy()
        x0, y0, x1, y1 = max(x, 0), max(y, 0), min(x + tw, fw), min(y + th, fh)
        if x1 > x0 and y1 > y0:
            f[y0:y1, x0:x1] = patch[y0 - y: y1 - y, x0 - x: x1 - x]
        frames.append(f)
    return frames


def linear_path(start: tuple[int, int], step: tuple[int, int], n: int) -> list[tuple[int, int]]:
    """``n`` corners from ``start`` moving by ``step`` per frame."""
    return [(start[0] + i * step[0], start[1] + i * step[1]) for i in range(n)]


def track_checked(tracker: wmiltrack.Tracker, frames: Sequence[Frame], box: Any) -> tuple[list[Box], str | None]:
    """Init on ``frames[0]`` and update on the rest, checking every result.

    Returns
    -------
    boxes : list of (x, y, w, h)
        The box after init and after each update.
    problem : str or None
        What was wrong (a box leaving the frame, a size change (for variants without scale
        search; outside the scale limits for those with it), a non-finite or out-of-range
        score), or ``None``.
    """
    fh, fw = frames[0].shape[:2]
    tracker.init(frames[0], box)
    boxes = [tracker.box]
    w0, h0 = tracker.box[2:]
    for i, frame in enumerate(frames[1:], start=1):
        r = tracker.update(frame)
        x, y, w, h = r.box
        boxes.append(r.box)
        if not all(math.isfinite(v) for v in r.box):
            return boxes, f"frame {i}: non-finite box {r.box}"
        if x < 0 or y < 0 or x + w > fw or y + h > fh:
            return boxes, f"frame {i}: box {r.box} outside the {fw}x{fh} frame"
        if tracker.params.scale_steps == 0 and (w, h) != (w0, h0):
            return boxes, f"frame {i}: box size changed from {(w0, h0)} to {(w, h)}"
        if tracker.params.scale_steps > 0 and not (
                tracker.params.scale_min * 0.9 <= w / w0 <= tracker.params.scale_max * 1.1
                and w >= 1 and h >= 1):
            return boxes, f"frame {i}: box size {(w, h)} outside the scale limits of {(w0, h0)}"
        if not (math.isfinite(r.score) and 0.0 <= r.score <= 1.0):
            return boxes, f"frame {i}: score {r.score} not in [0, 1]"
        # ok is the score against the threshold (or, with a judge, its verdict), except in
        # the lost state (score 0, ok False); with two experts, their judge's verdict alone
        lost = tracker.lost
        judge = tracker.parts.judge
        memory = tracker.params.judge_memory > 0  # (the judge's memory of the target)
        tracked = not judge.memory_lost if memory else r.score >= tracker.params.lost_threshold
        if tracker.parts.expert is not None:  # the experts' verdict: ok unless lost
            tracked = True
        # (the lost state's score is 0, except with a second expert: the judge's confidence)
        if r.ok != (tracked and not lost) or (lost and r.score and tracker.parts.expert is None):
            return boxes, f"frame {i}: ok={r.ok} disagrees with score {r.score} (lost: {lost})"
    return boxes, None


def _base_frames(n: int = 5, seed: int = 0) -> list[Frame]:
    return scene(linear_path((60, 40), (2, 1), n), (24, 20), seed=seed)


BASE_BOX: Box = (60.0, 40.0, 24.0, 20.0)


# ------------------------------------------------------------------------------ cases
@dataclass(frozen=True)
class Case:
    """One reliability case: ``action()`` returns ``None`` or what went wrong."""

    name: str
    action: Check
    raises: type[BaseException] | None = None
    match: str = ""


def _ok(variant: str, frames: Sequence[Frame], box: Any, *, expect_box: Box | None = None,
        **overrides: Any) -> Check:
    """Tracking must succeed and stay inside the frame (and start at ``expect_box``)."""
    def run() -> str | None:
        t = wmiltrack.Tracker(variant, seed=0, **overrides)
        boxes, problem = track_checked(t, frames, box)
        if problem is None and expect_box is not None and boxes[0] != expect_box:
            problem = f"init box {boxes[0]} != expected {expect_box}"
        return problem
    return run


def _init(variant: str, frame: Any, box: Any, **overrides: Any) -> Check:
    """``init`` alone (for the cases that must raise)."""
    def run() -> str | None:
        wmiltrack.Tracker(variant, seed=0, **overrides).init(frame, box)
        return None
    return run


def _same_boxes(variant: str, reference: Sequence[Frame], other: Sequence[Any], box: Any = BASE_BOX) -> Check:
    """Tracking on ``other`` gives exactly the boxes of tracking on ``reference``."""
    def run() -> str | None:
        want, problem = track_checked(wmiltrack.Tracker(variant, seed=0), reference, box)
        if problem:
            return f"reference run: {problem}"
        t = wmiltrack.Tracker(variant, seed=0)
        t.init(other[0], box)
        got = [t.box] + [t.update(f).box for f in other[1:]]
        return None if got == want else f"boxes differ: {got} != {want}"
    return run


def _make(variant: str, **overrides: Any) -> Check:
    def run() -> str | None:
        wmiltrack.Tracker(variant, **overrides)
        return None
    return run


def _box_cases() -> Iterator[Case]:
    """Boxes partly/wholly outside, empty, non-finite, too small, frame-sized; every variant."""
    frames = _base_frames()
    fh, fw = frames[0].shape[:2]
    huge = np.zeros((4100, 4200), np.uint8)  # 17.2 million pixels
    for v in VARIANTS:
        p = Params.for_variant(v)
        mw, mh = min_box_size(p)
        # partly outside: clipped, then tracked
        yield Case(f"{v}/box-partly-outside-top-left", _ok(v, frames, (-10, -6, 30, 26), expect_box=(0, 0, 20, 20)))
        yield Case(f"{v}/box-partly-outside-bottom-right",
                   _ok(v, frames, (fw - 14, fh - 12, 30, 30), expect_box=(fw - 14, fh - 12, 14, 12)))
        yield Case(f"{v}/box-larger-than-frame", _ok(v, frames, (-50, -50, 500, 500), expect_box=(0, 0, fw, fh)))
        yield Case(f"{v}/box-equals-frame", _ok(v, frames, (0, 0, fw, fh), expect_box=(0, 0, fw, fh)))
        yield Case(f"{v}/box-subpixel-rounded", _ok(v, frames, (60.4, 39.6, 23.8, 20.2), expect_box=(60, 40, 24, 20)))
        yield Case(f"{v}/box-numpy-array", _ok(v, frames, np.array(BASE_BOX), expect_box=BASE_BOX))
        yield Case(f"{v}/box-minimum-size", _ok(v, frames, (70, 50, mw, mh), expect_box=(70, 50, mw, mh)))
        # wholly outside
        for label, box in [("right", (fw + 5, 10, 20, 20)), ("left", (-40, 10, 20, 20)),
                           ("below", (10, fh, 20, 20)), ("above", (10, -20, 20, 20)),
                           ("touching-right-edge", (fw, 10, 20, 20)), ("far-away", (1e12, 1e12, 20, 20))]:
            yield Case(f"{v}/box-wholly-outside-{label}", _init(v, frames[0], box), ValueError, "wholly outside")
        # empty / negative / non-finite
        for label, box in [("zero-width", (10, 10, 0, 20)), ("zero-height", (10, 10, 20, 0)),
                           ("negative-width", (30, 10, -20, 20)), ("negative-height", (10, 30, 20, -5))]:
            yield Case(f"{v}/box-{label}", _init(v, frames[0], box), ValueError, "positive width and height")
        for label, box in [("nan-x", (math.nan, 10, 20, 20)), ("nan-w", (10, 10, math.nan, 20)),
                           ("inf-h", (10, 10, 20, math.inf)), ("neg-inf-y", (10, -math.inf, 20, 20))]:
            yield Case(f"{v}/box-{label}", _init(v, frames[0], box), ValueError, "NaN or infinite")
        # too small for the features: the message names the minimum
        yield Case(f"{v}/box-below-minimum", _init(v, frames[0], (70, 50, mw - 1, mh)), ValueError,
                   rf"needs at least {mw}x{mh}")
        yield Case(f"{v}/box-clipped-below-minimum", _init(v, frames[0], (fw - mw + 1, 10, 40, 40)), ValueError,
                   rf"after clipping.*needs at least {mw}x{mh}")
        yield Case(f"{v}/box-one-pixel", _init(v, frames[0], (10, 10, 1, 1)), ValueError, "needs at least")
        # too large for the core's exact 32-bit rectangle sums
        yield Case(f"{v}/box-beyond-32-bit-sums", _init(v, huge, (0, 0, 4200, 4100)), ValueError,
                   "sums in 32 bits")
    # not four numbers (variant-independent)
    for label, box in [("three-numbers", (1, 2, 3)), ("five-numbers", (1, 2, 3, 4, 5)), ("none", None),
                       ("string", "1234"), ("string-items", ("1", "2", "30", "40")), ("nested", ((1, 2), (3, 4))),
                       ("complex", (1j, 2, 3, 4)), ("dict", {"x": 1})]:
        yield Case(f"box-{label}", _init("rcwmil", frames[0], box), TypeError, "four numbers")


def _frame_cases() -> Iterator[Case]:
    """Frame dtypes, shapes, layouts, sizes and misuse."""
    frames = _base_frames()
    gray = [np.ascontiguousarray(f[..., 1]) for f in frames]
    for v in VARIANTS:  # every preset: the colour and correlation cues read frames through OpenCV
        # documented conversions: identical boxes
        yield Case(f"{v}/frame-uint16-in-range", _same_boxes(v, frames, [f.astype(np.uint16) for f in frames]))
        yield Case(f"{v}/frame-int64-in-range", _same_boxes(v, frames, [f.astype(np.int64) for f in frames]))
        yield Case(f"{v}/frame-float64-whole", _same_boxes(v, frames, [f.astype(np.float64) for f in frames]))
        yield Case(f"{v}/frame-float32-rounded",
                   _same_boxes(v, frames, [np.clip(f.astype(np.float32) + 0.3, 0, 255) for f in frames]))
        yield Case(f"{v}/frame-float16", _same_boxes(v, frames, [f.astype(np.float16) for f in frames]))
        bgra = [np.dstack([f, np.full(f.shape[:2], 7, np.uint8)]) for f in frames]
        yield Case(f"{v}/frame-bgra-alpha-ignored", _same_boxes(v, frames, bgra))
        yield Case(f"{v}/frame-gray-hw1", _same_boxes(v, gray, [g[:, :, None] for g in gray]))
        # layouts: identical boxes to the contiguous copy
        views: dict[str, list[np.ndarray]] = {
            "rows-reversed": [f[::-1] for f in frames],
            "cols-reversed": [f[:, ::-1] for f in frames],
            "channels-reversed": [f[..., ::-1] for f in frames],
            "every-other-pixel": [np.repeat(np.repeat(f, 2, 0), 2, 1)[::2, ::2] for f in frames],
            "crop-of-bigger": [np.pad(f, ((3, 4), (5, 6), (0, 0)))[3:-4, 5:-6] for f in frames],
            "fortran-order": [np.asfortranarray(f) for f in frames],
            "transposed": [np.ascontiguousarray(f.transpose(1, 0, 2)).transpose(1, 0, 2) for f in frames],
            "bgr-of-bgra": [b[..., :3] for b in bgra],
            "gray-broadcast-to-bgr": [np.broadcast_to(g[:, :, None], g.shape + (3,)) for g in gray],
            "read-only": [_readonly(f) for f in frames],
            "from-bytes": [np.frombuffer(f.tobytes(), np.uint8).reshape(f.shape) for f in frames],
            "gray-col-strided": [np.ascontiguousarray(f)[..., 1] for f in frames],
        }
        # gray frames: the colour cues read them as luma, through OpenCV
        views.update({
            "gray-fortran-order": [np.asfortranarray(g) for g in gray],
            "gray-transposed": [np.ascontiguousarray(g.T).T for g in gray],
            "gray-rows-reversed": [g[::-1] for g in gray],
            "gray-every-other-pixel": [np.repeat(np.repeat(g, 2, 0), 2, 1)[::2, ::2] for g in gray],
            "gray-np-matrix": [_as_matrix(g) for g in gray],
            "masked-array": [np.ma.masked_array(f, mask=False) for f in frames],
            "big-endian-uint16": [f.astype(">u2") for f in frames],
        })
        for label, view in views.items():
            copies = [np.ascontiguousarray(x) for x in view]
            yield Case(f"{v}/frame-{label}-same-as-copy", _same_boxes(v, copies, view))
    f0 = frames[0]
    bad: list[tuple[str, Any, type[BaseException], str]] = [
        ("list", f0.tolist(), TypeError, "numpy array"),
        ("1-d", f0.reshape(-1), ValueError, "H x W"),
        ("4-d", f0[None], ValueError, "H x W"),
        ("0-d", np.array(3, np.uint8), ValueError, "H x W"),
        ("2-channels", f0[..., :2], ValueError, "1, 3 .BGR. or 4 .BGRA. channels"),
        ("5-channels", np.dstack([f0, f0[..., :2]]), ValueError, "channels"),
        ("0-channels", f0[..., :0], ValueError, "channels"),
        ("zero-rows", f0[:0], ValueError, "empty"),
        ("zero-cols", f0[:, :0], ValueError, "empty"),
        ("bool", f0 > 128, TypeError, "dtype bool"),
        ("complex", f0.astype(np.complex64), TypeError, "not supported"),
        ("object", f0.astype(object), TypeError, "not supported"),
        ("uint16-above-255", f0.astype(np.uint16) * 4, ValueError, "8-bit scale"),
        ("int16-negative", f0.astype(np.int16) - 10, ValueError, "8-bit scale"),
        ("float-above-255", f0.astype(np.float32) * 1.5, ValueError, "0..255 scale"),
        ("float-negative", f0.astype(np.float64) - 1.0, ValueError, "0..255 scale"),
        ("float-nan", _poke(f0.astype(np.float64), math.nan), ValueError, "NaN or infinity"),
        ("float-inf", _poke(f0.astype(np.float32), math.inf), ValueError, "NaN or infinity"),
        ("float-unit-scale", f0.astype(np.float32) / 255.0, ValueError, "ambiguous"),
    ]
    for v in VARIANTS:
        for label, frame, exc, match in bad:
            yield Case(f"{v}/frame-{label}", _init(v, frame, BASE_BOX), exc, match)
    yield Case("frame-float-all-black-ok", _ok("rcwmil", [np.zeros((60, 80), np.float32)] * 3, (10, 10, 20, 20)))
    yield Case("update-before-init", _update_before_init, NotInitializedError, r"call init\(frame, box\)")
    yield Case("box-before-init", _box_before_init, NotInitializedError, "before update")
    yield Case("update-frame-size-changed", _update_other_size, ValueError, "frame size changed from 160x120 to 150x120")
    yield Case("update-bad-frame-then-good-frame", _bad_update_leaves_state)
    yield Case("init-bad-box-leaves-state", _bad_init_leaves_state)
    yield Case("reinit-on-new-size", _reinit_new_size)
    yield Case("update-gray-after-bgr-same-size", _gray_after_bgr)


def _poke(f: np.ndarray, value: float) -> np.ndarray:
    """``f`` with one pixel set to ``value``."""
    f[5, 7, 1] = value
    return f


def _readonly(f: np.ndarray) -> np.ndarray:
    g = f.copy()
    g.setflags(write=False)
    return g


def _update_before_init() -> str | None:
    wmiltrack.Tracker("rcwmil").update(_base_frames(1)[0])
    return None


def _box_before_init() -> str | None:
    _ = wmiltrack.Tracker("rcwmil").box
    return None


def _update_other_size() -> str | None:
    frames = _base_frames(2)
    t = wmiltrack.Tracker("rcwmil")
    t.init(frames[0], BASE_BOX)
    t.update(frames[1][:, :150])
    return None


def _reference_boxes(variant: str = "rcwmil") -> tuple[list[Frame], list[Box]]:
    frames = _base_frames()
    boxes, problem = track_checked(wmiltrack.Tracker(variant), frames, BASE_BOX)
    assert problem is None, problem
    return frames, boxes


def _bad_update_leaves_state() -> str | None:
    """A refused frame changes nothing: the next good frame gives the reference box."""
    frames, want = _reference_boxes()
    t = wmiltrack.Tracker("rcwmil")
    t.init(frames[0], BASE_BOX)
    got = [t.box]
    for f in frames[1:]:
        for bad in (f > 0, f[:, :-1], f.astype(np.float32) * 2, f[..., :2]):
            try:
                t.update(bad)
            except (TypeError, ValueError):
                pass
            else:
                return f"bad frame {bad.dtype} {bad.shape} was accepted"
        got.append(t.update(f).box)
    return None if got == want else f"boxes {got} != reference {want}"


def _bad_init_leaves_state() -> str | None:
    """A refused re-init leaves the running track untouched."""
    frames, want = _reference_boxes()
    t = wmiltrack.Tracker("rcwmil")
    t.init(frames[0], BASE_BOX)
    got = [t.box]
    for f in frames[1:]:
        for box in ((1000, 1000, 10, 10), (1, 1, 0, 5), (1, 1, 2, 2)):
            try:
                t.init(f, box)
            except ValueError:
                pass
            else:
                return f"bad box {box} was accepted"
        got.append(t.update(f).box)
    return None if got == want else f"boxes {got} != reference {want}"


def _reinit_new_size() -> str | None:
    t = wmiltrack.Tracker("rcwmil")
    _, problem = track_checked(t, _base_frames(3), BASE_BOX)
    if problem:
        return problem
    small = scene(linear_path((20, 15), (1, 1), 4), (16, 16), size=(60, 70), seed=3)
    _, problem = track_checked(t, small, (20, 15, 16, 16))
    return problem


def _gray_after_bgr() -> str | None:
    """Documented: frames may switch between BGR and gray of the same size (luma is used)."""
    frames = _base_frames()
    mixed = [f if i % 2 == 0 else np.ascontiguousarray(f[..., 0]) for i, f in enumerate(frames)]
    _, problem = track_checked(wmiltrack.Tracker("rcwmil"), mixed, BASE_BOX)
    return problem


def _param_cases() -> Iterator[Case]:
    """Unknown variants and parameters, values out of range."""
    yield Case("variant-unknown", _make("foo"), ValueError, "unknown variant 'foo'; choose one of")
    yield Case("variant-not-a-string", _make(3), ValueError, "unknown variant")  # type: ignore[arg-type]
    yield Case("variant-upper-case-ok", _make("RCWMIL"))
    yield Case("param-unknown-name", _make("rcwmil", radius=3), TypeError, "unknown parameter")
    yield Case("seed-negative", _make("rcwmil", seed=-1), ValueError, "seed")
    yield Case("seed-float", _make("rcwmil", seed=1.5), ValueError, "seed")
    yield Case("seed-bool", _make("rcwmil", seed=True), ValueError, "seed")
    for v in VARIANTS:
        m = Params.for_variant(v).num_features
        out_of_range: list[tuple[str, dict[str, Any], str]] = [
            ("pos-radius-negative", {"pos_radius": -1.0}, "pos_radius must be > 0"),
            ("pos-radius-zero", {"pos_radius": 0.0}, "pos_radius must be > 0"),
            ("pos-radius-inf", {"pos_radius": math.inf}, "finite"),
            ("pos-radius-huge", {"pos_radius": 1e5}, "pos_radius must be <="),
            ("neg-inner-negative", {"neg_inner": -2.0}, "neg_inner"),
            ("neg-outer-below-inner", {"neg_inner": 10.0, "neg_outer": 5.0}, "neg_inner < neg_outer"),
            ("neg-outer-huge", {"neg_outer": 1e6}, "neg_outer must be <="),
            ("init-pos-radius-inf", {"init_pos_radius": math.inf}, "init_pos_radius"),
            ("init-neg-outer-inf", {"init_neg_outer": math.inf}, "init_neg_outer"),
            ("init-pos-radius-negative", {"init_pos_radius": -3.0}, "init_pos_radius"),
            ("coarse-radius-zero", {"coarse_radius": 0}, "coarse_radius"),
            ("coarse-radius-negative", {"coarse_radius": -5}, "coarse_radius"),
            ("coarse-radius-huge", {"coarse_radius": 10**7}, "coarse_radius"),
            ("coarse-step-zero", {"coarse_step": 0}, "coarse_step"),
            ("fine-radius-negative", {"fine_radius": -1}, "fine_radius"),
            ("radius-not-int", {"coarse_radius": 2.5}, "must be an int"),
            ("k-above-m", {"num_selected": m + 1}, r"num_selected \(K\) must be in 1\.\."),
            ("k-zero", {"num_selected": 0}, r"num_selected \(K\)"),
            ("m-zero", {"num_features": 0, "num_selected": 0}, "num_features must be >= 1"),
            ("m-bool", {"num_features": True}, "must be an int"),
            ("lambda-one", {"learning_rate": 1.0}, r"learning_rate \(lambda\) must be in \[0, 1\)"),
            ("lambda-negative", {"learning_rate": -0.1}, "learning_rate"),
            ("lambda-above-one", {"learning_rate": 1.5}, "learning_rate"),
            ("lambda-nan", {"learning_rate": math.nan}, "learning_rate"),
            ("guard-zero", {"guard": 0.0}, "guard must be > 0"),
            ("sigma-floor-negative", {"sigma_floor": -1.0}, "sigma_floor"),
            ("lost-threshold-above-one", {"lost_threshold": 2.0}, "lost_threshold"),
            ("rects-min-above-max", {"rects_min": 5, "rects_max": 2}, "rects_min <= rects_max"),
            ("positive-prob-above-one", {"positive_prob": 1.5}, "positive_prob"),
            ("beta-min-zero", {"beta_min": 0.0}, "beta_min"),
            ("rect-bounds-inconsistent", {"rect_bounds": (0, 0, 5, 0)}, r"rect_bounds\[2\]"),
            ("rect-bounds-negative", {"rect_bounds": (-1, 4, 1, 2)}, "rect_bounds"),
            ("subregions-not-square", {"num_subregions": 3}, "num_subregions"),
            ("min-box-size-one", {"min_box_size": 1}, "min_box_size"),
            ("feature-kind-unknown", {"feature_kind": "sift"}, "feature_kind must be one of"),
            ("selection-unknown", {"selection": "best"}, "selection must be one of"),
        ]
        for label, kw, match in out_of_range:
            yield Case(f"{v}/param-{label}", _make(v, **kw), ValueError, match)
        yield Case(f"{v}/param-lambda-zero-ok", _ok(v, _base_frames(3), BASE_BOX, learning_rate=0.0))


def _geometry_cases() -> Iterator[Case]:
    """Targets at and leaving every border and corner, tiny and huge targets, tiny frames."""
    fh, fw = 120, 160
    t = (24, 20)
    starts: dict[str, tuple[tuple[int, int], tuple[int, int]]] = {
        # name: (start corner, motion per frame) -- every one ends partly or wholly outside
        "top-left-corner": ((0, 0), (-4, -3)),
        "top-right-corner": ((fw - t[0], 0), (4, -3)),
        "bottom-left-corner": ((0, fh - t[1]), (-4, 3)),
        "bottom-right-corner": ((fw - t[0], fh - t[1]), (4, 3)),
        "leaving-left": ((6, 50), (-6, 0)),
        "leaving-right": ((fw - t[0] - 6, 50), (6, 0)),
        "leaving-top": ((70, 5), (0, -5)),
        "leaving-bottom": ((70, fh - t[1] - 5), (0, 5)),
        "along-top-edge": ((0, 0), (7, 0)),
        "diagonal-through-frame": ((-10, -10), (15, 11)),
    }
    for v in VARIANTS:
        p = Params.for_variant(v)
        mw, _ = min_box_size(p)
        for label, (start, step) in starts.items():
            frames = scene(linear_path(start, step, 9), t, size=(fh, fw), seed=1)
            yield Case(f"{v}/geometry-{label}", _ok(v, frames, start + t))
        frames = scene(linear_path((70, 50), (3, -2), 6), (8, 8), seed=2)
        yield Case(f"{v}/geometry-tiny-8x8-target", _ok(v, frames, (70, 50, 8, 8)))
        frames = scene(linear_path((2, 2), (1, 1), 5), (fw - 4, fh - 4), seed=2)
        yield Case(f"{v}/geometry-huge-target", _ok(v, frames, (2, 2, fw - 4, fh - 4)))
        frames = scene(linear_path((6, 6), (1, 0), 5), (12, 12), size=(24, 26), seed=4)
        yield Case(f"{v}/geometry-frame-smaller-than-search-window", _ok(v, frames, (6, 6, 12, 12)))
        frames = scene([(0, 0)] * 4, (mw, mw), size=(mw, mw), seed=5)
        yield Case(f"{v}/geometry-frame-of-minimum-box-size", _ok(v, frames, (0, 0, mw, mw)))
        frames = scene(linear_path((0, 1), (1, 0), 5), (mw, mw), size=(mw + 2, 40), seed=6)
        yield Case(f"{v}/geometry-frame-one-strip", _ok(v, frames, (0, 1, mw, mw)))
        frames = [np.zeros((50, 60, 3), np.uint8)] * 4
        yield Case(f"{v}/geometry-blank-frames", _ok(v, frames, (20, 15, 16, 16)))
        frames = [np.full((50, 60), 255, np.uint8)] * 4
        yield Case(f"{v}/geometry-saturated-frames", _ok(v, frames, (20, 15, 16, 16)))


CASES: list[Case] = [*_box_cases(), *_frame_cases(), *_param_cases(), *_geometry_cases()]
_BY_NAME = {c.name: c for c in CASES}
assert len(_BY_NAME) == len(CASES), "case names must be unique"


# ------------------------------------------------------------------------------ running
def run_case(case: Case) -> dict[str, Any]:
    """Run one case and judge it.

    Returns
    -------
    dict
        ``name``; ``outcome`` (``"returned"`` or ``"raised"``); ``exception`` and
        ``message`` when it raised; ``verdict``: ``None`` when the case behaved as
        expected, else what was wrong.
    """
    out: dict[str, Any] = {"name": case.name}
    try:
        problem = case.action()
    except Exception as exc:  # noqa: BLE001 - every exception is judged below
        out.update(outcome="raised", exception=type(exc).__name__, message=str(exc))
        if case.raises is None:
            out["verdict"] = f"unexpected {type(exc).__name__}: {exc}"
        elif not isinstance(exc, case.raises):
            out["verdict"] = f"raised {type(exc).__name__} ({exc}), expected {case.raises.__name__}"
        elif not re.search(case.match, str(exc)):
            out["verdict"] = f"message {str(exc)!r} does not match {case.match!r}"
        else:
            out["verdict"] = None
        return out
    out["outcome"] = "returned"
    if case.raises is not None:
        out["verdict"] = f"no exception; expected {case.raises.__name__} matching {case.match!r}"
    else:
        out["verdict"] = problem
    return out


def run_cases_in_process(start: int = 0, stream: Any = None) -> list[dict[str, Any]]:
    """Run ``CASES[start:]`` here, printing ``START i`` / a JSON line per case to ``stream``."""
    results = []
    for i in range(start, len(CASES)):
        if stream is not None:
            print(f"START {i}", file=stream, flush=True)
        r = run_case(CASES[i])
        results.append(r)
        if stream is not None:
            print("RESULT " + json.dumps(r), file=stream, flush=True)
    return results


def _child_main() -> None:  # pragma: no cover - runs in the child interpreter
    run_cases_in_process(int(sys.argv[1]), sys.stdout)


def run_cases_isolated() -> dict[str, dict[str, Any]]:
    """Run every case in child interpreters; a crash fails only the case that crashed."""
    results: dict[str, dict[str, Any]] = {}
    start = 0
    code = (f"import sys; sys.path.insert(0, {str(HERE)!r}); "
            "import test_reliability as m; m._child_main()")
    env = dict(os.environ, PYTHONFAULTHANDLER="1")
    while start < len(CASES):
        proc = subprocess.run([sys.executable, "-c", code, str(start)], capture_output=True, text=True,
                              env=env, timeout=600)
        last = start - 1
        for line in proc.stdout.splitlines():
            if line.startswith("START "):
                last = int(line.split()[1])
            elif line.startswith("RESULT "):
                r = json.loads(line[len("RESULT "):])
                results[r["name"]] = r
        if proc.returncode == 0 and len(results) == len(CASES):
            break
        if last < start or CASES[last].name in results:
            raise RuntimeError(f"child failed outside a case (rc {proc.returncode}):\n{proc.stderr[-3000:]}")
        results[CASES[last].name] = {
            "name": CASES[last].name, "outcome": "crashed",
            "verdict": f"child interpreter died (return code {proc.returncode}):\n{proc.stderr[-3000:]}",
        }
        start = last + 1
    return results


@pytest.fixture(scope="module")
def isolated_results(nano_network: dict[str, tuple[Path, Path]]) -> dict[str, dict[str, Any]]:
    """Every case's result; rcwmil-nano's on NanoTrack's files when they are there, else on
    the stand-in networks (conftest's ``nano_network``), through the environment the child
    interpreters inherit."""
    from conftest import nano_files_in_environment  # (here: the child interpreters import this module alone)

    with nano_files_in_environment(nano_network["v3"]):
        return run_cases_isolated()


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_case(case: Case, isolated_results: dict[str, dict[str, Any]]) -> None:
    result = isolated_results[case.name]
    assert result["verdict"] is None, result["verdict"]


def test_cases_cover_every_variant() -> None:
    for v in VARIANTS:
        names = [c.name for c in CASES if c.name.startswith(v + "/")]
        assert any("box-wholly-outside" in n for n in names)
        assert any("geometry-" in n for n in names)
        assert any("param-" in n for n in names)


def test_isolation_survives_a_crash(monkeypatch: pytest.MonkeyPatch) -> None:
    """The runner itself: a case that kills its interpreter fails alone, the rest still run."""
    stand_in = [Case("fine", lambda: None), Case("crash", lambda: None), Case("fine-2", lambda: None)]
    monkeypatch.setattr(sys.modules[__name__], "CASES", stand_in)
    # The child would re-import this module (with the real CASES): run a tiny stand-in whose
    # second case aborts the interpreter, as a crash in the core would.
    child = (
        "import os, sys, json\n"
        "start = int(sys.argv[1])\n"
        "names = ['fine', 'crash', 'fine-2']\n"
        "for i in range(start, 3):\n"
        "    print('START', i, flush=True)\n"
        "    if names[i] == 'crash': os.abort()\n"
        "    print('RESULT ' + json.dumps({'name': names[i], 'verdict': None}), flush=True)\n"
    )
    real_run = subprocess.run

    def fake_run(cmd: list[str], **kw: Any) -> subprocess.CompletedProcess[str]:
        return real_run([cmd[0], "-c", child, cmd[-1]], **kw)

    monkeypatch.setattr(subprocess, "run", fake_run)
    results = run_cases_isolated()
    assert results["fine"]["verdict"] is None and results["fine-2"]["verdict"] is None
    assert results["crash"]["outcome"] == "crashed"


# ------------------------------------------------------------------------------ re-init memory
def _rss_kib() -> int:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") // 1024


@pytest.mark.skipif(not Path("/proc/self/statm").exists(), reason="needs /proc")
def test_reinit_many_times_does_not_grow() -> None:
    """200 re-inits (+ one update each) of one tracker: Python heap and RSS stay flat.

    The warm-up is long: the interpreter's and numpy's own caches keep growing, more slowly
    each time, over the first several hundred re-inits (in one process, 200 re-inits after 20
    grew the heap by 220-390 KiB, 200 after 1000 by 70-100 KiB; 1000 and 2000 re-inits in all,
    819 and 892 KiB: bounded), while a leak grows by the same amount every time."""
    frames = _base_frames(2)
    t = wmiltrack.Tracker("rcwmil")
    for _ in range(1000):  # warm-up: buffers and caches reach their steady size
        t.init(frames[0], BASE_BOX)
        t.update(frames[1])
    tracemalloc.start()
    try:
        py0, rss0 = tracemalloc.get_traced_memory()[0], _rss_kib()
        for i in range(200):
            t.init(frames[i % 2], BASE_BOX)
            t.update(frames[1 - i % 2])
        py1, rss1 = tracemalloc.get_traced_memory()[0], _rss_kib()
    finally:
        tracemalloc.stop()
    assert py1 - py0 < 256 * 1024, f"Python heap grew by {(py1 - py0) / 1024:.0f} KiB over 200 re-inits"
    assert rss1 - rss0 < 8 * 1024, f"RSS grew by {rss1 - rss0} KiB over 200 re-inits"
