"""Illumination-change options (off in every preset): the log-luma and |gx|, |gy| channels,
zero-DC features and the first-frame anchor of the target model."""

from __future__ import annotations

import math

import numpy as np
import pytest

import wmiltrack
from wmiltrack import _core
from wmiltrack.engine.features import make_bank, scale_bank, zero_dc_bank


def _frame(seed: int = 0, lo: int = 0, hi: int = 256) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return rng.integers(lo, hi, (60, 80, 3), dtype=np.uint8)


def _pixels(ii: _core.IntegralImage, k: int) -> np.ndarray:
    """Per-pixel values of plane k (the table's second differences)."""
    t = ii.table(k)
    return np.rint(t[1:, 1:] - t[:-1, 1:] - t[1:, :-1] + t[:-1, :-1]).astype(np.int64)


def test_log_luma_channel_is_the_table_of_the_luma() -> None:
    img = _frame()
    img[0, 0] = (0, 0, 0)
    img[0, 1] = (255, 255, 255)
    ii = _core.IntegralImage()
    ii.compute_channels(img, (0, 0, 80, 60), [_core.CH_LUMA, _core.CH_LOGLUMA])
    luma, log = _pixels(ii, 0), _pixels(ii, 1)
    want = np.rint(255.0 * np.log((luma + 16.0) / 16.0) / math.log(271.0 / 16.0)).astype(np.int64)
    np.testing.assert_array_equal(log, want)
    assert log[0, 0] == 0 and log[0, 1] == 255
    # monotone: brighter pixels never get a smaller value
    order = np.argsort(luma.ravel(), kind="stable")
    assert np.all(np.diff(log.ravel()[order]) >= 0)
    # a shadow (luma x 0.66) moves the value by about the same amount at any brightness
    lum = np.array([60, 120, 180, 240])
    shade = np.rint(lum * 0.66)
    f = lambda v: 255.0 * np.log((v + 16.0) / 16.0) / math.log(271.0 / 16.0)  # noqa: E731
    drop = f(lum) - f(shade)
    assert drop.max() - drop.min() < 0.25 * drop.mean()


def test_grad_x_and_grad_y_channels_are_the_central_differences() -> None:
    img = _frame(1)
    ii = _core.IntegralImage()
    roi = (10, 8, 50, 40)  # inside the frame: the neighbours outside the ROI are used
    ii.compute_channels(img, roi, [_core.CH_LUMA, _core.CH_GRAD_X, _core.CH_GRAD_Y, _core.CH_GRAD])
    full = _core.IntegralImage()
    full.compute_channels(img, (0, 0, 80, 60), [_core.CH_LUMA])
    lum = _pixels(full, 0)
    x, y, w, h = roi
    gx = lum[y:y + h, x + 1:x + w + 1] - lum[y:y + h, x - 1:x + w - 1]
    gy = lum[y + 1:y + h + 1, x:x + w] - lum[y - 1:y + h - 1, x:x + w]
    np.testing.assert_array_equal(_pixels(ii, 1), np.abs(gx))
    np.testing.assert_array_equal(_pixels(ii, 2), np.abs(gy))
    np.testing.assert_array_equal(_pixels(ii, 3), (np.abs(gx) + np.abs(gy)) // 2)


@pytest.mark.parametrize("mode", ["box", "subregion"])
@pytest.mark.parametrize("variant", ["rcwmil", "fct"])
def test_zero_dc_features_ignore_an_added_constant(mode: str, variant: str) -> None:
    p = wmiltrack.Params.for_variant(variant, zero_dc=mode)
    w, h = 30, 24
    base = make_bank(p, w, h, np.random.default_rng(5))
    bank = zero_dc_bank(p, base, w, h)
    areas = bank.rects[:, 2] * bank.rects[:, 3]
    dc = np.add.reduceat(bank.weights * areas, bank.starts[:-1])
    np.testing.assert_allclose(dc, 0.0, atol=1e-12)
    before = np.add.reduceat(base.weights * base.rects[:, 2] * base.rects[:, 3], base.starts[:-1])
    assert np.any(np.abs(before) > 0.5)  # most drawn features do see the offset
    # the reference rectangle is the box or the feature's quadrant, inside the box
    assert np.all(bank.rects[:, 0] + bank.rects[:, 2] <= w)
    assert np.all(bank.rects[:, 1] + bank.rects[:, 3] <= h)
    img = _frame(2, 40, 200)
    corners = np.array([[3, 4], [20, 11], [35, 20]], dtype=np.int32)
    values = []
    for frame in (img, img + np.uint8(37)):
        ii = _core.IntegralImage()
        ii.compute(frame, (0, 0, 80, 60))
        fb = _core.FeatureBank(bank.starts, bank.rects, bank.weights)
        values.append(_core.project(ii, fb, corners[:, 0], corners[:, 1]))
    np.testing.assert_allclose(values[0], values[1], atol=1e-9)
    # scaled banks keep the balance (each weight times its area is kept)
    big = scale_bank(bank, w, h, 37, 30)
    dc = np.add.reduceat(big.weights * big.rects[:, 2] * big.rects[:, 3], big.starts[:-1])
    np.testing.assert_allclose(dc, 0.0, atol=1e-12)


def test_zero_dc_only_on_the_chosen_channels() -> None:
    frames = [_frame(3)] * 3
    box = (20, 15, 30, 24)
    t = wmiltrack.Tracker("rcwmil", seed=0, channels=("luma", "logluma"), zero_dc="box",
                          zero_dc_channels=("logluma",))
    t.init(frames[0], box)
    plain = make_bank(t.params, 30, 24, np.random.default_rng(0))
    counts = np.diff(t._bank_arrays.starts) - np.diff(plain.starts)
    chan = t._feature_channel
    assert set(counts[chan == 0].tolist()) == {0}  # luma features as drawn
    assert counts[chan == 1].max() == 1 and counts[chan == 1].sum() > 0
    t.update(frames[1])


def test_anchor_keeps_the_target_model_near_the_first_frame() -> None:
    from wmiltrack.data.synthetic import make_preset

    seq = make_preset("all", seed=2, n_frames=30)
    frames, gt = seq.load(), np.asarray(seq.groundtruth)
    # the scene darkens by half over the sequence
    dark = [np.clip(f * (1.0 - 0.5 * i / (len(frames) - 1)), 0, 255).astype(np.uint8)
            for i, f in enumerate(frames)]
    drift = {}
    for a in (0.0, 0.5, 1.0):
        t = wmiltrack.Tracker("rcwmil", seed=0, anchor_weight=a)
        t.init(dark[0], gt[0])
        first = t._pool.mu1.copy()
        assert (t._anchor is not None) == (a > 0)
        for f in dark[1:]:
            t.update(f)
        drift[a] = float(np.abs(t._pool.mu1 - first).mean())
    assert drift[1.0] < drift[0.5] < drift[0.0]
    np.testing.assert_array_equal(
        wmiltrack.Tracker("rcwmil", seed=0, anchor_weight=0.0).track(frames[:10], gt[0]),
        wmiltrack.Tracker("rcwmil", seed=0).track(frames[:10], gt[0]))


@pytest.mark.parametrize("overrides", [
    {"zero_dc": "dc"}, {"anchor_weight": -0.1}, {"anchor_weight": 1.5}, {"anchor_weight": True},
    {"zero_dc_channels": ("logluma",)}, {"channels": ("luma",), "zero_dc_channels": ("grad",)},
    {"channels": ("lum",)},
])
def test_illumination_options_are_validated(overrides: dict[str, object]) -> None:
    with pytest.raises(ValueError):
        wmiltrack.Params.for_variant("rcwmil-plus", **overrides)


def test_gray_channels_and_anchor_apply_to_frames_without_colour_only() -> None:
    from wmiltrack.data.synthetic import make_preset

    seq = make_preset("all", seed=2, n_frames=6)
    frames, gt = seq.load(), np.asarray(seq.groundtruth)
    gray = [np.repeat(f.mean(axis=2, keepdims=True).astype(np.uint8), 3, axis=2) for f in frames]
    kw = {"gray_channels": ("logluma", "orient0", "orient1", "orient2", "orient3"),
          "gray_anchor_weight": 0.1}
    t = wmiltrack.Tracker("rcwmil-plus", seed=0, **kw)
    t.init(gray[0], gt[0])
    assert t._chan_names == kw["gray_channels"] and t._anchor is not None
    for f in gray[1:]:
        t.update(f)
    assert t._ii.channels == (_core.CH_LOGLUMA, _core.CH_ORIENT0, _core.CH_ORIENT1,
                              _core.CH_ORIENT2, _core.CH_ORIENT3)
    # colour frames: the preset's own channels (none) and anchor (off), so the same boxes
    np.testing.assert_array_equal(
        wmiltrack.Tracker("rcwmil-plus", seed=0, **kw).track(frames, gt[0]),
        wmiltrack.Tracker("rcwmil-plus", seed=0).track(frames, gt[0]))
    c = wmiltrack.Tracker("rcwmil-plus", seed=0, **kw)
    c.init(frames[0], gt[0])
    assert c._chan_names is None and c._anchor is None


@pytest.mark.parametrize("overrides", [
    {"gray_anchor_weight": 1.5}, {"gray_anchor_weight": False}, {"gray_channels": ("opp_rg",)},
    {"gray_channels": ("luma", "luma")}, {"gray_channels": ("lum",)},
])
def test_gray_options_are_validated(overrides: dict[str, object]) -> None:
    with pytest.raises(ValueError):
        wmiltrack.Params.for_variant("rcwmil-plus", **overrides)
