"""The Tracker API, determinism and tracking accuracy on generated sequences."""

from __future__ import annotations

import numpy as np
import pytest

import wmiltrack
from wmiltrack.data import synthetic
from wmiltrack.engine.tracker import NotInitializedError
from wmiltrack.eval.metrics import ope_metrics


@pytest.fixture(scope="module")
def demo_sequence():
    seq = synthetic.make_preset("all", seed=0, n_frames=150)
    return seq.load(), seq.groundtruth


def test_api_shape(demo_sequence) -> None:
    frames, gt = demo_sequence
    t = wmiltrack.Tracker("rcwmil", seed=0)
    assert not t.initialized
    t.init(frames[0], tuple(gt[0]))
    r = t.update(frames[1])
    assert isinstance(r, wmiltrack.TrackResult)
    assert len(r.box) == 4 and all(isinstance(v, float) for v in r.box)
    assert 0.0 <= r.score <= 1.0 and isinstance(r.ok, bool)
    ok, box = r  # OpenCV's unpacking
    assert box == r.box and ok == r.ok
    assert t.box == r.box


def test_boxes_may_be_any_real_numbers(demo_sequence) -> None:
    frames, gt = demo_sequence
    x, y, w, h = gt[0]
    a = wmiltrack.Tracker(seed=0)
    a.init(frames[0], (np.float32(x), int(y), float(w), np.int64(round(h))))
    b = wmiltrack.Tracker(seed=0)
    b.init(frames[0], [round(x), round(y), round(w), round(h)])
    assert a.box == b.box


def test_same_seed_same_boxes_different_seed_different_features(demo_sequence) -> None:
    frames, gt = demo_sequence
    runs = [wmiltrack.Tracker("rcwmil", seed=s).track(frames[:60], gt[0]) for s in (3, 3, 4)]
    np.testing.assert_array_equal(runs[0], runs[1])
    a, c = wmiltrack.Tracker(seed=3), wmiltrack.Tracker(seed=4)
    a.init(frames[0], gt[0])
    c.init(frames[0], gt[0])
    assert not np.array_equal(a.parts.appearance.bank_arrays.rects, c.parts.appearance.bank_arrays.rects)


def test_reinit_restarts_identically(demo_sequence) -> None:
    frames, gt = demo_sequence
    t = wmiltrack.Tracker(seed=1)
    first = t.track(frames[:30], gt[0])
    second = t.track(frames[:30], gt[0])  # track() calls init again on the same object
    np.testing.assert_array_equal(first, second)
    t.reinit(frames[40], gt[40])
    assert t.box == tuple(float(round(v)) for v in gt[40])


def test_clear_errors(demo_sequence) -> None:
    frames, gt = demo_sequence
    t = wmiltrack.Tracker()
    with pytest.raises(NotInitializedError, match="init"):
        t.update(frames[0])
    assert issubclass(NotInitializedError, ValueError)
    with pytest.raises(ValueError, match="outside"):
        t.init(frames[0], (1000, 1000, 20, 20))
    with pytest.raises(ValueError, match="positive"):
        t.init(frames[0], (10, 10, 0, 20))
    with pytest.raises(ValueError, match="NaN|infinite"):
        t.init(frames[0], (10, 10, float("nan"), 20))
    with pytest.raises(TypeError):
        t.init(frames[0], (10, 10, 20))
    with pytest.raises(TypeError):
        t.init(frames[0].tolist(), gt[0])
    with pytest.raises(TypeError):
        t.init(frames[0].astype(bool), gt[0])
    with pytest.raises(ValueError, match="channels"):
        t.init(frames[0][:, :, :2], gt[0])
    with pytest.raises(ValueError, match="at least"):
        t.init(frames[0], (10, 10, 3, 3))
    with pytest.raises(ValueError, match="unknown variant"):
        wmiltrack.Tracker("nope")
    with pytest.raises(TypeError, match="unknown parameter"):
        wmiltrack.Tracker(num_selectd=3)
    with pytest.raises(ValueError, match="num_selected"):
        wmiltrack.Tracker(num_selected=200)
    with pytest.raises(ValueError, match="learning_rate"):
        wmiltrack.Tracker(learning_rate=1.0)
    t.init(frames[0], gt[0])
    with pytest.raises(ValueError, match="size changed"):
        t.update(frames[1][:100])


def test_partly_outside_box_is_clipped(demo_sequence) -> None:
    frames, _ = demo_sequence
    t = wmiltrack.Tracker()
    t.init(frames[0], (-10.4, -5, 50, 40))
    assert t.box == (0.0, 0.0, 40.0, 35.0)
    r = t.update(frames[1])
    x, y, w, h = r.box
    assert x >= 0 and y >= 0 and x + w <= frames[0].shape[1] and y + h <= frames[0].shape[0]


def test_variants_lists_the_six_family_members() -> None:
    v = wmiltrack.variants()
    assert list(v) == ["rcwmil", "ct", "fct", "mil", "wmil", "osil", "rcwmil-plus", "rcwmil-cf",
                       "rcwmil-nano"]
    nano, cf = v["rcwmil-nano"].as_dict(), v["rcwmil-cf"].as_dict()
    assert {k for k in nano if nano[k] != cf[k]} == {"variant", "description", "network",
                                                     "likeness_every", "tracker_every"}
    assert all(isinstance(p, wmiltrack.Params) for p in v.values())
    assert wmiltrack.Tracker().params == v["rcwmil"]


def static_auc(gt: np.ndarray) -> float:
    """What a tracker that never moves would score."""
    return ope_metrics(np.repeat(gt[:1], len(gt), axis=0), gt).auc


@pytest.mark.parametrize("preset", ["all", "occlusion", "illumination", "clutter"])
def test_rcwmil_tracks_generated_sequences(preset: str) -> None:
    aucs, statics = [], []
    for seed in (0, 1):
        seq = synthetic.make_preset(preset, seed=seed, n_frames=150)
        frames, gt = seq.load(), seq.groundtruth
        boxes = wmiltrack.Tracker("rcwmil", seed=0).track(frames, gt[0])
        aucs.append(ope_metrics(boxes, gt).auc)
        statics.append(static_auc(gt))
    # measured (seeds 0, 1): all 0.66/0.56, occlusion 0.74/0.79, illumination 0.75/0.63,
    # clutter 0.80/0.84; a box that never moves scores well under 0.3
    assert min(aucs) >= 0.5, aucs
    assert np.mean(aucs) >= np.mean(statics) + 0.3, (aucs, statics)
