"""Tests for wmiltrack.data.synthetic."""

from __future__ import annotations

import numpy as np
import pytest

from wmiltrack.data.sequences import Sequence
from wmiltrack.data.synthetic import PRESETS, make_preset, make_sequence


@pytest.fixture(scope="module")
def demo() -> Sequence:
    return make_sequence(150, seed=3)


def _box_pixels(seq: Sequence, t: int) -> np.ndarray:
    """Pixels fully inside the ground-truth box of frame ``t`` (as float)."""
    assert seq.groundtruth is not None
    x, y, w, h = seq.groundtruth[t]
    x0, y0 = int(np.ceil(x)), int(np.ceil(y))
    x1, y1 = int(np.floor(x + w)), int(np.floor(y + h))
    return np.asarray(seq.frame(t)[y0:y1, x0:x1], dtype=np.float64)


def test_shapes_dtypes_and_meta(demo: Sequence) -> None:
    assert len(demo) == 150
    assert demo.fps == 30.0
    assert demo.name == "synthetic-s3"
    for t in (0, 77, 149):
        f = demo.frame(t)
        assert f.shape == (240, 320, 3) and f.dtype == np.uint8
    assert demo.groundtruth is not None and demo.groundtruth.shape == (150, 4)
    assert np.isfinite(demo.groundtruth).all()
    np.testing.assert_array_equal(demo.groundtruth[:, 2:], np.tile([48.0, 40.0], (150, 1)))
    assert demo.init_box == tuple(demo.groundtruth[0])
    assert demo.meta["occlusion"].shape == (150,)
    assert demo.meta["gain"].shape == (150,)
    assert demo.meta["distractors"].shape == (150, 3, 4)


def test_custom_size_and_target() -> None:
    seq = make_sequence(5, size=(100, 90), target_size=(20, 30), seed=1, name="tiny")
    assert seq.name == "tiny"
    assert seq.frame(0).shape == (100, 90, 3)
    assert seq.groundtruth is not None
    np.testing.assert_array_equal(seq.groundtruth[:, 2:], np.tile([20.0, 30.0], (5, 1)))
    assert len(make_sequence(1)) == 1


def test_deterministic() -> None:
    one, two = make_sequence(40, seed=3), make_sequence(40, seed=3)
    assert one.groundtruth is not None and two.groundtruth is not None
    np.testing.assert_array_equal(one.groundtruth, two.groundtruth)
    for a, b in zip(one, two):
        np.testing.assert_array_equal(a, b)


def test_seeds_differ(demo: Sequence) -> None:
    other = make_sequence(30, seed=4)
    assert other.groundtruth is not None and demo.groundtruth is not None
    assert not np.allclose(other.groundtruth, demo.groundtruth[:30])
    assert np.abs(other.frame(0).astype(int) - demo.frame(0).astype(int)).mean() > 10


@pytest.mark.parametrize("seed", range(6))
def test_gt_inside_frame_and_speed_bound(seed: int) -> None:
    speed = 2.0 + seed
    seq = make_sequence(120, seed=seed, max_speed=speed, size=(120, 160), target_size=(30, 24))
    gt = seq.groundtruth
    assert gt is not None
    x, y, w, h = gt.T
    assert (x >= 0).all() and (y >= 0).all()
    assert (x + w <= 160).all() and (y + h <= 120).all()
    step = np.hypot(*np.diff(gt[:, :2], axis=0).T)
    assert step.max() <= speed + 1e-9
    assert step.mean() > 0.2 * speed  # it does move
    static = make_sequence(10, seed=seed, max_speed=0.0)
    assert static.groundtruth is not None
    assert np.ptp(static.groundtruth, axis=0).max() == 0


def test_rendered_target_follows_groundtruth() -> None:
    # without nuisances the target patch looks the same wherever the ground truth says it is
    seq = make_preset("easy", seed=5, n_frames=60, noise=0.0)
    assert seq.groundtruth is not None
    ref = seq.frame(0)
    x, y, w, h = seq.groundtruth[0]
    errors = []
    for t in (20, 40, 59):
        xt, yt = seq.groundtruth[t, :2]
        dx, dy = round(xt) - round(x), round(yt) - round(y)
        xi, yi = round(x) + 2, round(y) + 2
        a = ref[yi : yi + int(h) - 4, xi : xi + int(w) - 4].astype(float)
        b = seq.frame(t)[yi + dy : yi + dy + int(h) - 4, xi + dx : xi + dx + int(w) - 4]
        errors.append(np.abs(a - b).mean())
    assert max(errors) < 6  # rounding to whole pixels only (a 2 px misplacement gives ~8)


def test_occlusion_covers_part_of_target() -> None:
    with_occ = make_sequence(100, seed=7, occlusion=True, illumination=False, clutter=False)
    without = make_sequence(100, seed=7, occlusion=False, illumination=False, clutter=False)
    frac = with_occ.meta["occlusion"]
    occluded = np.nonzero(frac > 0)[0]
    assert 10 <= len(occluded) <= 40
    assert 0.3 <= frac.max() <= 0.55
    assert (frac == 0).sum() > 50
    assert without.meta["occlusion"].max() == 0
    # only the occluder differs between the two renderings
    for t in range(100):
        a, b = _box_pixels(with_occ, t), _box_pixels(without, t)
        changed = (np.abs(a - b).max(axis=2) > 0).mean()
        if frac[t] == 0:
            assert changed == 0, t
        else:
            assert changed == pytest.approx(frac[t], abs=0.12), t
    t = int(np.argmax(frac))
    assert np.abs(_box_pixels(with_occ, t) - _box_pixels(without, t)).mean() > 10


def test_illumination_changes_target_brightness() -> None:
    lit = make_sequence(120, seed=2, occlusion=False, illumination=True, clutter=False)
    flat = make_sequence(120, seed=2, occlusion=False, illumination=False, clutter=False)
    gain = lit.meta["gain"]
    assert gain[0] == pytest.approx(1.0)
    assert gain.min() == pytest.approx(0.6, abs=0.02)
    assert gain.max() == pytest.approx(1.3, abs=0.02)
    dark, bright = int(np.argmin(gain)), int(np.argmax(gain))
    lit_means = [_box_pixels(lit, t).mean() for t in (dark, bright)]
    flat_means = [_box_pixels(flat, t).mean() for t in (dark, bright)]
    assert lit_means[1] > 1.4 * lit_means[0]
    assert abs(flat_means[1] - flat_means[0]) < 0.1 * flat_means[0]
    assert np.all(flat.meta["gain"] == 1.0)
    # frame 0 is not relit (gain 1, no offset); the shadow band starts off-screen
    assert np.abs(lit.frame(0).astype(int) - flat.frame(0).astype(int)).mean() < 1.0


def test_clutter_adds_distractors() -> None:
    busy = make_sequence(30, seed=9, occlusion=False, illumination=False, clutter=True)
    calm = make_sequence(30, seed=9, occlusion=False, illumination=False, clutter=False)
    boxes = busy.meta["distractors"]
    assert boxes.shape == (30, 3, 4)
    assert calm.meta["distractors"].shape == (30, 0, 4)
    assert busy.groundtruth is not None and calm.groundtruth is not None
    np.testing.assert_array_equal(busy.groundtruth, calm.groundtruth)  # same target path
    diff = np.abs(busy.frame(10).astype(int) - calm.frame(10).astype(int)).max(axis=2) > 0
    for x, y, w, h in boxes[10]:
        assert diff[int(y) + 2 : int(y + h) - 2, int(x) + 2 : int(x + w) - 2].mean() > 0.5
    assert np.ptp(boxes[:, :, :2], axis=0).max() > 5  # they move


def test_noise_is_gaussian_like() -> None:
    clean = make_sequence(3, seed=1, noise=0.0, occlusion=False, illumination=False, clutter=False)
    noisy = make_sequence(3, seed=1, noise=6.0, occlusion=False, illumination=False, clutter=False)
    d = noisy.frame(1).astype(float) - clean.frame(1).astype(float)
    assert abs(d.mean()) < 0.5
    assert 5.0 < d.std() < 7.0


def test_presets() -> None:
    assert {"easy", "occlusion", "illumination", "clutter", "all"} <= set(PRESETS)
    easy = make_preset("easy", seed=1, n_frames=20)
    assert easy.name == "synthetic-easy-s1" and len(easy) == 20
    assert easy.meta["occlusion"].max() == 0 and np.all(easy.meta["gain"] == 1.0)
    assert easy.meta["params"]["max_speed"] == PRESETS["easy"]["max_speed"]
    occ = make_preset("occlusion", n_frames=60)
    assert occ.meta["occlusion"].max() > 0.3
    assert make_preset("all", n_frames=5, name="x").name == "x"
    with pytest.raises(ValueError, match="unknown preset"):
        make_preset("nope")


def test_invalid_arguments() -> None:
    with pytest.raises(ValueError):
        make_sequence(0)
    with pytest.raises(ValueError, match="does not fit"):
        make_sequence(5, size=(40, 40), target_size=(48, 40))
    with pytest.raises(ValueError):
        make_sequence(5, max_speed=-1.0)
    with pytest.raises(ValueError):
        make_sequence(5, noise=-1.0)


def test_full_occlusion_and_out_of_view_windows() -> None:
    """A full occlusion hides the whole box (the ground truth keeps it), out of view removes
    the target (NaN ground truth); both are marked not visible, and the sequence is otherwise
    the one generated without them."""
    plain = make_sequence(40, seed=3, occlusion=False)
    seq = make_sequence(40, seed=3, occlusion=False, full_occlusion=(10, 5), out_of_view=(25, 6))
    frames, gt = seq.load(), np.asarray(seq.groundtruth)
    visible = seq.meta["visible"]
    assert visible.dtype == bool and not visible[10:15].any() and not visible[25:31].any()
    assert visible[:10].all() and visible[15:25].all() and visible[31:].all()
    np.testing.assert_array_equal(gt[:25], np.asarray(plain.groundtruth)[:25])
    assert np.isnan(gt[25:31]).all() and np.isfinite(gt[31:]).all()
    assert np.all(seq.meta["occlusion"][10:15] == 1.0)
    base = plain.load()
    for i in (0, 9, 15, 24, 31, 39):  # untouched frames are the same pixels
        np.testing.assert_array_equal(frames[i], base[i])
    x, y, w, h = (int(v) for v in gt[12])
    assert not np.array_equal(frames[12][y:y + h, x:x + w], base[12][y:y + h, x:x + w])
    for i in (25, 30):  # the target's place differs from the plain sequence: it is not drawn
        x, y, w, h = (int(v) for v in np.asarray(plain.groundtruth)[i])
        assert not np.array_equal(frames[i][y:y + h, x:x + w], base[i][y:y + h, x:x + w])
    with pytest.raises(ValueError, match="overlap"):
        make_sequence(40, full_occlusion=(10, 10), out_of_view=(15, 5))
    with pytest.raises(ValueError, match="out_of_view"):
        make_sequence(40, out_of_view=(0, 5))
