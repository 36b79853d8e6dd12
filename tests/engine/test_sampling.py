"""Bag sampling: counts and geometry (spec sections 0 and 7)."""

from __future__ import annotations

import numpy as np

from wmiltrack.engine.params import Params
from wmiltrack.engine.sampling import BagSampler, annulus_offsets, disc_offsets, instance_weights


def test_disc_and_annulus_sizes_follow_the_spec() -> None:
    assert len(disc_offsets(4)) == 45
    assert len(disc_offsets(3)) == 25
    assert len(disc_offsets(25)) == 1941
    assert len(disc_offsets(20)) == 1245
    assert len(disc_offsets(10)) == 305
    assert len(annulus_offsets(8, 22)) == 1320
    # inner bound inclusive, outer exclusive
    d2 = (annulus_offsets(8, 22) ** 2).sum(axis=1)
    assert d2.min() == 64 and d2.max() < 22 * 22
    assert (8, 0) in {tuple(o) for o in annulus_offsets(8, 22)}
    assert (4, 0) not in {tuple(o) for o in disc_offsets(4)}


def test_offsets_are_row_major() -> None:
    off = disc_offsets(4)
    keys = off[:, 1] * 100 + off[:, 0]
    assert np.all(np.diff(keys) > 0)


def test_positives_are_all_45_and_negatives_exactly_50_distinct_in_the_annulus() -> None:
    s = BagSampler(Params())
    rng = np.random.default_rng(0)
    box = (100, 80, 30, 40)
    pos, dist = s.positives(box, 320, 240)
    assert pos.shape == (45, 2)
    assert dist.min() == 0 and dist.max() < 4
    neg = s.negatives(box, 320, 240, rng)
    assert neg.shape == (50, 2)
    assert len({tuple(n) for n in neg}) == 50
    d = np.hypot(neg[:, 0] - box[0], neg[:, 1] - box[1])
    assert d.min() >= 8 and d.max() < 22


def test_samples_are_clipped_to_the_image() -> None:
    s = BagSampler(Params())
    rng = np.random.default_rng(1)
    box = (0, 0, 30, 40)  # in the top-left corner: only offsets >= 0 fit
    pos, _ = s.positives(box, 100, 100)
    neg = s.negatives(box, 100, 100, rng)
    for pts in (pos, neg):
        assert np.all(pts >= 0)
        assert np.all(pts[:, 0] + 30 <= 100) and np.all(pts[:, 1] + 40 <= 100)
    assert len(pos) == 15  # the quarter disc dx, dy >= 0, d < 4: rows of 4, 4, 4, 3
    # a frame hardly larger than the box: fewer than 50 negatives fit, all are taken
    tight = s.negatives((2, 2, 30, 40), 40, 50, rng)
    expected = {(dx, dy) for dx in range(-2, 9) for dy in range(-2, 9) if 64 <= dx * dx + dy * dy < 484}
    assert len(expected) == 29
    assert {(int(x) - 2, int(y) - 2) for x, y in tight} == expected


def test_bernoulli_thinning_keeps_a_random_count_below_the_maximum() -> None:
    p = Params.for_variant("ct")
    s = BagSampler(p)
    rng = np.random.default_rng(2)
    counts = [len(s.negatives((200, 200, 30, 30), 600, 600, rng)) for _ in range(200)]
    # annulus 8..30 has 2625 points; keep probability 50 / 61^2 -> about 35 on average
    assert 30 < np.mean(counts) < 40
    assert max(counts) <= 50 and len(set(counts)) > 3


def test_first_frame_bags_can_differ() -> None:
    p = Params.for_variant("mil")
    first, track = BagSampler(p, first_frame=True), BagSampler(p)
    assert len(first.pos_offsets) == 25 and len(track.pos_offsets) == 45
    assert first.neg_count == 65 and first.reach == 50


def test_instance_weights() -> None:
    d = disc_offsets(4)
    dist = np.hypot(d[:, 0], d[:, 1])
    w = instance_weights(dist, "exp")
    assert np.isclose(w.sum(), 1.0)
    assert np.allclose(w, np.exp(-dist) / np.exp(-dist).sum())
    assert w.argmax() == np.argmin(dist)
    sq = instance_weights(dist, "exp_sq")
    assert sq.max() == 1.0 and np.isclose(sq[dist == 1][0], np.exp(-1))
    u = instance_weights(dist, "uniform")
    assert np.allclose(u, 1 / 45)
