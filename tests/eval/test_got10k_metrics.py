"""GOT-10k figures (wmiltrack.eval.got10k_metrics) against hand-computed values and the toolkit."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from wmiltrack.data.layouts import load_layout
from wmiltrack.eval.got10k_metrics import (
    GOT10K_THRESHOLDS,
    clip_to_bound,
    got10k_aggregate,
    got10k_ious,
    got10k_metrics,
)

NAN4 = [np.nan] * 4
SQ = [0.0, 0.0, 10.0, 10.0]

# frame: ground truth, prediction, overlap by hand
GT = np.array([SQ, SQ, SQ, NAN4, SQ, SQ, SQ, SQ])
PRED = np.array(
    [
        [100.0, 100.0, 1.0, 1.0],  # frame 0: initialisation frame, never scored
        SQ,  # 1.0
        [5.0, 0.0, 10.0, 10.0],  # 50 / 150 = 1/3
        SQ,  # ground truth absent: not scored
        NAN4,  # no box: 0
        [0.0, 0.0, 10.0, 5.0],  # 50 / 100 = 0.5 exactly: not a success at 0.5
        [0.0, 0.0, 10.0, 8.0],  # 80 / 100 = 0.8
        [0.0, 0.0, 10.0, 7.5],  # 75 / 100 = 0.75 exactly: not a success at 0.75
    ]
)
HAND = [1.0, 1 / 3, 0.0, 0.5, 0.8, 0.75]


def test_hand_computed_ao_sr_and_curve() -> None:
    r = got10k_metrics(PRED, GT)
    assert r.n_frames == 8 and r.n_scored == 6
    np.testing.assert_allclose(r.ious[[1, 2, 4, 5, 6, 7]], HAND, atol=1e-12)
    assert np.isnan(r.ious[[0, 3]]).all()
    assert r.ao == pytest.approx(sum(HAND) / 6)  # 0.56389
    assert r.sr50 == pytest.approx(3 / 6)  # 1.0, 0.8 and 0.75; 0.5 is not > 0.5
    assert r.sr75 == pytest.approx(2 / 6)  # 1.0 and 0.8; 0.75 is not > 0.75
    curve = dict(zip(np.round(GOT10K_THRESHOLDS, 2), r.success_curve))
    assert len(r.success_curve) == 101
    assert curve[0.0] == pytest.approx(5 / 6)  # the 0-overlap frame fails even at 0
    assert curve[0.33] == pytest.approx(5 / 6)
    assert curve[0.34] == pytest.approx(4 / 6)
    assert curve[0.5] == pytest.approx(3 / 6)
    assert curve[0.74] == pytest.approx(3 / 6)
    assert curve[0.79] == pytest.approx(2 / 6)
    assert curve[0.81] == pytest.approx(1 / 6)
    assert curve[1.0] == 0.0
    d = r.to_dict(per_frame=True)
    assert d["ao"] == pytest.approx(r.ao) and d["ious"][0] is None and len(d["success_curve"]) == 101


def test_visible_mask_like_cover_label() -> None:
    cover = [8, 8, 8, 8, 8, 0, 8, 8]  # frame 5 fully covered: left out
    r = got10k_metrics(PRED, GT, visible=cover)
    assert r.n_scored == 5
    assert r.ao == pytest.approx((1 + 1 / 3 + 0 + 0.8 + 0.75) / 5)
    with pytest.raises(ValueError, match=r"visible must have shape \(8,\)"):
        got10k_metrics(PRED, GT, visible=[1, 1])


def test_bound_clips_like_the_toolkit() -> None:
    gt = np.array([SQ, [90.0, 0.0, 20.0, 10.0], [0.0, 0.0, 20.0, 10.0]])
    pred = np.array([SQ, [90.0, 0.0, 10.0, 10.0], [-10.0, 0.0, 20.0, 10.0]])
    # unclipped: 100 / 200 and 100 / 300
    np.testing.assert_allclose(got10k_ious(pred, gt)[1:], [0.5, 1 / 3])
    # in a 100 x 50 image the toolkit moves x to 0 and then caps w at W - x (it does not crop):
    # gt 1 -> (90, 0, 10, 10) = pred 1; pred 2 -> (0, 0, 20, 10) = gt 2
    np.testing.assert_allclose(got10k_ious(pred, gt, bound=(100, 50))[1:], [1.0, 1.0])
    np.testing.assert_array_equal(
        clip_to_bound([[-10.0, 45.0, 20.0, 10.0]], (100, 50)), [[0.0, 45.0, 20.0, 5.0]]
    )


def test_no_scored_frame_gives_nan_and_errors() -> None:
    r = got10k_metrics([SQ, SQ], [SQ, NAN4])
    assert r.n_scored == 0 and np.isnan(r.ao) and r.to_dict()["ao"] is None
    with pytest.raises(ValueError, match="prediction has 2 boxes but the ground truth has 3"):
        got10k_metrics([SQ, SQ], [SQ, SQ, SQ])
    with pytest.raises(ValueError, match="at least one result"):
        got10k_aggregate([])


def test_aggregate_pools_frames_like_the_toolkit() -> None:
    a = got10k_metrics([SQ, SQ], [SQ, SQ])  # one scored frame, overlap 1
    far = [50.0, 50.0, 10.0, 10.0]
    b = got10k_metrics([SQ, far, far, far], [SQ, SQ, SQ, SQ])  # three scored frames, overlap 0
    agg = got10k_aggregate([a, b])
    assert agg.pooled.ao == pytest.approx(1 / 4)  # frames pooled: 1 of 4
    assert agg.pooled.sr50 == pytest.approx(1 / 4)
    assert agg.per_sequence["ao"] == pytest.approx(1 / 2)  # mean of 1.0 and 0.0
    assert agg.n_sequences == 2 and agg.to_dict()["pooled"]["n_scored"] == 4


@pytest.mark.extras("got10k", "six")
def test_matches_got10k_toolkit_on_random_boxes() -> None:
    import got10k.experiments.got10k as exp_mod
    import got10k.utils.metrics as metrics_mod

    rng = np.random.default_rng(7)
    n = 300
    gt = np.column_stack([rng.uniform(-20, 300, n), rng.uniform(-20, 200, n), rng.uniform(1, 80, n), rng.uniform(1, 80, n)])
    pred = gt + rng.normal(0, 12, (n, 4))
    pred[:, 2:] = np.abs(pred[:, 2:]) + 0.5
    bound = (320, 240)
    ours = got10k_ious(pred, gt, bound=bound)[1:]
    theirs = metrics_mod.rect_iou(pred[1:].copy(), gt[1:].copy(), bound=bound)
    np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-12)
    ao, sr, _, curve = exp_mod.ExperimentGOT10k._evaluate(None, theirs, [])
    r = got10k_metrics(pred, gt, bound=bound)
    assert r.ao == pytest.approx(ao, abs=1e-12)
    assert r.sr50 == pytest.approx(sr, abs=1e-12)
    np.testing.assert_allclose(r.success_curve, curve, rtol=0, atol=1e-12)


def test_tracker_on_a_generated_got10k_val_split(tmp_path: Path) -> None:
    """The loader's sequences plug into a tracker and the GOT-10k scoring end to end."""
    from wmiltrack.data.synthetic import make_sequence
    from wmiltrack.engine.tracker import Tracker

    syn = make_sequence(12, size=(96, 128), target_size=(24, 20), seed=2, occlusion=False, clutter=False)
    seq_dir = tmp_path / "val" / "GOT-10k_Val_000001"
    seq_dir.mkdir(parents=True)
    for k, frame in enumerate(syn):
        assert cv2.imwrite(str(seq_dir / f"{k + 1:08d}.jpg"), frame)
    assert syn.groundtruth is not None
    np.savetxt(seq_dir / "groundtruth.txt", syn.groundtruth, fmt="%.4f", delimiter=",")
    absence = [0] * 12
    absence[7] = 1
    (seq_dir / "absence.label").write_text("\n".join(map(str, absence)) + "\n")
    (seq_dir / "cover.label").write_text("\n".join("0" if a else "8" for a in absence) + "\n")
    (seq_dir / "meta_info.ini").write_text("[METAINFO]\nresolution: (128, 96)\n")
    (tmp_path / "val" / "list.txt").write_text("GOT-10k_Val_000001\n")

    (seq,) = load_layout(tmp_path)
    assert seq.groundtruth is not None
    np.testing.assert_allclose(np.delete(seq.groundtruth, 7, axis=0), np.delete(syn.groundtruth, 7, axis=0), atol=1e-4)
    pred = Tracker("rcwmil", seed=0).track(seq, seq.init_box)
    assert pred.shape == (12, 4)
    r = got10k_metrics(pred, seq.groundtruth, bound=seq.meta["resolution"])
    assert r.n_scored == 10  # 12 frames - the first - the absent one
    assert r.ao > 0.5, r.to_dict()
    # a tracker that stays in place does worse than ours on a moving target
    still = got10k_metrics(np.tile(seq.init_box, (12, 1)), seq.groundtruth)
    assert still.ao < r.ao
