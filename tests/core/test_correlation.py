"""The correlation-filter parts: fHOG, the translation and scale filters against numpy
references, and what they must find on generated images (a shift, a scale change)."""

from __future__ import annotations

import math

import cv2
import numpy as np
import numpy.typing as npt
import pytest

from wmiltrack import _core
from wmiltrack.engine.correlation import (
    CorrelationFilter,
    CorrelationSettings,
    ScaleFilter,
    ScaleFilterSettings,
    smooth_size,
)

F64 = npt.NDArray[np.float64]


def texture(h: int, w: int, seed: int, blur: float = 2.0) -> npt.NDArray[np.uint8]:
    """A smooth random gray texture stretched to 0..255."""
    rng = np.random.default_rng(seed)
    a = cv2.GaussianBlur(rng.random((h, w)), (0, 0), blur)
    a = (a - a.min()) / (a.max() - a.min())
    return np.round(a * 255).astype(np.uint8)


# ----------------------------------------------------------------------------- references
def fhog_reference(patch: F64, cell: int) -> F64:
    """fHOG as documented in fhog.hpp, written out with numpy loops."""
    rows, cols = patch.shape
    cr, cc = rows // cell, cols // cell
    p = np.pad(patch, 1, mode="edge")
    gx = p[1:-1, 2:] - p[1:-1, :-2]
    gy = p[2:, 1:-1] - p[:-2, 1:-1]
    mag = np.sqrt(gx * gx + gy * gy)
    ang = np.arctan2(gy, gx)
    ang = np.where(ang < 0, ang + 2 * np.pi, ang)
    hist = np.zeros((cr, cc, 18))
    for r in range(rows):
        y = (r + 0.5) / cell - 0.5
        y0 = math.floor(y)
        fy = y - y0
        for c in range(cols):
            if mag[r, c] == 0:
                continue
            o = ang[r, c] * 18 / (2 * np.pi)
            o0 = math.floor(o)
            fo = o - o0
            o0 %= 18
            x = (c + 0.5) / cell - 0.5
            x0 = math.floor(x)
            fx = x - x0
            for yy, wy in ((y0, 1 - fy), (y0 + 1, fy)):
                for xx, wx in ((x0, 1 - fx), (x0 + 1, fx)):
                    if 0 <= yy < cr and 0 <= xx < cc:
                        hist[yy, xx, o0] += mag[r, c] * wy * wx * (1 - fo)
                        hist[yy, xx, (o0 + 1) % 18] += mag[r, c] * wy * wx * fo
    unsigned = hist[..., :9] + hist[..., 9:]
    energy = np.pad((unsigned**2).sum(-1), 1, mode="edge")
    out = np.zeros((31, cr, cc))
    for r in range(cr):
        for c in range(cc):
            e = energy
            R, C = r + 1, c + 1
            n = [1 / math.sqrt(e[R, C] + e[R + dy, C] + e[R, C + dx] + e[R + dy, C + dx] + 1e-4)
                 for dy, dx in ((-1, -1), (-1, 1), (1, -1), (1, 1))]
            h = hist[r, c]
            t = np.stack([np.minimum(h * nj, 0.2) for nj in n])  # 4 x 18
            out[:18, r, c] = 0.5 * t.sum(0)
            u = np.stack([np.minimum(unsigned[r, c] * nj, 0.2) for nj in n])
            out[18:27, r, c] = 0.5 * u.sum(0)
            out[27:, r, c] = 0.2357 * t.sum(1)
    return out


def hann(n: int) -> F64:
    return np.ones(1) if n == 1 else 0.5 * (1 - np.cos(2 * np.pi * np.arange(n) / (n - 1)))


class NumpyDCF:
    """The translation filter of correlation.hpp with np.fft."""

    def __init__(self, rows: int, cols: int, sigma: float, lam: float) -> None:
        self.window = np.outer(hann(rows), hann(cols))
        dr = np.minimum(np.arange(rows), rows - np.arange(rows))
        dc = np.minimum(np.arange(cols), cols - np.arange(cols))
        self.label = np.exp(-0.5 * (dr[:, None] ** 2 + dc[None, :] ** 2) / sigma**2)
        self.yf = np.fft.fft2(self.label)
        self.lam = lam
        self.n = rows * cols
        self.num: npt.NDArray[np.complex128] | None = None
        self.den: F64 | None = None

    def learn(self, x: F64, rate: float) -> None:
        xf = np.fft.fft2(x * self.window)
        num = np.conj(self.yf) * xf / self.n
        den = (np.abs(xf) ** 2).sum(0) / self.n
        if self.num is None or self.den is None:
            self.num, self.den = num, den
        else:
            self.num = (1 - rate) * self.num + rate * num
            self.den = (1 - rate) * self.den + rate * den

    def respond(self, z: F64) -> F64:
        assert self.num is not None and self.den is not None
        zf = np.fft.fft2(z * self.window)
        return np.real(np.fft.ifft2((np.conj(self.num) * zf).sum(0) / (self.den + self.lam)))


# ----------------------------------------------------------------------------- kernels
def test_fhog_matches_numpy_reference() -> None:
    patch = texture(22, 27, 0, blur=1.5).astype(np.float32) / 255
    got = _core.fhog(patch, 4)
    assert got.shape == (_core.FHOG_CHANNELS, 5, 6)
    np.testing.assert_allclose(got, fhog_reference(patch.astype(np.float64), 4), atol=2e-5)


def test_gray_patch_is_the_frame_on_whole_pixels_and_luma_of_colour() -> None:
    rng = np.random.default_rng(1)
    frame = rng.integers(0, 256, (30, 40, 3), dtype=np.uint8)
    patch = _core.cf_gray_patch(frame, (20.0, 15.0), (10.0, 6.0), (10, 6))
    luma = cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
    np.testing.assert_allclose(patch * 255, luma[12:18, 15:25], atol=1e-3)
    # Shrinking a constant frame keeps it constant; outside the frame is the edge pixel.
    flat = np.full((30, 40), 77, np.uint8)
    np.testing.assert_allclose(_core.cf_gray_patch(flat, (20.0, 15.0), (30.0, 30.0), (7, 5)),
                               77 / 255, rtol=1e-6)
    corner = _core.cf_gray_patch(luma, (-50.0, -50.0), (4.0, 4.0), (2, 2))
    np.testing.assert_allclose(corner * 255, luma[0, 0], atol=1e-3)


@pytest.mark.parametrize(("rows", "cols"), [(12, 15), (9, 16), (10, 10)])
def test_translation_filter_matches_numpy_reference(rows: int, cols: int) -> None:
    rng = np.random.default_rng(2)
    k = 3
    a = rng.random((k, rows, cols)).astype(np.float32)
    b = rng.random((k, rows, cols)).astype(np.float32)
    z = rng.random((k, rows, cols)).astype(np.float32)
    f = _core.TranslationFilter(rows, cols, k, 1.3, 1e-2)
    ref = NumpyDCF(rows, cols, 1.3, 1e-2)
    np.testing.assert_allclose(f.window, ref.window, atol=1e-6)
    np.testing.assert_allclose(f.label, ref.label, atol=1e-6)
    for x, rate in ((a, 1.0), (b, 0.3)):
        f.learn(x, rate)
        ref.learn(x.astype(np.float64), rate)
    r = f.respond(z, 2)
    want = ref.respond(z.astype(np.float64))
    np.testing.assert_allclose(r.values, want, atol=2e-5 * np.abs(want).max())
    assert r.peak == pytest.approx(want.max(), rel=1e-4)
    # PSR and APCE as documented, from the reference response.
    pr, pc = np.unravel_index(np.argmax(want), want.shape)
    dr = np.minimum((np.arange(rows) - pr) % rows, (pr - np.arange(rows)) % rows)
    dc = np.minimum((np.arange(cols) - pc) % cols, (pc - np.arange(cols)) % cols)
    side = want[~((dr[:, None] <= 2) & (dc[None, :] <= 2))]
    assert r.psr == pytest.approx((want.max() - side.mean()) / side.std(), rel=1e-3)
    lo = want.min()
    assert r.apce == pytest.approx((want.max() - lo) ** 2 / np.mean((want - lo) ** 2), rel=1e-3)


@pytest.mark.parametrize(("n", "d"), [(33, 20), (33, 7), (17, 1), (4, 5)])
def test_scale_filter_matches_numpy_reference(n: int, d: int) -> None:
    rng = np.random.default_rng(3)
    a, b, z = (rng.random((n, d)).astype(np.float32) for _ in range(3))
    sigma, lam = math.sqrt(n) / 4, 1e-3
    f = _core.ScaleFilter(n, d, sigma, lam)
    y = np.exp(-0.5 * (np.arange(n) - (n - 1) // 2) ** 2 / sigma**2)
    yf = np.fft.fft(y)
    w = hann(n)[:, None]
    num: npt.NDArray[np.complex128] | None = None
    den: F64 | None = None
    for x, rate in ((a, 1.0), (b, 0.2)):
        f.learn(x, rate)
        xf = np.fft.fft(x * w, axis=0)
        nn, dd = np.conj(yf)[:, None] * xf, (np.abs(xf) ** 2).sum(1)
        if num is None or den is None:
            num, den = nn, dd
        else:
            num, den = (1 - rate) * num + rate * nn, (1 - rate) * den + rate * dd
    assert num is not None and den is not None
    zf = np.fft.fft(z * w, axis=0)
    want = np.real(np.fft.ifft((np.conj(num) * zf).sum(1) / (den + lam)))
    r = f.respond(z)
    np.testing.assert_allclose(r.values, want, atol=1e-5 * np.abs(want).max())
    assert r.best == int(np.argmax(want))


# ----------------------------------------------------------------------------- the parts
def shifted(frame: npt.NDArray[np.uint8], dx: float, dy: float) -> npt.NDArray[np.uint8]:
    """The frame's content moved by (dx, dy) pixels (bilinear, edges replicated)."""
    m = np.array([[1.0, 0.0, dx], [0.0, 1.0, dy]])
    return cv2.warpAffine(frame, m, (frame.shape[1], frame.shape[0]), flags=cv2.INTER_LINEAR,
                          borderMode=cv2.BORDER_REPLICATE)


@pytest.mark.parametrize(("dx", "dy"), [(6.0, -4.0), (-9.5, 3.25), (0.0, 0.0), (2.6, 7.4)])
def test_filter_finds_a_known_shift_within_a_pixel(dx: float, dy: float) -> None:
    frame = texture(240, 320, 4)
    box = (130.0, 90.0, 60.0, 50.0)
    cf = CorrelationFilter()
    cf.init(frame, box)
    loc = cf.locate(shifted(frame, dx, dy), (160.0, 115.0))
    assert abs(loc.dx - dx) < 1.0 and abs(loc.dy - dy) < 1.0, (loc.dx, loc.dy)
    # The response's peak cell is the shift, in cells of loc.cell frame pixels.
    rows, cols = loc.response.shape
    r, c = np.unravel_index(np.argmax(loc.response), loc.response.shape)
    sx = ((c + cols // 2) % cols - cols // 2) * loc.cell[0]
    sy = ((r + rows // 2) % rows - rows // 2) * loc.cell[1]
    assert abs(sx - dx) <= 0.6 * loc.cell[0] and abs(sy - dy) <= 0.6 * loc.cell[1]


def test_psr_is_high_on_the_target_and_low_on_noise() -> None:
    frame = texture(240, 320, 5)
    cf = CorrelationFilter()
    cf.init(frame, (130.0, 90.0, 60.0, 50.0))
    on_target = cf.locate(shifted(frame, 3.0, 2.0), (160.0, 115.0))
    noise = np.random.default_rng(6).integers(0, 256, (240, 320), dtype=np.uint8)
    on_noise = cf.locate(noise, (160.0, 115.0))
    other = cf.locate(texture(240, 320, 7), (160.0, 115.0))
    assert on_target.psr > 20.0, on_target.psr
    assert on_noise.psr < 8.0 and other.psr < 8.0, (on_noise.psr, other.psr)
    assert on_target.apce > 3 * max(on_noise.apce, other.apce)
    assert on_target.peak > 3 * max(on_noise.peak, other.peak)


def zoomed(frame: npt.NDArray[np.uint8], factor: float, cx: float, cy: float) -> npt.NDArray[np.uint8]:
    """The frame magnified by ``factor`` about (cx, cy) (pixel-centre coordinates)."""
    m = np.array([[factor, 0.0, (1 - factor) * cx], [0.0, factor, (1 - factor) * cy]])
    return cv2.warpAffine(frame, m, (frame.shape[1], frame.shape[0]), flags=cv2.INTER_LINEAR,
                          borderMode=cv2.BORDER_REPLICATE)


@pytest.mark.parametrize("factor", [1.1, 1 / 1.1, 1.05])
def test_scale_estimator_recovers_a_known_scale_change(factor: float) -> None:
    frame = texture(240, 320, 8, blur=1.5)
    box = (120.0, 90.0, 80.0, 60.0)
    centre = (160.0, 120.0)  # the box's centre; pixel i covers [i, i + 1)
    se = ScaleFilter()
    se.init(frame, box)
    assert se.estimate(frame, centre, (80.0, 60.0)).factor == pytest.approx(1.0, abs=0.005)
    # warpAffine's pixel centres are at integers: the box's centre is (159.5, 119.5) there.
    est = se.estimate(zoomed(frame, factor, 159.5, 119.5), centre, (80.0, 60.0))
    assert est.factor == pytest.approx(factor, rel=0.01), est.factor
    assert est.response.shape == (33,)


def test_learning_follows_the_rate() -> None:
    frame = texture(200, 200, 9)
    other = texture(200, 200, 10)
    box = (70.0, 70.0, 60.0, 60.0)
    fast, slow = CorrelationFilter(), CorrelationFilter()
    for cf in (fast, slow):
        cf.init(frame, box)
    fast.learn(other, box, 1.0)
    slow.learn(other, box, 0.01)
    # rate 1 forgets the first frame; rate 0.01 hardly learns the second.
    assert fast.locate(other, (100.0, 100.0)).psr > fast.locate(frame, (100.0, 100.0)).psr
    assert slow.locate(frame, (100.0, 100.0)).psr > slow.locate(other, (100.0, 100.0)).psr


def test_copies_are_independent() -> None:
    frame, other = texture(200, 200, 13), texture(200, 200, 14)
    box = (70.0, 70.0, 60.0, 60.0)
    cf, se = CorrelationFilter(), ScaleFilter()
    cf.init(frame, box)
    se.init(frame, box)
    cf2, se2 = cf.copy(), se.copy()
    before = cf.locate(frame, (100.0, 100.0)).response
    scale_before = se.estimate(frame, (100.0, 100.0), (60.0, 60.0)).response
    cf.learn(other, box, 1.0)
    se.learn(other, (100.0, 100.0), (60.0, 60.0), 1.0)
    np.testing.assert_array_equal(cf2.locate(frame, (100.0, 100.0)).response, before)
    np.testing.assert_array_equal(se2.estimate(frame, (100.0, 100.0), (60.0, 60.0)).response,
                                  scale_before)
    assert not np.array_equal(cf.locate(frame, (100.0, 100.0)).response, before)
    assert cf2.grid == cf.grid and cf2.size == cf.size
    with pytest.raises(RuntimeError, match="init"):
        CorrelationFilter().copy().locate(frame, (1.0, 1.0))


def test_template_grid_is_fixed_and_smooth() -> None:
    for box in ((0.0, 0.0, 20.0, 30.0), (0.0, 0.0, 300.0, 120.0)):
        cf = CorrelationFilter()
        cf.init(texture(400, 400, 11), box)
        rows, cols = cf.grid
        assert rows == smooth_size(rows) and cols == smooth_size(cols)
        assert 0.7 * 150**2 < rows * cols * 16 < 1.4 * 150**2
    assert [smooth_size(n) for n in (1, 7, 37, 38, 49)] == [1, 8, 36, 40, 50]


# ----------------------------------------------------------------------------- bad input
def test_settings_are_checked() -> None:
    with pytest.raises(ValueError, match="cell"):
        CorrelationSettings(cell=0)
    with pytest.raises(ValueError, match="learning_rate"):
        CorrelationSettings(learning_rate=0.0)
    with pytest.raises(ValueError, match="padding"):
        CorrelationSettings(padding=-1.0)
    with pytest.raises(ValueError, match="num_scales"):
        ScaleFilterSettings(num_scales=32)
    with pytest.raises(ValueError, match="step"):
        ScaleFilterSettings(step=1.0)
    with pytest.raises(ValueError, match="max_area"):
        ScaleFilterSettings(max_area=1.0)


def test_bad_calls_raise() -> None:
    frame = texture(100, 100, 12)
    cf = CorrelationFilter()
    with pytest.raises(RuntimeError, match="init"):
        cf.locate(frame, (50.0, 50.0))
    with pytest.raises(ValueError, match="positive"):
        cf.init(frame, (10.0, 10.0, 0.0, 20.0))
    with pytest.raises(TypeError, match="box"):
        cf.init(frame, (10.0, 10.0, 20.0))
    with pytest.raises(TypeError):
        cf.init(frame.astype(np.complex64), (10.0, 10.0, 20.0, 20.0))
    cf.init(frame, (30.0, 30.0, 40.0, 40.0))
    with pytest.raises(ValueError, match="finite"):
        cf.locate(frame, (math.nan, 50.0))
    with pytest.raises(ValueError, match="rate"):
        cf.learn(frame, (30.0, 30.0, 40.0, 40.0), 0.0)
    with pytest.raises(ValueError, match="rate"):
        cf.learn(frame, (30.0, 30.0, 40.0, 40.0), True)
    se = ScaleFilter()
    with pytest.raises(RuntimeError, match="init"):
        se.estimate(frame, (50.0, 50.0), (20.0, 20.0))
    se.init(frame, (30.0, 30.0, 40.0, 40.0))
    with pytest.raises(ValueError, match="size"):
        se.estimate(frame, (50.0, 50.0), (-20.0, 20.0))


def test_core_rejects_bad_arguments() -> None:
    f = _core.TranslationFilter(8, 8, 31, 1.0, 1e-3)
    x = np.zeros((31, 8, 8), np.float32)
    with pytest.raises(ValueError, match="learn"):
        f.respond(x)
    with pytest.raises(ValueError, match="shape"):
        f.learn(np.zeros((31, 8, 9), np.float32), 1.0)
    with pytest.raises(ValueError, match="rate"):
        f.learn(x, 1.5)
    with pytest.raises(ValueError):
        _core.TranslationFilter(8, 8, 31, 0.0, 1e-3)
    with pytest.raises(ValueError, match="cell"):
        _core.fhog(np.zeros((3, 3), np.float32), 4)
    with pytest.raises(ValueError, match="2-D"):
        _core.fhog(np.zeros((3, 3, 3), np.float32), 1)
    with pytest.raises(TypeError, match="uint8"):
        _core.cf_gray_patch(np.zeros((5, 5), np.float32), (2.0, 2.0), (2.0, 2.0), (2, 2))
    with pytest.raises(ValueError, match="size"):
        _core.cf_gray_patch(np.zeros((5, 5), np.uint8), (2.0, 2.0), (0.0, 2.0), (2, 2))
    s = _core.ScaleFilter(5, 3, 1.0, 1e-3)
    with pytest.raises(ValueError, match="shape"):
        s.learn(np.zeros((4, 3), np.float32), 1.0)
    with pytest.raises(ValueError, match="learn"):
        s.respond(np.zeros((5, 3), np.float32))
    with pytest.raises(ValueError, match="factors"):
        _core.scale_samples(np.zeros((50, 50), np.uint8), (25.0, 25.0), (10.0, 10.0), [], (8, 8))


# ------------------------------------------------------- shared transforms, compression, map
def test_a_sample_learnt_with_a_shift_puts_the_peak_there() -> None:
    """learn_spectrum moves the sample so that the target, ``shift`` cells off its centre, is
    centred: answering the same sample then peaks at that shift (sub-cell too), for a full
    and a compressed filter alike."""
    rng = np.random.default_rng(11)
    x = rng.random((31, 30, 36)).astype(np.float32)
    for compressed in (0, 10):
        f = _core.TranslationFilter(30, 36, 31, 2.0, 1e-3, compressed)
        f.learn(x, 1.0)
        s = f.transform(x)
        assert s.channels == (compressed or 31) == f.filter_channels
        r = f.respond_spectrum(s, 5)
        assert (r.row_shift, r.col_shift) == pytest.approx((0.0, 0.0), abs=1e-6)
        for shift in [(3.0, -2.0), (1.4, 2.6), (-4.0, 0.0)]:
            f.learn_spectrum(s, 1.0, shift)
            r = f.respond_spectrum(s, 5)
            assert (r.row_shift, r.col_shift) == pytest.approx(shift, abs=0.05), shift


def test_respond_and_respond_spectrum_agree() -> None:
    rng = np.random.default_rng(12)
    x, z = rng.random((2, 31, 24, 20)).astype(np.float32)
    f = _core.TranslationFilter(24, 20, 31, 1.5, 1e-3)
    f.learn(x, 1.0)
    np.testing.assert_array_equal(f.respond(z, 5).values, f.respond_spectrum(f.transform(z), 5).values)


def test_compression_keeps_the_principal_axes_of_the_first_sample() -> None:
    """The projection's rows are orthonormal, largest variance first (second moments of the
    first sample's cells), and fixed after the first learn."""
    rng = np.random.default_rng(13)
    base = rng.random((31, 3)).astype(np.float32)  # features mostly in a 3-D subspace
    x = (base @ rng.random((3, 20 * 20)).astype(np.float32)
         + 0.01 * rng.random((31, 400)).astype(np.float32)).reshape(31, 20, 20)
    f = _core.TranslationFilter(20, 20, 31, 1.5, 1e-3, 5)
    assert f.projection.shape == (0, 31)
    f.learn(x, 1.0)
    p = f.projection.astype(np.float64)
    assert p.shape == (5, 31)
    np.testing.assert_allclose(p @ p.T, np.eye(5), atol=1e-5)
    flat = x.reshape(31, -1).astype(np.float64)
    energy = np.sum((p @ flat) ** 2, axis=1)
    assert np.all(np.diff(energy) <= 1e-6 * energy[0])  # largest first
    assert energy[:3].sum() / np.sum(flat**2) > 0.99  # the subspace is found
    f.learn(rng.random((31, 20, 20)).astype(np.float32), 0.5)
    np.testing.assert_array_equal(f.projection, p.astype(np.float32))
    with pytest.raises(ValueError, match="compressed"):
        _core.TranslationFilter(20, 20, 31, 1.5, 1e-3, 5).transform(x)


@pytest.mark.parametrize(("rows", "cols"), [(20, 23), (12, 5), (40, 40)])
def test_compressed_filter_is_the_filter_of_the_projected_features(rows: int, cols: int) -> None:
    """A compressed filter answers as an uncompressed one given the projected channels (the
    core projects with its weighted-row kernel, in blocks of lanes whatever the plane's size:
    they must add up as a matrix product does)."""
    rng = np.random.default_rng(21)
    a, b, z = (rng.random((31, rows, cols)).astype(np.float32) for _ in range(3))
    small = _core.TranslationFilter(rows, cols, 31, 1.5, 1e-3, 6)
    small.learn(a, 1.0)
    p = small.projection.astype(np.float64)

    def project(x: npt.NDArray[np.float32]) -> npt.NDArray[np.float32]:
        return (p @ x.reshape(31, -1).astype(np.float64)).astype(np.float32).reshape(6, rows, cols)

    plain = _core.TranslationFilter(rows, cols, 6, 1.5, 1e-3, 0)
    plain.learn(project(a), 1.0)
    small.learn(b, 0.3)
    plain.learn(project(b), 0.3)
    got, want = small.respond(z).values, plain.respond(project(z)).values
    np.testing.assert_allclose(got, want, atol=1e-4 * np.abs(want).max())


def test_response_map_matches_numpy() -> None:
    """Location.map: the response at every pixel of a region taken as the target's centre,
    bilinear between cells, wrapping around, divided by the peak, clipped to [0, 1]."""
    frame = texture(240, 320, 14)
    cf = CorrelationFilter()
    cf.init(frame, (130.0, 90.0, 60.0, 50.0))
    loc = cf.locate(shifted(frame, 2.5, -1.5), (160.0, 115.0))
    region = (100, 60, 230, 170)
    got = loc.map(region)
    r = loc.response.astype(np.float64)
    rows, cols = r.shape
    u = (np.arange(region[0], region[2]) - loc.centre[0]) / loc.cell[0]
    v = (np.arange(region[1], region[3]) - loc.centre[1]) / loc.cell[1]
    j0, i0 = np.floor(u).astype(int), np.floor(v).astype(int)
    fu, fv = u - j0, v - i0
    across = r[:, j0 % cols] * (1 - fu) + r[:, (j0 + 1) % cols] * fu
    want = across[i0 % rows] * (1 - fv)[:, None] + across[(i0 + 1) % rows] * fv[:, None]
    want = np.clip(want / r.max(), 0.0, 1.0)
    assert got.shape == (110, 130)
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-12)


def test_learning_from_the_search_sample_follows_the_target() -> None:
    """learn(from_search=True) reuses the last locate's sample on that frame, moved to the new
    box, when the box is near; a box far away, another frame, or no locate take a new
    sample. Either way the filter then finds the moved target."""
    frame = texture(240, 320, 15)
    box = (130.0, 90.0, 60.0, 50.0)
    cf = CorrelationFilter(CorrelationSettings(compressed=10))
    cf.init(frame, box)
    moved = shifted(frame, 5.0, 3.0)
    loc = cf.locate(moved, (160.0, 115.0))
    cf.learn(moved, (box[0] + loc.dx, box[1] + loc.dy, 60.0, 50.0), 0.5, from_search=True)
    assert cf.reused == 1
    cf.learn(moved, (box[0] + 5, box[1] + 3, 60.0, 50.0), 0.5, from_search=True)  # no locate
    assert cf.reused == 1
    cf.locate(moved, (165.0, 118.0))
    cf.learn(moved, (10.0, 10.0, 60.0, 50.0), 0.5, from_search=True)  # far: a new sample
    assert cf.reused == 1
    cf.locate(moved, (165.0, 118.0))
    cf.learn(frame, box, 0.5, from_search=True)  # another frame
    assert cf.reused == 1
    again = cf.locate(shifted(frame, 7.0, 4.0), (165.0, 118.0))
    assert abs(again.dx - 2.0) < 1.5 and abs(again.dy - 1.0) < 1.5, (again.dx, again.dy)


def test_scale_filter_learnt_with_a_shift_prefers_that_size() -> None:
    """The scale filter's learn_spectrum moves the label: answering the same samples then
    peaks ``shift`` samples off the middle; respond and respond_spectrum agree."""
    frame = texture(240, 320, 16, blur=1.5)
    factors = list(ScaleFilter().factors)
    args = (frame, (160.0, 120.0), (80.0, 60.0), factors, (20, 16), 4)
    samples = _core.scale_samples(*args)
    f = _core.ScaleFilter(33, samples.shape[1], math.sqrt(33) / 4, 1e-3)
    f.learn(samples, 1.0)
    spectrum = f.sample(*args)
    np.testing.assert_allclose(f.respond(samples).values, f.respond_spectrum(spectrum).values,
                               rtol=0, atol=1e-6)
    for shift in (3.0, -2.4):
        f.learn_spectrum(spectrum, 1.0, shift)
        r = f.respond_spectrum(spectrum)
        assert r.best + r.offset - 16 == pytest.approx(shift, abs=0.1)


def test_scale_settings_spanning_keeps_dssts_range() -> None:
    assert ScaleFilterSettings.spanning(33) == ScaleFilterSettings()
    s = ScaleFilterSettings.spanning(17, 0.05)
    assert s.num_scales == 17 and s.learning_rate == 0.05
    assert s.step**8 == pytest.approx(1.02**16)
    # the label as wide in log-size: sigma (samples) x log(step) is DSST's
    assert math.sqrt(17) * s.sigma_factor * math.log(s.step) == pytest.approx(
        math.sqrt(33) * 0.25 * math.log(1.02))
    with pytest.raises(ValueError, match="num_scales"):
        ScaleFilterSettings.spanning(16)


def test_the_new_core_calls_refuse_bad_arguments() -> None:
    """A spectrum of another filter, a shift that is not finite, a region without pixels, the
    wrong number of scale factors: ValueError naming the problem, nothing learnt."""
    rng = np.random.default_rng(17)
    x = rng.random((31, 20, 24)).astype(np.float32)
    f = _core.TranslationFilter(20, 24, 31, 1.5, 1e-3)
    g = _core.TranslationFilter(20, 24, 31, 1.5, 1e-3, 8)
    with pytest.raises(ValueError, match="learn"):
        f.learn_spectrum(f.transform(x), 0.5)  # the first learn takes features
    f.learn(x, 1.0)
    g.learn(x, 1.0)
    with pytest.raises(ValueError, match="shape"):
        f.learn_spectrum(g.transform(x), 0.5)
    with pytest.raises(ValueError, match="shape"):
        f.respond_spectrum(g.transform(x))
    with pytest.raises(ValueError, match="finite"):
        f.learn_spectrum(f.transform(x), 0.5, (math.nan, 0.0))
    with pytest.raises(ValueError, match="rate"):
        f.learn_spectrum(f.transform(x), 1.5)
    with pytest.raises(ValueError, match="compressed"):
        _core.TranslationFilter(20, 24, 31, 1.5, 1e-3, -1)
    r = f.respond(x, 5)
    with pytest.raises(ValueError, match="region"):
        r.map((10.0, 10.0), (2.0, 2.0), (5, 5, 5, 9))
    with pytest.raises(ValueError, match="cell"):
        r.map((10.0, 10.0), (0.0, 2.0), (0, 0, 5, 5))
    frame = texture(120, 160, 18)
    samples = _core.scale_samples(frame, (80.0, 60.0), (40.0, 30.0), [0.9, 1.0, 1.1], (20, 16), 4)
    s = _core.ScaleFilter(3, samples.shape[1], 1.0, 1e-3)
    s.learn(samples, 1.0)
    with pytest.raises(ValueError, match="factors"):
        s.sample(frame, (80.0, 60.0), (40.0, 30.0), [1.0, 1.1], (20, 16), 4)
    with pytest.raises(ValueError, match="dims"):
        s.sample(frame, (80.0, 60.0), (40.0, 30.0), [0.9, 1.0, 1.1], (24, 16), 4)
    with pytest.raises(ValueError, match="finite"):
        s.learn_spectrum(s.sample(frame, (80.0, 60.0), (40.0, 30.0), [0.9, 1.0, 1.1], (20, 16), 4),
                         0.5, math.inf)
    with pytest.raises(ValueError, match="compressed"):
        CorrelationSettings(compressed=32)
