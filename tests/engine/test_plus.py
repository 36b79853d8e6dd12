"""rcwmil-plus: its components, each switchable, and the box following a growing and shrinking target."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

import wmiltrack
from wmiltrack import _core
from wmiltrack.eval.metrics import iou


def zoom_sequence(n: int = 120, seed: int = 0) -> tuple[list[np.ndarray], np.ndarray]:
    """A textured target on a textured background that grows to 1.6x and shrinks back to 0.7x.

    The target is a fixed texture resized (area interpolation) to each frame's size and pasted
    at a centre drifting slowly; ground truth is the pasted box.
    """
    rng = np.random.default_rng(seed)
    h, w = 240, 320
    bg = cv2.resize(rng.integers(0, 256, (h // 8, w // 8, 3), dtype=np.uint8), (w, h),
                    interpolation=cv2.INTER_CUBIC)
    tex = cv2.resize(rng.integers(0, 256, (8, 6, 3), dtype=np.uint8), (120, 160),
                     interpolation=cv2.INTER_CUBIC)
    cv2.rectangle(tex, (20, 30), (90, 60), (250, 250, 250), -1)
    cv2.circle(tex, (60, 115), 25, (10, 10, 10), -1)
    frames, gt = [], []
    for i in range(n):
        u = i / (n - 1)
        s = 1.0 + 0.6 * math.sin(math.pi * min(u / 0.5, 1.0)) if u < 0.5 else 1.0 - 0.3 * math.sin(
            math.pi * (u - 0.5) / 0.5)
        tw, th = int(round(30 * s)), int(round(40 * s))
        cx, cy = 160 + 20 * math.sin(2 * math.pi * u), 120 + 10 * math.cos(2 * math.pi * u)
        x, y = int(round(cx - tw / 2)), int(round(cy - th / 2))
        f = bg.copy()
        f[y:y + th, x:x + tw] = cv2.resize(tex, (tw, th), interpolation=cv2.INTER_AREA)
        noise = rng.normal(0, 3, f.shape)
        frames.append(np.clip(f + noise, 0, 255).astype(np.uint8))
        gt.append((x, y, tw, th))
    return frames, np.array(gt, dtype=np.float64)


@pytest.fixture(scope="module")
def zoom() -> tuple[list[np.ndarray], np.ndarray]:
    return zoom_sequence()


def _run(frames: list[np.ndarray], gt: np.ndarray, variant: str, **overrides: object) -> np.ndarray:
    return wmiltrack.Tracker(variant, seed=0, **overrides).track(frames, gt[0])


def test_box_follows_growing_and_shrinking_target(zoom) -> None:
    frames, gt = zoom
    boxes = _run(frames, gt, "rcwmil-plus")
    ov = iou(boxes, gt)
    areas = boxes[:, 2] * boxes[:, 3]
    gt_areas = gt[:, 2] * gt[:, 3]
    peak = int(np.argmax(gt_areas))
    low = int(np.argmin(gt_areas[peak:])) + peak
    # the box grows with the target (2.56x its first area at the peak), then shrinks below its
    # first size (0.49x); measured for seed 0: 1.34x and 0.41x, mean IoU 0.66 (2.04x, 0.49x and
    # 0.82 without scale_contrast: the colour model learns the target's rim outside a box that
    # lags the growth as background, so the colour contrast holds the box back)
    assert areas[peak] > 1.3 * areas[0]
    assert areas[low] < 0.85 * areas[0]
    assert np.mean(ov) > 0.6
    # the fixed-size paper tracker cannot do this
    fixed = _run(frames, gt, "rcwmil")
    assert np.all(fixed[:, 2:] == fixed[0, 2:])
    assert np.mean(ov) > np.mean(iou(fixed, gt)) + 0.1


PAPER = ("rcwmil", "ct", "fct", "mil", "wmil", "osil")
#: Each rcwmil-plus component's field and the value that switches it off.
OFF = {"scale_steps": 0, "scale_negatives": 0, "channels": (), "motion": "none",
       "colour_weight": 0.0, "score_colour": 0.0, "score_colour_model": "current",
       "score_luma": 0.0, "scale_contrast": 0.0, "gray_colour": False, "redetect": False}


@pytest.mark.parametrize("variant", PAPER)
def test_paper_presets_switch_every_plus_component_off(variant: str) -> None:
    p = wmiltrack.Params.for_variant(variant)
    for name, off in OFF.items():
        assert getattr(p, name) == off, (variant, name)
    assert p.confidence_offset == 1.4


@pytest.mark.parametrize("variant", PAPER)
def test_paper_presets_are_the_appearance_model_alone(variant: str) -> None:
    """A paper preset composes no cue, scale estimator or motion model and the paper's policy,
    so its frame runs as one core call; rcwmil-plus composes all of them."""
    frame = np.zeros((60, 80, 3), dtype=np.uint8)
    frame[20:40, 30:50] = (40, 90, 200)
    t = wmiltrack.Tracker(variant, seed=0)
    t.init(frame, (30, 20, 20, 20))
    assert t.parts.appearance_only
    plus = wmiltrack.Tracker("rcwmil-plus", seed=0)
    plus.init(frame, (30, 20, 20, 20))
    parts = plus.parts
    assert parts.cues and parts.scale is not None and parts.motion is not None
    assert parts.recovery is not None
    assert not parts.policy.plain and not parts.appearance_only


@pytest.fixture(scope="module")
def demo() -> tuple[list[np.ndarray], np.ndarray]:
    from wmiltrack.data.synthetic import make_preset

    seq = make_preset("all", seed=2, n_frames=40)
    return seq.load(), np.asarray(seq.groundtruth)


@pytest.mark.parametrize("overrides", [
    {"scale_steps": 0, "scale_negatives": 0}, {"scale_model": "ratio"}, {"scale_model": "likelihood"},
    {"scale_negatives": 0}, {"scale_negatives": 4}, {"scale_contrast": 0.0}, {"colour_weight": 0.0}, {"colour_weight": 1.0}, {"channels": ("luma", "grad", "opp_rg", "opp_yb")},
    {"channels": ("luma", "grad")}, {"motion": "none"}, {"score_colour": 0.0, "score_luma": 0.0},
    {"redetect": False},
])
def test_each_component_switches_and_tracks(demo, overrides: dict[str, object]) -> None:
    frames, gt = demo
    boxes = _run(frames, gt, "rcwmil-plus", **overrides)
    assert boxes.shape == (len(frames), 4) and np.all(np.isfinite(boxes))
    assert np.mean(iou(boxes, gt)) > 0.3, overrides


def test_luma_channel_path_equals_the_single_integral_image(demo) -> None:
    frames, gt = demo
    a = _run(frames, gt, "rcwmil")
    b = _run(frames, gt, "rcwmil", channels=("luma",))
    np.testing.assert_array_equal(a, b)


def test_colour_channels_drop_out_for_gray_frames(demo) -> None:
    frames, gt = demo
    gray = [cv2.cvtColor(f, cv2.COLOR_BGR2GRAY) for f in frames]
    t = wmiltrack.Tracker("rcwmil-plus", seed=0, channels=("luma", "grad", "opp_rg", "opp_yb"))
    t.init(gray[0], gt[0])
    assert t.parts.appearance.chan_names == ("luma", "grad")
    for f in gray[1:]:
        t.update(f)
    assert t.parts.appearance.ii.channels == (_core.CH_LUMA, _core.CH_GRAD)
    c = wmiltrack.Tracker("rcwmil-plus", seed=0, gray_colour=False)
    c.init(gray[0], gt[0])
    assert c.parts.cues == []  # no colour likelihood on gray frames either
    c.init(frames[0], gt[0])
    assert len(c.parts.cues) == 1
    t.init(frames[0], gt[0])  # colour frames: all four
    assert t.parts.appearance.chan_names == ("luma", "grad", "opp_rg", "opp_yb")
    with pytest.raises(ValueError, match="gray"):
        t.update(gray[1])


def test_gray_colour_reads_luma_histograms_on_gray_frames_only(demo) -> None:
    frames, gt = demo
    gray = [cv2.cvtColor(f, cv2.COLOR_BGR2GRAY) for f in frames]
    on = wmiltrack.Tracker("rcwmil-plus", seed=0)
    on.init(gray[0], gt[0])
    assert on.parts.cues[0].model.histograms.intensity  # type: ignore[attr-defined]
    on.init(frames[0], gt[0])
    assert not on.parts.cues[0].model.histograms.intensity  # type: ignore[attr-defined]
    # colour frames: the option changes nothing
    np.testing.assert_array_equal(_run(frames, gt, "rcwmil-plus"),
                                  _run(frames, gt, "rcwmil-plus", gray_colour=False))
    # gray frames: the luma likelihood joins the search and the scale's contrast
    with_luma = _run(gray, gt, "rcwmil-plus")
    without = _run(gray, gt, "rcwmil-plus", gray_colour=False)
    assert not np.array_equal(with_luma, without)
    assert np.mean(iou(with_luma, gt)) > 0.5, np.mean(iou(with_luma, gt))


@pytest.mark.parametrize("value", [1, 0, None, "yes"])
def test_gray_colour_is_validated(value: object) -> None:
    with pytest.raises(ValueError, match="gray_colour"):
        wmiltrack.Params.for_variant("rcwmil-plus").replace(gray_colour=value)


def _box_sums(table: np.ndarray, x: np.ndarray, y: np.ndarray, w: np.ndarray,
              h: np.ndarray) -> np.ndarray:
    """Sums over ``[x, x + w) x [y, y + h)`` of the image of an integral table (table coordinates)."""
    return table[y + h, x + w] - table[y, x + w] - table[y + h, x] + table[y, x]


@pytest.mark.parametrize("index", [0, 1, -1])
def test_channel_features_are_sums_over_their_own_core_plane(demo, index: int) -> None:
    """Each feature of a ``channels=`` tracker reads its own channel's plane of the core's table."""
    frames, gt = demo
    names = ("luma", "grad", "opp_rg", "opp_yb")
    t = wmiltrack.Tracker("rcwmil", seed=3, channels=names)
    t.init(frames[0], gt[0])
    t.update(frames[1])
    model = t.parts.appearance
    ii = model.ii
    # plane k holds channel names[k], built by the core over the search region
    assert ii.channels == (_core.CH_LUMA, _core.CH_GRAD, _core.CH_OPP_RG, _core.CH_OPP_YB)
    fresh = _core.IntegralImage()
    fresh.compute_channels(frames[1], (ii.x0, ii.y0, ii.width, ii.height), list(ii.channels))
    tables = [fresh.table(k) for k in range(4)]
    for a, b in zip(tables, tables[1:]):
        assert not np.array_equal(a, b)  # the planes differ, so a wrong plane would show
    from wmiltrack.engine.features import scale_bank

    chan = model.feature_channel
    assert set(chan.tolist()) == {0, 1, 2, 3}
    scale = wmiltrack.Tracker("rcwmil-plus", seed=3, channels=names)
    scale.init(frames[0], gt[0])
    assert scale.parts.scale is not None
    bw, bh = scale.parts.scale.box_size(index)
    bank = model.bank(bw, bh)
    arrays = scale_bank(model.bank_arrays, *model.base_wh, bw, bh, model.edge_rects)
    np.testing.assert_array_equal(bank.channels, np.repeat(chan, np.diff(arrays.starts)))
    rng = np.random.default_rng(0)
    xs = rng.integers(ii.x0, ii.x0 + ii.width - bw + 1, size=7).astype(np.int32)
    ys = rng.integers(ii.y0, ii.y0 + ii.height - bh + 1, size=7).astype(np.int32)
    got = model.project(bw, bh, np.stack([xs, ys], axis=1))
    want = np.zeros((arrays.size, xs.size))
    for f in range(arrays.size):
        for r in range(arrays.starts[f], arrays.starts[f + 1]):
            rx, ry, rw, rh = arrays.rects[r]
            want[f] += arrays.weights[r] * _box_sums(tables[chan[f]], xs - ii.x0 + rx,
                                                     ys - ii.y0 + ry, rw, rh)
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-9)
    # on luma only, the same bank gives other values: the planes are really used
    luma = np.zeros_like(want)
    for f in range(arrays.size):
        for r in range(arrays.starts[f], arrays.starts[f + 1]):
            rx, ry, rw, rh = arrays.rects[r]
            luma[f] += arrays.weights[r] * _box_sums(tables[0], xs - ii.x0 + rx, ys - ii.y0 + ry,
                                                     rw, rh)
    assert not np.allclose(got[chan != 0], luma[chan != 0])


def test_scaled_bank_keeps_area_normalised_features() -> None:
    """On an image whose every pixel is the same, every feature has the same value at every scale."""
    from wmiltrack import _core
    from wmiltrack.engine.features import make_bank, scale_bank

    p = wmiltrack.Params.for_variant("rcwmil-plus")
    base = make_bank(p, 30, 40, np.random.default_rng(0))
    img = np.full((200, 200), 77, np.uint8)
    ii = _core.IntegralImage()
    ii.compute(img, (0, 0, 200, 200))
    ref = _core.project(ii, _core.FeatureBank(base.starts, base.rects, base.weights),
                        np.array([50], np.int32), np.array([50], np.int32))
    for w, h in ((27, 36), (33, 44), (45, 60), (10, 13)):
        b = scale_bank(base, 30, 40, w, h)
        assert np.all(b.rects[:, 0] + b.rects[:, 2] <= w) and np.all(b.rects[:, 1] + b.rects[:, 3] <= h)
        assert np.all(b.rects[:, 2:] >= 1)
        v = _core.project(ii, _core.FeatureBank(b.starts, b.rects, b.weights),
                          np.array([50], np.int32), np.array([50], np.int32))
        np.testing.assert_allclose(v, ref, rtol=1e-12, atol=1e-9)


def test_samples_report_the_scales_searched(demo) -> None:
    frames, gt = demo
    t = wmiltrack.Tracker("rcwmil-plus", seed=0)
    t.init(frames[0], gt[0])
    assert t.samples()["scales"] == []
    t.update(frames[1])
    s = t.samples()
    assert len(s["scales"]) == 2  # 1.03^-1 and 1.03^+1 around the current scale
    small, large = (b[2] * b[3] for b in s["scales"])
    assert small < large
    plain = wmiltrack.Tracker("rcwmil", seed=0)
    plain.init(frames[0], gt[0])
    plain.update(frames[1])
    assert plain.samples()["scales"] == []


def test_lost_target_gives_ok_false() -> None:
    """A target that vanishes (the scene is replaced by noise) is reported lost."""
    frames, gt = zoom_sequence(60, seed=1)
    rng = np.random.default_rng(5)
    blank = [rng.integers(0, 256, frames[0].shape, dtype=np.uint8) for _ in range(10)]
    t = wmiltrack.Tracker("rcwmil-plus", seed=0)
    t.init(frames[0], gt[0])
    for f in frames[1:30]:
        t.update(f)
    results = [t.update(f) for f in blank]
    assert not any(r.ok for r in results[2:])


def test_inspect_drawing_shows_the_scales(demo) -> None:
    from wmiltrack.visualize import draw_samples

    frames, gt = demo
    t = wmiltrack.Tracker("rcwmil-plus", seed=0)
    t.init(frames[0], gt[0])
    t.update(frames[1])
    s = t.samples()
    with_scales = draw_samples(frames[1], s)
    without = draw_samples(frames[1], {**s, "scales": []})
    def magenta(img: np.ndarray) -> int:
        b, g, r = (img[..., i].astype(int) for i in range(3))
        return int(np.count_nonzero((b > 200) & (r > 200) & (g < 80)))

    assert magenta(with_scales) > 50 and magenta(without) == 0


def test_colour_contrast_is_largest_for_the_box_that_holds_the_target() -> None:
    from reference_kernels import colour_contrast

    prob = np.zeros((120, 140))
    prob[50:80, 40:60] = 1.0  # the target: 20 x 30 at (40, 50)
    table = cv2.integral(prob, sdepth=cv2.CV_64F)
    exact = (40, 50, 20, 30)
    others = [(36, 46, 28, 38), (44, 54, 12, 22), (46, 50, 20, 30), (40, 44, 20, 30),
              (30, 40, 40, 50), (0, 0, 20, 30)]
    c = colour_contrast(table, 0, 0, np.array([exact, *others]))
    assert c[0] == pytest.approx(1.0)
    assert np.all(c[1:] < c[0] - 0.1)
    # the region may start anywhere in the frame, and rings are clipped to it
    c2 = colour_contrast(table, 10, 20, np.array([(50, 70, 20, 30), (10, 20, 20, 30)]))
    assert c2[0] == pytest.approx(1.0) and c2[1] < 0.5


def test_score_colour_changes_the_report_only(demo) -> None:
    frames, gt = demo

    def run(frames: list[np.ndarray], **kw: object) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        # the current colour model's contrast alone (the preset also reads the first frame's
        # histograms: see test_first_frame_scores_change_the_report_only)
        t = wmiltrack.Tracker("rcwmil-plus", seed=0, score_colour_model="current", score_luma=0.0,
                              redetect=False, **kw)  # ok: the score alone, no lost state
        t.init(frames[0], gt[0])
        rs = [t.update(f) for f in frames[1:]]
        return (np.array([r.box for r in rs]), np.array([r.score for r in rs]),
                np.array([r.ok for r in rs]))

    b0, s0, _ = run(frames, score_colour=0.0)
    b1, s1, ok1 = run(frames, score_colour=0.5)
    np.testing.assert_array_equal(b0, b1)  # the boxes do not depend on the report
    assert np.all((s1 >= 0) & (s1 <= 1)) and not np.allclose(s0, s1)
    np.testing.assert_array_equal(ok1, s1 >= wmiltrack.Params.for_variant("rcwmil-plus").lost_threshold)
    gray = [cv2.cvtColor(f, cv2.COLOR_BGR2GRAY) for f in frames]
    _, g0, _ = run(gray, score_colour=0.0, gray_colour=False)
    _, g1, _ = run(gray, score_colour=0.5, gray_colour=False)
    np.testing.assert_array_equal(g0, g1)  # no colour model on gray frames: the classifier's
    _, l0, _ = run(gray, score_colour=0.0)
    _, l1, _ = run(gray, score_colour=0.5)
    assert not np.allclose(l0, l1)  # gray_colour: the luma histograms' contrast


def test_score_drops_when_the_target_vanishes() -> None:
    frames, gt = zoom_sequence(60, seed=1)
    rng = np.random.default_rng(5)
    blank = [rng.integers(0, 256, frames[0].shape, dtype=np.uint8) for _ in range(10)]
    t = wmiltrack.Tracker("rcwmil-plus", seed=0)
    t.init(frames[0], gt[0])
    tracked = [t.update(f).score for f in frames[1:30]]
    lost = [t.update(f).score for f in blank]
    assert np.median(lost[2:]) < 0.5 < np.median(tracked)


@pytest.mark.parametrize("value", [-0.1, 1.5, True])
def test_score_colour_is_validated(value: object) -> None:
    with pytest.raises(ValueError, match="score_colour"):
        wmiltrack.Params.for_variant("rcwmil-plus", score_colour=value)


def _occluder(rng: np.random.Generator, h: int, w: int) -> np.ndarray:
    """A blocky random texture (8x8-pixel cells) of another colour range than the scene's."""
    cells = rng.integers(60, 200, size=(h // 8 + 1, w // 8 + 1, 3), dtype=np.uint8)
    return np.kron(cells, np.ones((8, 8, 1), dtype=np.uint8))[:h, :w]


@pytest.mark.parametrize("case", ["occluded", "vanished"])
def test_plus_score_falls_when_the_target_is_hidden(case: str) -> None:
    """The preset's reported score (classifier and first-frame colour contrast) drops once the
    target is fully covered by an occluder or the scene is swapped for one without it, and
    comes out on the lost side of ``lost_threshold``."""
    frames, gt = zoom_sequence(90, seed=1)
    rng = np.random.default_rng(7)
    hidden = range(40, 70)
    frames = [f.copy() for f in frames]
    if case == "occluded":
        for i in hidden:
            x, y, w, h = gt[i].astype(int)
            x0, y0 = max(x - w // 4, 0), max(y - h // 4, 0)
            x1, y1 = x + w + w // 4, y + h + h // 4
            frames[i][y0:y1, x0:x1] = _occluder(rng, y1 - y0, x1 - x0)
    else:
        other, _ = zoom_sequence(90, seed=4)
        scene = cv2.GaussianBlur(other[0], (0, 0), 8)  # another scene, no target in it
        for i in hidden:
            frames[i] = np.clip(scene + rng.normal(0, 3, scene.shape), 0, 255).astype(np.uint8)
    p = wmiltrack.Params.for_variant("rcwmil-plus")
    assert p.score_colour > 0 and p.score_colour_model == "first"
    t = wmiltrack.Tracker("rcwmil-plus", seed=0)
    t.init(frames[0], gt[0])
    rs = [t.update(f) for f in frames[1:hidden.stop]]
    tracked = np.array([r.score for r in rs[10:hidden.start - 1]])
    lost = np.array([r.score for r in rs[hidden.start + 1:hidden.stop - 1]])
    assert np.all((tracked >= 0) & (tracked <= 1)) and np.all((lost >= 0) & (lost <= 1))
    assert np.median(lost) < p.lost_threshold < np.median(tracked)
    assert np.percentile(lost, 90) < np.percentile(tracked, 10)
    # the classifier learns the occluder as it goes (its confidence creeps back towards 0.5);
    # the first frame's histograms do not, so most hidden frames stay reported lost
    assert np.mean([r.ok for r in rs[hidden.start + 1:hidden.stop - 1]]) < 1 / 3
    # and the score stays below that of the contrast under the colours learnt as it goes (the
    # two reports on the same boxes, those of the preset before scale_contrast and
    # colour_relative; with scale_contrast the occluded case's medians are 0.42 and 0.44, and
    # with colour_relative too 0.42 and 0.43)
    scores = []
    for model, luma in (("first", p.score_luma), ("current", 0.0)):
        t = wmiltrack.Tracker("rcwmil-plus", seed=0, scale_contrast=0.0, colour_relative=None,
                              score_colour_model=model, score_luma=luma, redetect=False)
        t.init(frames[0], gt[0])
        scores.append(np.array([t.update(f).score for f in frames[1:hidden.stop]]))
    first, adaptive = (s[hidden.start + 1:hidden.stop - 1] for s in scores)
    assert np.median(first) < np.median(adaptive) - 0.03


def test_first_frame_scores_change_the_report_only(demo) -> None:
    frames, gt = demo

    def run(fr: list[np.ndarray] | None = None, **kw: object
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        fr = frames if fr is None else fr
        # ok from the score alone: without the lost state (its own tests: test_recovery.py)
        t = wmiltrack.Tracker("rcwmil-plus", seed=0, redetect=False, **kw)
        t.init(fr[0], gt[0])
        rs = [t.update(f) for f in fr[1:]]
        return (np.array([r.box for r in rs]), np.array([r.score for r in rs]),
                np.array([r.ok for r in rs]))

    thr = wmiltrack.Params.for_variant("rcwmil-plus").lost_threshold
    b0, s0, _ = run(score_colour=0.0, score_luma=0.0)  # the classifier's confidence
    b1, s1, _ = run(score_colour=0.5, score_colour_model="current", score_luma=0.0)
    b2, s2, ok2 = run()  # the preset: first frame's colours and intensities
    b3, s3, _ = run(score_colour=0.0)  # intensities only
    for b in (b1, b2, b3):
        np.testing.assert_array_equal(b0, b)
    assert not np.allclose(s1, s2) and not np.allclose(s0, s2) and not np.allclose(s3, s2)
    assert np.all((s2 >= 0) & (s2 <= 1))
    np.testing.assert_array_equal(ok2, s2 >= thr)
    # gray frames: the same boxes; the intensity contrast still counts
    gray = [cv2.cvtColor(f, cv2.COLOR_BGR2GRAY) for f in frames]
    g0, gs0, _ = run(gray, score_colour=0.0, score_luma=0.0)
    g2, gs2, gok2 = run(gray)
    np.testing.assert_array_equal(g0, g2)
    assert not np.allclose(gs0, gs2) and np.all((gs2 >= 0) & (gs2 <= 1))
    np.testing.assert_array_equal(gok2, gs2 >= thr)
    # the first frame's histograms stay as they were learnt
    t = wmiltrack.Tracker("rcwmil-plus", seed=0)
    t.init(frames[0], gt[0])
    report = t.parts.policy.report
    assert report is not None
    firsts = [report.colour, report.luma]
    assert all(m is not None for m in firsts)
    before = [m.histograms.likelihood for m in firsts]  # type: ignore[union-attr]
    for f in frames[1:10]:
        t.update(f)
    for m, b in zip(firsts, before):
        np.testing.assert_array_equal(m.histograms.likelihood, b)  # type: ignore[union-attr]


@pytest.mark.parametrize("value", ["last", "", 1])
def test_score_colour_model_is_validated(value: object) -> None:
    with pytest.raises(ValueError, match="score_colour_model"):
        wmiltrack.Params.for_variant("rcwmil-plus", score_colour_model=value)


@pytest.mark.parametrize("value", [-0.1, 0.8, True, "0.3"])
def test_score_luma_is_validated(value: object) -> None:
    with pytest.raises(ValueError, match="score_luma"):  # 0.8: with score_colour 0.33, over 1
        wmiltrack.Params.for_variant("rcwmil-plus", score_luma=value)


def test_scaled_bank_keeps_edge_features() -> None:
    """On a gradient channel a rectangle's sum grows with the length of the edges it holds: a
    feature over a step edge keeps its value at every scale when its weights are marked as edge
    weights (sqrt of the area ratio), and would not with the area ratio."""
    from wmiltrack import _core
    from wmiltrack.engine.features import BankArrays, scale_bank

    img = np.zeros((200, 200), np.uint8)
    img[:, 100:] = 200  # one vertical step edge between columns 99 and 100
    ii = _core.IntegralImage()
    ii.compute_channels(img, (0, 0, 200, 200), [_core.CH_GRAD])
    base = BankArrays(starts=np.array([0, 1], np.int32), rects=np.array([[0, 0, 30, 40]], np.int32),
                      weights=np.array([1.0 / (30 * 40)]), subregion=np.array([-1], np.int32))

    def value(b: BankArrays, w: int, h: int) -> float:
        bank = _core.FeatureBank(b.starts, b.rects, b.weights)
        x = np.array([100 - w // 2], np.int32)  # the box centred on the edge
        return float(_core.project(ii, bank, x, np.array([50], np.int32))[0, 0])

    ref = value(base, 30, 40)
    assert ref > 0
    edge = np.array([True])
    for w, h in ((60, 80), (15, 20), (45, 60)):
        np.testing.assert_allclose(value(scale_bank(base, 30, 40, w, h, edge), w, h), ref, rtol=1e-12)
        assert not np.isclose(value(scale_bank(base, 30, 40, w, h), w, h), ref)


def test_a_colour_only_channel_list_is_refused() -> None:
    with pytest.raises(ValueError, match="gray channel"):
        wmiltrack.Params(channels=("opp_rg",))


@pytest.mark.parametrize("value", [-1.0, True, "20", math.inf])
def test_scale_contrast_is_validated(value: object) -> None:
    with pytest.raises(ValueError, match="scale_contrast"):
        wmiltrack.Params.for_variant("rcwmil-plus", scale_contrast=value)


def test_scale_contrast_reads_the_search_table(demo, monkeypatch) -> None:
    """Each tried scale's contrast is colour_contrast of its box on the search's likelihood
    table, the same as the colour model's own contrast of that box on the frame."""
    from wmiltrack.engine.cues import ColourCue

    frames, gt = demo
    seen: list[tuple[float, float]] = []
    original = ColourCue.contrast
    now: list[np.ndarray] = []

    def checked(self: ColourCue, box: tuple[int, int, int, int]) -> float:
        value = original(self, box)
        seen.append((value, self.model.contrast(now[-1], box)))
        return value

    monkeypatch.setattr(ColourCue, "contrast", checked)
    t = wmiltrack.Tracker("rcwmil-plus", seed=0)
    assert t.params.scale_contrast > 0
    t.init(frames[0], gt[0])
    for f in frames[1:6]:
        now.append(f)
        t.update(f)
    # the current scale and the two others, every frame
    assert len(seen) == 5 * 3
    got, want = np.array(seen).T
    assert got == pytest.approx(want, abs=1e-9)


def test_scale_contrast_moves_the_scale(demo, monkeypatch) -> None:
    """The contrast term enters each scale's value: a contrast that grows with the box makes
    the box grow every frame; with scale_contrast=0 it is never read."""
    from wmiltrack.engine.cues import ColourCue

    frames, gt = demo
    calls = []

    def bigger_is_better(self: ColourCue, box: tuple[int, int, int, int]) -> float:
        calls.append(box)
        return float(box[2] * box[3])

    monkeypatch.setattr(ColourCue, "contrast", bigger_is_better)
    t = wmiltrack.Tracker("rcwmil-plus", seed=0)
    t.init(frames[0], gt[0])
    for f in frames[1:5]:
        t.update(f)
    assert t.scale == pytest.approx(1.03 ** 4)
    calls.clear()
    off = wmiltrack.Tracker("rcwmil-plus", seed=0, scale_contrast=0.0)
    off.init(frames[0], gt[0])
    for f in frames[1:5]:
        off.update(f)
    assert calls == []


def test_scale_contrast_is_off_without_colour(demo, monkeypatch) -> None:
    from wmiltrack.engine.cues import ColourCue

    frames, gt = demo
    gray = [cv2.cvtColor(f, cv2.COLOR_BGR2GRAY) for f in frames[:5]]
    monkeypatch.setattr(ColourCue, "contrast", lambda self, box: pytest.fail("read"))
    t = wmiltrack.Tracker("rcwmil-plus", seed=0, gray_colour=False)
    t.init(gray[0], gt[0])
    for f in gray[1:]:
        t.update(f)


@pytest.mark.parametrize("value", [math.inf, math.nan, True, "0"])
def test_colour_relative_is_validated(value: object) -> None:
    with pytest.raises(ValueError, match="colour_relative"):
        wmiltrack.Params.for_variant("rcwmil-plus", colour_relative=value)



def test_colour_relative_in_the_preset_only() -> None:
    """The preset reads the classifier relative to the grid's best; no paper preset merges a
    colour cue, and ``None`` (the absolute reading) is accepted."""
    assert wmiltrack.Params.for_variant("rcwmil-plus").colour_relative == 0.0
    for name, p in wmiltrack.variants().items():
        if name not in ("rcwmil-plus", "rcwmil-cf", "rcwmil-nano"):
            assert p.colour_relative is None and p.colour_weight == 0.0
    assert wmiltrack.Params.for_variant("rcwmil-plus", colour_relative=None).colour_relative is None


@pytest.mark.parametrize("value", [0.0, -0.1, 1.5, math.nan, True])
def test_colour_learning_rate_is_validated(value: object) -> None:
    with pytest.raises(ValueError, match="colour_learning_rate"):
        wmiltrack.Params.for_variant("rcwmil-plus", colour_learning_rate=value)


def test_colour_learning_rate_reaches_the_colour_model() -> None:
    """The search's colour model blends frames at ``colour_learning_rate`` (0.02 in the preset,
    Staple's 0.04 by default); the first frame's copies for the score never learn."""
    frames, gt = zoom_sequence(3, seed=0)
    for rate in (None, 0.5):
        extra = {} if rate is None else {"colour_learning_rate": rate}
        t = wmiltrack.Tracker("rcwmil-plus", seed=0, **extra)
        t.init(frames[0], gt[0])
        report = t.parts.policy.report
        assert report is not None and report.colour is not None
        first = report.colour.histograms.likelihood
        t.update(frames[1])
        cue = t.parts.cues[0]
        assert cue.model.histograms.rate == (0.02 if rate is None else rate)  # type: ignore[attr-defined]
        assert np.array_equal(report.colour.histograms.likelihood, first)
    assert wmiltrack.Params().colour_learning_rate == 0.04
