"""Multi-channel integral images and features on a channel, against numpy references."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from wmiltrack import _core

ALL_CHANNELS = (_core.CH_LUMA, _core.CH_GRAD, _core.CH_OPP_RG, _core.CH_OPP_YB)
GRAY_CHANNELS = (_core.CH_LUMA, _core.CH_GRAD)


def luma(frame: np.ndarray) -> np.ndarray:
    if frame.ndim == 2:
        return frame.astype(np.int64)
    return cv2.cvtColor(np.ascontiguousarray(frame[:, :, :3]), cv2.COLOR_BGR2GRAY).astype(np.int64)


def channel_ref(frame: np.ndarray, ch: int) -> np.ndarray:
    """The whole frame's channel `ch`, written from the definitions, independently of the C++."""
    if ch in (_core.CH_OPP_RG, _core.CH_OPP_YB):
        b, g, r = (frame[:, :, i].astype(np.int64) for i in range(3))
        if ch == _core.CH_OPP_RG:
            return (r - g + 255) // 2
        return (r + g - 2 * b + 510) // 4
    lum = luma(frame)
    if ch == _core.CH_LUMA:
        return lum
    p = np.pad(lum, 1, mode="edge")  # the frame's edge replicated
    gx = p[1:-1, 2:] - p[1:-1, :-2]
    gy = p[2:, 1:-1] - p[:-2, 1:-1]
    assert ch == _core.CH_GRAD, ch
    return (np.abs(gx) + np.abs(gy)) // 2


def integral_ref(values: np.ndarray) -> np.ndarray:
    out = np.zeros((values.shape[0] + 1, values.shape[1] + 1), dtype=np.int64)
    out[1:, 1:] = values.cumsum(0).cumsum(1)
    return out


def clip(roi: tuple[int, int, int, int], shape: tuple[int, ...]) -> tuple[int, int, int, int]:
    x, y, w, h = roi
    x0, y0 = max(x, 0), max(y, 0)
    return x0, y0, min(x + w, shape[1]) - x0, min(y + h, shape[0]) - y0


ROIS = [
    (0, 0, 61, 47),      # the whole frame
    (10, 7, 30, 20),     # inside: gradients use the pixels around the ROI
    (-4, -3, 15, 12),    # hangs off the top-left corner
    (50, 40, 30, 30),    # hangs off the bottom-right corner
    (0, 20, 61, 1),      # one row, touching the left and right edges
    (30, 0, 1, 47),      # one column, touching the top and bottom edges
    (60, 46, 1, 1),      # the bottom-right pixel
    (5, 5, 2, 2),        # smaller than 3 px
    (0, 0, 2, 1),
]


LAYOUTS = ["gray", "bgr", "bgra", "strided"]


@pytest.mark.parametrize("layout", LAYOUTS)
@pytest.mark.parametrize("roi", ROIS)
def test_every_channel_matches_numpy(layout: str, roi: tuple[int, int, int, int]) -> None:
    rng = np.random.default_rng([LAYOUTS.index(layout), ROIS.index(roi)])
    if layout == "gray":
        frame = rng.integers(0, 256, size=(47, 61), dtype=np.uint8)
    elif layout == "strided":
        frame = rng.integers(0, 256, size=(94, 183, 3), dtype=np.uint8)[::2, ::3, :]
    else:
        frame = rng.integers(0, 256, size=(47, 61, 4 if layout == "bgra" else 3), dtype=np.uint8)
    # Smooth half the frame so that the gradients see runs, not only noise.
    frame[:, :30] = cv2.GaussianBlur(np.ascontiguousarray(frame[:, :30]), (7, 7), 2.0)
    channels = list(GRAY_CHANNELS if layout == "gray" else ALL_CHANNELS)
    ii = _core.IntegralImage()
    ii.compute_channels(frame, roi, channels)
    x0, y0, w, h = clip(roi, frame.shape)
    assert (ii.x0, ii.y0, ii.width, ii.height) == (x0, y0, w, h)
    assert ii.num_channels == len(channels) and ii.channels == tuple(channels)
    for k, ch in enumerate(channels):
        ref = channel_ref(frame, ch)
        assert ref.min() >= 0 and ref.max() <= 255
        np.testing.assert_array_equal(ii.table(k), integral_ref(ref[y0:y0 + h, x0:x0 + w]),
                                      err_msg=f"channel {ch} on plane {k}")


def test_a_pixel_does_not_depend_on_the_roi() -> None:
    rng = np.random.default_rng(3)
    frame = rng.integers(0, 256, size=(40, 50, 3), dtype=np.uint8)
    whole, part = _core.IntegralImage(), _core.IntegralImage()
    whole.compute_channels(frame, (0, 0, 50, 40), list(ALL_CHANNELS))
    part.compute_channels(frame, (13, 9, 3, 2), list(ALL_CHANNELS))
    for k in range(len(ALL_CHANNELS)):
        for x, y in [(13, 9), (15, 10), (14, 9)]:
            assert part.rect_sum(x, y, 1, 1, plane=k) == whole.rect_sum(x, y, 1, 1, plane=k)


@pytest.mark.parametrize("layout", [(47, 61), (47, 61, 1), (47, 61, 3), (47, 61, 4)])
def test_luma_plane_is_bit_identical_to_compute(layout: tuple[int, ...]) -> None:
    rng = np.random.default_rng(len(layout))
    frame = rng.integers(0, 256, size=layout, dtype=np.uint8)
    a, b = _core.IntegralImage(), _core.IntegralImage()
    a.compute(frame, (3, 4, 50, 30))
    b.compute_channels(frame, (3, 4, 50, 30), [_core.CH_GRAD, _core.CH_LUMA])
    assert a.num_channels == 1 and a.channels == (_core.CH_LUMA,)
    np.testing.assert_array_equal(a.table(), b.table(1))
    # compute() after compute_channels() is back to one plane.
    b.compute(frame, (3, 4, 50, 30))
    assert b.num_channels == 1
    np.testing.assert_array_equal(a.table(), b.table())
    with pytest.raises(IndexError):
        b.table(1)


def test_channel_errors() -> None:
    gray = np.zeros((20, 20), dtype=np.uint8)
    ii = _core.IntegralImage()
    for ch in (_core.CH_OPP_RG, _core.CH_OPP_YB):
        with pytest.raises(ValueError, match="gray"):
            ii.compute_channels(gray, (0, 0, 10, 10), [_core.CH_LUMA, ch])
    with pytest.raises(ValueError, match="unknown channel"):
        ii.compute_channels(gray, (0, 0, 10, 10), [_core.NUM_CHANNEL_KINDS])
    with pytest.raises(ValueError, match="unknown channel"):
        ii.compute_channels(gray, (0, 0, 10, 10), [-1])
    with pytest.raises(ValueError, match="no channels"):
        ii.compute_channels(gray, (0, 0, 10, 10), [])
    with pytest.raises(ValueError, match="does not meet"):
        ii.compute_channels(gray, (30, 30, 10, 10), [_core.CH_LUMA])
    ii.compute_channels(gray, (0, 0, 10, 10), [_core.CH_GRAD])
    with pytest.raises(IndexError):
        ii.rect_sum(0, 0, 2, 2, plane=1)
    with pytest.raises(IndexError):
        ii.table(-1)


def random_bank(rng: np.random.Generator, m: int, box: int, n_planes: int,
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    counts = rng.integers(1, 4, size=m)
    starts = np.zeros(m + 1, dtype=np.int32)
    np.cumsum(counts, out=starts[1:])
    r = int(starts[-1])
    xy = rng.integers(0, box - 2, size=(r, 2))
    wh = 1 + rng.integers(0, box - xy - 1)
    rects = np.concatenate([xy, wh], axis=1).astype(np.int32)
    weights = rng.uniform(-1, 1, size=r)
    planes = rng.integers(0, n_planes, size=r).astype(np.int32)
    return starts, rects, weights, planes


def test_project_on_planes_matches_numpy_sums() -> None:
    rng = np.random.default_rng(4)
    frame = rng.integers(0, 256, size=(60, 80, 3), dtype=np.uint8)
    channels = [_core.CH_OPP_YB, _core.CH_GRAD, _core.CH_LUMA, _core.CH_OPP_RG]
    ii = _core.IntegralImage()
    ii.compute_channels(frame, (5, 4, 70, 50), channels)
    refs = [channel_ref(frame, ch) for ch in channels]
    starts, rects, weights, planes = random_bank(rng, 30, 16, len(channels))
    assert set(planes.tolist()) == set(range(len(channels)))
    bank = _core.FeatureBank(starts, rects, weights, channels=planes)
    np.testing.assert_array_equal(bank.channels, planes)
    assert bank.planes_needed == len(channels)
    xs = rng.integers(5, 75 - 16, size=40).astype(np.int32)
    ys = rng.integers(4, 54 - 16, size=40).astype(np.int32)
    values = _core.project(ii, bank, xs, ys)
    expected = np.zeros((30, 40))
    for f in range(30):
        for q in range(starts[f], starts[f + 1]):
            rx, ry, rw, rh = rects[q]
            ref = refs[planes[q]]
            for n in range(40):
                x, y = xs[n] + rx, ys[n] + ry
                expected[f, n] += weights[q] * ref[y:y + rh, x:x + rw].sum()
    np.testing.assert_allclose(values, expected, rtol=1e-12, atol=1e-9)
    # A subset of features, in another order.
    sel = np.array([7, 2, 29], dtype=np.int32)
    np.testing.assert_array_equal(_core.project(ii, bank, xs, ys, sel), values[sel])


def test_bank_with_channels_on_plane_zero_is_bit_identical() -> None:
    rng = np.random.default_rng(5)
    frame = rng.integers(0, 256, size=(90, 120, 3), dtype=np.uint8)
    starts, rects, weights, _ = random_bank(rng, 40, 20, 1)
    plain = _core.FeatureBank(starts, rects, weights)
    zeros = _core.FeatureBank(starts, rects, weights, channels=np.zeros(len(weights), np.int32))
    assert plain.planes_needed == 1 and not plain.channels.any()
    luma_only, stacked = _core.IntegralImage(), _core.IntegralImage()
    luma_only.compute(frame, (10, 10, 100, 70))
    stacked.compute_channels(frame, (10, 10, 100, 70), [_core.CH_LUMA, _core.CH_GRAD, _core.CH_OPP_RG])
    xs = rng.integers(10, 90, size=50).astype(np.int32)
    ys = rng.integers(10, 60, size=50).astype(np.int32)
    base = _core.project(luma_only, plain, xs, ys)
    for ii in (luma_only, stacked):
        for bank in (plain, zeros):
            np.testing.assert_array_equal(_core.project(ii, bank, xs, ys), base)
    sel = np.arange(0, 40, 3, dtype=np.int32)
    k = sel.size
    weak = (rng.normal(0, 50, k), rng.uniform(20, 60, k), rng.normal(0, 50, k), rng.uniform(20, 60, k))
    ref = _core.score_grid(luma_only, plain, sel, *weak, 1e-30, (50, 35, 20, 20), 12, 1, (120, 90), True)
    for ii in (luma_only, stacked):
        for bank in (plain, zeros):
            got = _core.score_grid(ii, bank, sel, *weak, 1e-30, (50, 35, 20, 20), 12, 1, (120, 90), True)
            assert got[:4] == ref[:4]
            np.testing.assert_array_equal(got[4], ref[4])


def test_score_grid_on_planes_matches_project() -> None:
    rng = np.random.default_rng(6)
    frame = rng.integers(0, 256, size=(80, 100, 3), dtype=np.uint8)
    ii = _core.IntegralImage()
    ii.compute_channels(frame, (0, 0, 100, 80), [_core.CH_LUMA, _core.CH_OPP_RG, _core.CH_GRAD])
    starts, rects, weights, planes = random_bank(rng, 20, 16, 3)
    bank = _core.FeatureBank(starts, rects, weights, channels=planes)
    sel = np.array([3, 0, 11, 19], dtype=np.int32)
    mu1, mu0 = rng.normal(0, 500, 4), rng.normal(0, 500, 4)
    s1, s0 = rng.uniform(200, 400, 4), rng.uniform(200, 400, 4)
    box, radius = (40, 30, 16, 16), 6
    dx, dy, score, n, grid = _core.score_grid(ii, bank, sel, mu1, s1, mu0, s0, 1e-30, box, radius, 1,
                                              (100, 80), True)
    assert n > 0
    offs = [(i, j) for j in range(-5, 6) for i in range(-5, 6) if i * i + j * j < radius * radius]
    xs = np.array([box[0] + i for i, _ in offs], dtype=np.int32)
    ys = np.array([box[1] + j for _, j in offs], dtype=np.int32)
    h = _core.log_ratio(_core.project(ii, bank, xs, ys, sel), mu1, s1, mu0, s0, 1e-30).sum(0)
    # The search sums exact-path log ratios in float (issue 28): float rounding of each term,
    # and the chosen candidate is the best up to that rounding.
    for (i, j), v in zip(offs, h):
        assert grid[j + 5, i + 5] == pytest.approx(v, rel=1e-5, abs=1e-4)
    best = offs.index((dx, dy))
    assert h[best] == pytest.approx(h.max(), abs=1e-4) and score == pytest.approx(h[best], rel=1e-5, abs=1e-4)


def test_plane_errors() -> None:
    rng = np.random.default_rng(7)
    frame = rng.integers(0, 256, size=(40, 40, 3), dtype=np.uint8)
    starts = np.array([0, 1, 2], dtype=np.int32)
    rects = np.array([[0, 0, 3, 3], [1, 1, 2, 2]], dtype=np.int32)
    weights = np.array([1.0, -1.0])
    with pytest.raises(ValueError, match="one plane index per rect"):
        _core.FeatureBank(starts, rects, weights, channels=np.array([0], dtype=np.int32))
    with pytest.raises(ValueError, match=">= 0"):
        _core.FeatureBank(starts, rects, weights, channels=np.array([0, -1], dtype=np.int32))
    bank = _core.FeatureBank(starts, rects, weights, channels=np.array([0, 2], dtype=np.int32))
    assert bank.planes_needed == 3
    ii = _core.IntegralImage()
    xs = ys = np.array([5], dtype=np.int32)
    weak = (np.zeros(1), np.ones(1), np.ones(1), np.ones(1))
    for build in (lambda: ii.compute(frame, (0, 0, 40, 40)),
                  lambda: ii.compute_channels(frame, (0, 0, 40, 40), [_core.CH_LUMA, _core.CH_GRAD])):
        build()
        with pytest.raises(ValueError, match="plane"):
            _core.project(ii, bank, xs, ys)
        with pytest.raises(ValueError, match="plane"):
            _core.project(ii, bank, xs, ys, np.array([0], dtype=np.int32))
        with pytest.raises(ValueError, match="plane"):
            _core.score_grid(ii, bank, np.array([1], dtype=np.int32), *weak, 1e-30, (10, 10, 5, 5), 3, 1,
                             (40, 40))
    ii.compute_channels(frame, (0, 0, 40, 40), [_core.CH_LUMA, _core.CH_GRAD, _core.CH_OPP_YB])
    assert _core.project(ii, bank, xs, ys).shape == (2, 1)
