"""What distinguishes each variant of the family, and that each one tracks."""

from __future__ import annotations

import math

import numpy as np
import pytest

import wmiltrack
from wmiltrack.data import synthetic
from wmiltrack.engine import tracker as tracker_mod
from wmiltrack.engine.params import Params
from wmiltrack.eval.metrics import ope_metrics

FRAME = np.random.default_rng(0).integers(0, 256, size=(300, 400, 3), dtype=np.uint8)
BOX = (180, 130, 40, 48)


def bank(variant: str, seed: int = 0):
    t = wmiltrack.Tracker(variant, seed=seed)
    t.init(FRAME, BOX)
    return t, t._bank_arrays


def rect_counts(b) -> np.ndarray:
    return np.diff(b.starts)


def test_ct_features_random_rectangles_on_raw_sums() -> None:
    _, b = bank("ct")
    assert b.size == 50
    assert set(rect_counts(b)) == {2, 3}
    for f in range(b.size):
        n = rect_counts(b)[f]
        w = b.weights[b.starts[f]:b.starts[f + 1]]
        assert np.allclose(np.abs(w), 1 / math.sqrt(n))  # +-1/sqrt(n), no area normalisation
    r = b.rects
    assert r[:, 0].max() <= 40 - 4 and np.all(r[:, 0] + r[:, 2] <= 40 - 2)


def test_fct_features_are_area_normalised() -> None:
    _, b = bank("fct")
    assert b.size == 100 and set(rect_counts(b)) == {2, 3, 4}
    area = b.rects[:, 2] * b.rects[:, 3]
    assert np.allclose(np.abs(b.weights) * area, 1.0)
    assert b.rects[:, 0].min() >= 1 and b.rects[:, 2].min() >= 2


def test_mil_and_wmil_features_have_uniform_weights() -> None:
    _, m = bank("mil")
    assert m.size == 250 and set(rect_counts(m)) == {2, 3, 4, 5, 6}
    assert np.abs(m.weights).max() <= 1 and len(np.unique(np.round(np.abs(m.weights), 6))) > 100
    _, w = bank("wmil")
    assert w.size == 150 and set(rect_counts(w)) == {2, 3}


@pytest.mark.parametrize("variant", ["rcwmil", "osil"])
def test_subregion_features_stay_in_their_quadrant_with_size_limits(variant: str) -> None:
    _, b = bank(variant)
    W, H = BOX[2], BOX[3]
    quads = {0: (0, 0), 1: (W // 2, 0), 2: (0, H // 2), 3: (W // 2, H // 2)}
    signs = []
    for f in range(b.size):
        qx, qy = quads[f % 4]
        sw = W // 2 if qx == 0 else W - W // 2
        sh = H // 2 if qy == 0 else H - H // 2
        for r in range(b.starts[f], b.starts[f + 1]):
            x, y, w, h = b.rects[r]
            assert qx <= x and x + w <= qx + sw and qy <= y and y + h <= qy + sh
            assert max(2, math.ceil(0.2 * sw)) <= w <= math.floor(0.8 * sw)
            assert max(2, math.ceil(0.2 * sh)) <= h <= math.floor(0.8 * sh)
            assert np.isclose(abs(b.weights[r]) * w * h, 1.0)
            signs.append(np.sign(b.weights[r]))
    assert set(rect_counts(b)) == {2, 3, 4}
    assert 0.70 < np.mean(np.array(signs) > 0) < 0.86  # P(+1) = 0.78


def test_positive_sign_proportion_over_many_banks() -> None:
    signs = np.concatenate([np.sign(bank("rcwmil", seed=s)[1].weights) for s in range(10)])
    assert abs(np.mean(signs > 0) - 0.78) < 0.03


SEARCH = {
    "rcwmil": [(25, 4), (10, 1)],
    "fct": [(25, 4), (10, 1)],
    "ct": [(20, 1)],
    "osil": [(20, 1)],
    "mil": [(25, 1)],
    "wmil": [(25, 1)],
}
CANDIDATES = {(25, 4): 121, (10, 1): 305, (20, 1): 1245, (25, 1): 1941}


@pytest.mark.parametrize("variant", list(SEARCH))
def test_search_grids(variant: str, monkeypatch: pytest.MonkeyPatch) -> None:
    calls = []
    real = tracker_mod._core.score_grid

    def spy(*args, **kw):
        out = real(*args, **kw)
        calls.append((args[9], args[10], out[3], len(args[2])))
        return out

    t, _ = bank(variant)
    monkeypatch.setattr(tracker_mod._core, "score_grid", spy)
    t.update(FRAME)
    assert [(r, s) for r, s, _, _ in calls] == SEARCH[variant]
    assert [n for _, _, n, _ in calls] == [CANDIDATES[g] for g in SEARCH[variant]]
    assert {k for *_, k in calls} == {t.params.num_selected}


@pytest.mark.parametrize("variant,expected", [
    ("rcwmil", ("wmil", "exp", 20)), ("wmil", ("wmil", "exp", 15)), ("osil", ("wmil", "uniform", 20)),
    ("mil", ("milboost", None, 50)), ("ct", (None, None, 50)), ("fct", (None, None, 100)),
])
def test_bag_model_and_selection(variant: str, expected, monkeypatch: pytest.MonkeyPatch) -> None:
    seen = []
    real_w, real_m = tracker_mod.wmil_select, tracker_mod.milboost_select

    def spy_w(h_pos, h_neg, w, k, **kw):
        seen.append(("wmil", w, k))
        return real_w(h_pos, h_neg, w, k, **kw)

    def spy_m(h_pos, h_neg, k, **kw):
        seen.append(("milboost", None, k))
        return real_m(h_pos, h_neg, k, **kw)

    monkeypatch.setattr(tracker_mod, "wmil_select", spy_w)
    monkeypatch.setattr(tracker_mod, "milboost_select", spy_m)
    t, _ = bank(variant)
    t.update(FRAME)
    kind, weights, k = expected
    if kind is None:
        assert seen == [] and len(t._selected) == k == t.params.num_features
        return
    assert {s[0] for s in seen} == {kind} and all(s[2] == k for s in seen)
    if weights == "exp":
        w = seen[-1][1]
        assert np.isclose(w.sum(), 1) and w.max() / w.min() > 20  # exp(-d), d up to ~3.6
    elif weights == "uniform":
        assert np.allclose(seen[-1][1], seen[-1][1][0])


def test_update_rules_differ_between_mil_and_the_gaussian_family() -> None:
    t_mil, _ = bank("mil")
    t_ct, _ = bank("ct")
    assert t_mil.params.classifier == "mil" and t_mil.params.guard == 1e-5
    assert t_ct.params.classifier == "gaussian" and t_ct.params.guard == 1e-30
    assert t_ct.params.learning_rate == 0.85 and wmiltrack.Tracker().params.learning_rate == 0.9


def test_reference_compat_flags() -> None:
    p = Params.for_variant("wmil", instance_weights="exp_sq", gradient="code", first_update="blend")
    t = wmiltrack.Tracker(params=p)
    t.init(FRAME, BOX)
    r = t.update(FRAME)
    assert all(math.isfinite(v) for v in r.box)


@pytest.mark.parametrize("variant", list(SEARCH))
def test_every_variant_tracks_generated_sequences(variant: str) -> None:
    aucs = []
    for preset in ("occlusion", "clutter"):
        seq = synthetic.make_preset(preset, seed=0, n_frames=150)
        frames, gt = seq.load(), seq.groundtruth
        aucs.append(ope_metrics(wmiltrack.Tracker(variant, seed=0).track(frames, gt[0]), gt).auc)
    # measured: 0.73 to 0.87 for every variant on these two
    assert np.mean(aucs) >= 0.6, aucs
