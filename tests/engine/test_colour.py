"""engine.colour: the colour likelihood that rcwmil-plus merges with its classifier score."""

from __future__ import annotations

import numpy as np
import pytest
from reference_kernels import box_means, colour_contrast

from wmiltrack.engine.colour import ColourModel, is_colour


def scene(rng: np.random.Generator) -> np.ndarray:
    """Blue-green noisy background with a red-ish 20x16 target at (30, 20)."""
    img = np.empty((80, 100, 3), np.uint8)
    img[..., 0] = rng.integers(150, 250, (80, 100))   # B
    img[..., 1] = rng.integers(80, 180, (80, 100))    # G
    img[..., 2] = rng.integers(0, 60, (80, 100))      # R
    img[20:36, 30:50, 0] = rng.integers(0, 60, (16, 20))
    img[20:36, 30:50, 1] = rng.integers(0, 60, (16, 20))
    img[20:36, 30:50, 2] = rng.integers(180, 255, (16, 20))
    return img


def test_is_colour() -> None:
    rng = np.random.default_rng(0)
    g = rng.integers(0, 256, (10, 12), dtype=np.uint8)
    assert not is_colour(g)
    assert not is_colour(np.dstack([g, g, g]))           # gray video saved as BGR
    assert is_colour(scene(rng))
    assert is_colour(np.dstack([g, g, g, g * 0 + 3])) is False


def test_target_scores_high_background_low() -> None:
    rng = np.random.default_rng(1)
    img = scene(rng)
    cm = ColourModel(bits=3)  # 512 bins: every colour of this scene is seen while learning
    cm.learn(img, (30, 20, 20, 16))
    table, x0, y0 = cm.integral(img, (0, 0, 100, 80))
    means = box_means(table, x0, y0, np.array([30, 60, 5]), np.array([20, 50, 5]), 20, 16)
    assert means[0] > 0.95 and means[1] < 0.05 and means[2] < 0.05
    # a box half on the target scores about half
    half = box_means(table, x0, y0, np.array([40]), np.array([20]), 20, 16)[0]
    assert 0.4 < half < 0.6


def test_integral_matches_brute_force_and_is_clipped() -> None:
    rng = np.random.default_rng(2)
    img = scene(rng)
    cm = ColourModel(bits=4)
    cm.learn(img, (30, 20, 20, 16))
    table, x0, y0 = cm.integral(img, (-10, 5, 70, 200))       # clipped to the frame
    assert (x0, y0) == (0, 5) and table.shape == (80 - 5 + 1, 70 + 1)
    s = 8 - cm.bits
    idx = ((img[5:, :70, 0] >> s).astype(int) << 8) | ((img[5:, :70, 1] >> s).astype(int) << 4) | (
        img[5:, :70, 2] >> s).astype(int)
    f, b = cm.histograms.foreground[idx], cm.histograms.background[idx]
    p = np.where(f + b > 0, f / np.where(f + b > 0, f + b, 1), 0.5)
    got = box_means(table, x0, y0, np.array([3]), np.array([9]), 11, 7)[0]
    assert got == pytest.approx(p[4:11, 3:14].mean(), rel=1e-12)


def test_learning_rate_blends_histograms() -> None:
    rng = np.random.default_rng(3)
    a = scene(rng)
    b = a.copy()
    b[20:36, 30:50] = (0, 200, 0)  # the target turns green
    cm = ColourModel(learning_rate=0.5)
    cm.learn(a, (30, 20, 20, 16))
    table, x0, y0 = cm.integral(b, (0, 0, 100, 80))
    before = box_means(table, x0, y0, np.array([30]), np.array([20]), 20, 16)[0]
    cm.learn(b, (30, 20, 20, 16))
    table, x0, y0 = cm.integral(b, (0, 0, 100, 80))
    after = box_means(table, x0, y0, np.array([30]), np.array([20]), 20, 16)[0]
    assert after > before + 0.3


def test_errors() -> None:
    with pytest.raises(ValueError, match="bits"):
        ColourModel(bits=0)
    with pytest.raises(ValueError, match="learning_rate"):
        ColourModel(learning_rate=0.0)
    with pytest.raises(ValueError, match="learn"):
        ColourModel().integral(np.zeros((4, 4, 3), np.uint8), (0, 0, 4, 4))


def _sampled(region: tuple[int, int, int, int], step: int) -> np.ndarray:
    """The region's pixels whose frame row and column are multiples of step."""
    x, y, w, h = region
    return (((np.arange(y, y + h) % step) == 0)[:, None]
            & ((np.arange(x, x + w) % step) == 0)[None, :])


def _bins_numpy(patch: np.ndarray, bits: int) -> np.ndarray:
    s = 8 - bits
    b, g, r = ((patch[..., c] >> s).astype(np.int64) for c in range(3))
    return (b << (2 * bits)) | (g << bits) | r


class _NumpyHistograms:
    """The colour model's update over every bin, in numpy: what the core must equal bit for bit."""

    def __init__(self, bits: int, rate: float, step: int = 1) -> None:
        n = 1 << (3 * bits)
        self.bits, self.rate, self.step = bits, rate, step
        self.fg, self.bg, self.lik = np.zeros(n), np.zeros(n), np.full(n, 0.5)
        self.first = True

    def learn(self, frame: np.ndarray, region: tuple[int, int, int, int],
              inside: tuple[int, int, int, int], core: tuple[int, int, int, int]) -> None:
        x, y, w, h = region
        idx = _bins_numpy(frame[y:y + h, x:x + w], self.bits)
        m_in = np.zeros(idx.shape, bool)
        m_in[inside[0]:inside[1], inside[2]:inside[3]] = True
        m_core = np.zeros(idx.shape, bool)
        m_core[core[0]:core[1], core[2]:core[3]] = True
        sampled = _sampled(region, self.step)
        n = self.fg.size
        fc = np.bincount(idx[m_core & sampled], minlength=n).astype(float)
        bc = np.bincount(idx[~m_in & sampled], minlength=n).astype(float)
        f, b = fc / max(fc.sum(), 1.0), bc / max(bc.sum(), 1.0)
        keep = 1.0 - self.rate
        self.fg = f if self.first else keep * self.fg + self.rate * f
        self.bg = b if self.first else keep * self.bg + self.rate * b
        total = self.fg + self.bg
        self.lik = np.where(total > 0, self.fg / np.where(total > 0, total, 1.0), 0.5)
        self.first = False


@pytest.mark.parametrize("bits", [1, 3, 5, 6])
@pytest.mark.parametrize("channels", [3, 4])
def test_core_histograms_match_numpy_bit_for_bit(bits: int, channels: int) -> None:
    """Counts, blend and likelihood over several frames, and the likelihood's integral image,
    equal a numpy pass over every bin (the core only visits the bins seen) and cv2.integral."""
    import cv2

    from wmiltrack import _core

    rng = np.random.default_rng(bits * 10 + channels)
    frames = [rng.integers(0, 256, (37, 53, channels), dtype=np.uint8) for _ in range(4)]
    frames[2][:] = frames[1]  # a frame with no new colour
    frames[3] = np.ascontiguousarray(frames[3][:, ::-1])[:, ::-1]  # a strided view
    core_h = _core.ColourHistograms(bits, 0.3)
    ref = _NumpyHistograms(bits, 0.3)
    spans = [((4, 20, 6, 30), (6, 18, 9, 27)), ((0, 30, 0, 41), (2, 5, 3, 4)),
             ((10, 10, 5, 5), (0, 0, 0, 0)), ((30, 40, 40, 50), (1, 29, 1, 40))]
    region = (5, 3, 41, 30)
    for frame, (inside, core) in zip(frames, spans):
        core_h.learn(frame, region, inside, core)
        ref.learn(frame, region, inside, core)
        np.testing.assert_array_equal(core_h.foreground, ref.fg)
        np.testing.assert_array_equal(core_h.background, ref.bg)
        np.testing.assert_array_equal(core_h.likelihood, ref.lik)
        x, y, w, h = 2, 1, 47, 33
        want = cv2.integral(ref.lik[_bins_numpy(frame[y:y + h, x:x + w], bits)], sdepth=cv2.CV_64F)
        np.testing.assert_array_equal(core_h.likelihood_integral(frame, (x, y, w, h)), want)
        p = ref.lik[_bins_numpy(frame[y:y + h, x:x + w], bits)]
        inner, whole, n_inner, n_whole = core_h.likelihood_sums(frame, (x, y, w, h),
                                                                (3, 20, -4, 30))  # clipped
        assert inner == pytest.approx(p[3:20, 0:30].sum(), rel=1e-12)
        assert whole == pytest.approx(p.sum(), rel=1e-12)
        assert (n_inner, n_whole) == (17 * 30, w * h)


@pytest.mark.parametrize("step", [2, 3])
def test_core_histograms_step_reads_the_frame_grid(step: int) -> None:
    """With step > 1, learning and the likelihood sums see exactly the pixels whose frame row
    and column are multiples of step (numpy over those pixels); the integral reads all."""
    import cv2

    from wmiltrack import _core

    rng = np.random.default_rng(step)
    frames = [rng.integers(0, 256, (41, 57, 3), dtype=np.uint8) for _ in range(3)]
    core_h = _core.ColourHistograms(4, 0.3)
    ref = _NumpyHistograms(4, 0.3, step)
    for frame, region in zip(frames, [(5, 3, 41, 30), (0, 0, 57, 41), (7, 2, 33, 37)]):
        inside, core = (4, 20, 6, 30), (6, 18, 9, 27)
        core_h.learn(frame, region, inside, core, step=step)
        ref.learn(frame, region, inside, core)
        np.testing.assert_array_equal(core_h.foreground, ref.fg)
        np.testing.assert_array_equal(core_h.background, ref.bg)
        x, y, w, h = 3, 1, 47, 33
        p = ref.lik[_bins_numpy(frame[y:y + h, x:x + w], 4)]
        want = cv2.integral(p, sdepth=cv2.CV_64F)
        np.testing.assert_array_equal(core_h.likelihood_integral(frame, (x, y, w, h)), want)
        sampled = _sampled((x, y, w, h), step)
        inner_mask = np.zeros_like(sampled)
        inner_mask[3:20, 5:30] = True
        inner, whole, n_inner, n_whole = core_h.likelihood_sums(frame, (x, y, w, h),
                                                                (3, 20, 5, 30), step=step)
        assert inner == pytest.approx(p[sampled & inner_mask].sum(), rel=1e-12)
        assert whole == pytest.approx(p[sampled].sum(), rel=1e-12)
        assert (n_inner, n_whole) == ((sampled & inner_mask).sum(), sampled.sum())
    with pytest.raises(ValueError, match="step"):
        core_h.learn(frames[0], (0, 0, 10, 10), (0, 5, 0, 5), (1, 4, 1, 4), step=0)


def test_core_histograms_refuse_bad_input() -> None:
    from wmiltrack import _core

    frame = np.zeros((20, 30, 3), np.uint8)
    h = _core.ColourHistograms(5, 0.04)
    with pytest.raises(ValueError, match="learn"):
        h.likelihood_integral(frame, (0, 0, 10, 10))
    with pytest.raises(ValueError, match="learn"):
        h.likelihood_sums(frame, (0, 0, 10, 10), (2, 5, 2, 5))
    with pytest.raises(ValueError):
        h.learn(frame[..., 0], (0, 0, 10, 10), (0, 5, 0, 5), (1, 4, 1, 4))  # gray
    with pytest.raises(ValueError):
        h.learn(frame, (25, 0, 10, 10), (0, 5, 0, 5), (1, 4, 1, 4))  # outside the frame
    with pytest.raises(ValueError, match="bits"):
        _core.ColourHistograms(0, 0.04)
    with pytest.raises(ValueError, match="rate"):
        _core.ColourHistograms(5, 0.0)
    assert not h.learnt
    h.learn(frame, (0, 0, 10, 10), (0, 5, 0, 5), (1, 4, 1, 4))
    assert h.learnt and h.foreground.sum() == 1.0


def test_contrast_of_one_box_equals_the_integral_image_one() -> None:
    rng = np.random.default_rng(3)
    frame = scene(rng)
    fh, fw = frame.shape[:2]
    model = ColourModel()
    model.learn(frame, (40, 30, 30, 40))
    table, x0, y0 = model.integral(frame, (0, 0, fw, fh))
    boxes = [(40, 30, 30, 40), (0, 0, 20, 25), (fw - 12, fh - 9, 12, 9), (5, fh - 30, 60, 30)]
    for _ in range(50):
        w, h = (int(v) for v in rng.integers(4, 60, 2))
        boxes.append((int(rng.integers(0, fw - w + 1)), int(rng.integers(0, fh - h + 1)), w, h))
    expected = colour_contrast(table, x0, y0, np.array(boxes))
    got = [model.contrast(frame, b) for b in boxes]
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-12)
    copy = model.copy()
    model.learn(frame, (0, 0, 20, 25))  # the copy keeps its histograms
    assert copy.contrast(frame, boxes[0]) == pytest.approx(got[0], abs=1e-12)
    with pytest.raises(ValueError, match="learn"):
        ColourModel().contrast(frame, boxes[0])


@pytest.mark.parametrize("sample", [0, 500])
def test_intensity_model_is_the_colour_model_of_the_luma(sample: int) -> None:
    """An intensity model learns from a BGR, BGRA or gray frame exactly what a colour model
    learns from the frame's luma (cv2.COLOR_BGR2GRAY) repeated in three channels."""
    import cv2

    rng = np.random.default_rng(4)
    frame = scene(rng)
    gray = cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
    gray3 = cv2.merge([gray, gray, gray])
    bgra = cv2.cvtColor(frame, cv2.COLOR_BGR2BGRA)
    box = (30, 20, 20, 16)
    ref = ColourModel(sample=sample)
    ref.learn(gray3, box)
    for img in (frame, bgra, gray, gray[:, :, None]):
        model = ColourModel(intensity=True, sample=sample)
        model.learn(img, box)
        np.testing.assert_array_equal(model.histograms.foreground, ref.histograms.foreground)
        np.testing.assert_array_equal(model.histograms.likelihood, ref.histograms.likelihood)
        for b in (box, (0, 0, 30, 30), (60, 50, 40, 30)):
            assert model.contrast(img, b) == ref.contrast(gray3, b)
        table, _, _ = model.integral(img, (0, 0, 100, 80))
        np.testing.assert_array_equal(table, ref.integral(gray3, (0, 0, 100, 80))[0])
    with pytest.raises(ValueError, match="BGR"):
        ColourModel().learn(gray, box)  # a colour model needs colour


def test_box_contrast_equals_colour_contrast() -> None:
    """The scalar one-box contrast (rcwmil-plus's scale search) gives colour_contrast's bits,
    for boxes inside, across and outside the table's region."""
    from wmiltrack.engine.colour import box_contrast

    rng = np.random.default_rng(3)
    table = np.pad(rng.random((90, 120)).cumsum(0).cumsum(1), ((1, 0), (1, 0)))
    for _ in range(2000):
        box = (int(rng.integers(-30, 140)), int(rng.integers(-30, 110)), int(rng.integers(1, 80)),
               int(rng.integers(1, 80)))
        x0, y0 = int(rng.integers(-5, 15)), int(rng.integers(-5, 15))
        ring = float(rng.choice([0.1, 0.25, 0.5]))
        want = colour_contrast(table, x0, y0, np.array([box]), ring=ring)[0]
        assert box_contrast(table, x0, y0, box, ring=ring) == want
