"""The C++ kernels against plain numpy references on random data."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from wmiltrack import _core


def gray_of(frame: np.ndarray) -> np.ndarray:
    if frame.ndim == 2:
        return frame.astype(np.int64)
    if frame.shape[2] == 1:
        return frame[:, :, 0].astype(np.int64)
    return cv2.cvtColor(np.ascontiguousarray(frame[:, :, :3]), cv2.COLOR_BGR2GRAY).astype(np.int64)


def integral_ref(gray: np.ndarray) -> np.ndarray:
    out = np.zeros((gray.shape[0] + 1, gray.shape[1] + 1), dtype=np.int64)
    out[1:, 1:] = gray.cumsum(0).cumsum(1)
    return out


@pytest.mark.parametrize("channels", [None, 1, 3, 4])
def test_integral_image_matches_numpy_and_opencv_luma(channels: int | None) -> None:
    rng = np.random.default_rng(channels or 0)
    shape = (47, 61) if channels is None else (47, 61, channels)
    frame = rng.integers(0, 256, size=shape, dtype=np.uint8)
    ii = _core.IntegralImage()
    ii.compute(frame, (0, 0, 61, 47))
    np.testing.assert_array_equal(ii.table(), integral_ref(gray_of(frame)))


def test_luma_of_every_row_width_and_offset_matches_opencv() -> None:
    """The BGR luma runs 16 pixels at a time (SSSE3, when the CPU has it) and finishes each
    row one pixel at a time: every width and start column must give cv2's bytes, including
    saturated colours (the extreme weighted sums)."""
    rng = np.random.default_rng(7)
    frame = rng.integers(0, 256, size=(6, 131, 3), dtype=np.uint8)
    frame[0] = 255
    frame[1, ::2] = (255, 255, 0)
    frame[2, 1::3] = (0, 0, 255)
    gray = gray_of(frame)
    ii = _core.IntegralImage()
    for x in range(0, 20):
        for w in range(1, 131 - x, 7):
            ii.compute(frame, (x, 0, w, 6))
            np.testing.assert_array_equal(ii.table(), integral_ref(gray[:, x:x + w]), err_msg=f"x={x} w={w}")


def test_integral_image_over_a_region_is_clipped_and_exact() -> None:
    rng = np.random.default_rng(1)
    frame = rng.integers(0, 256, size=(80, 90, 3), dtype=np.uint8)
    ii = _core.IntegralImage()
    ii.compute(frame, (-5, 10, 40, 200))  # hangs off the left and bottom edges
    assert (ii.x0, ii.y0, ii.width, ii.height) == (0, 10, 35, 70)
    gray = gray_of(frame)
    np.testing.assert_array_equal(ii.table(), integral_ref(gray[10:80, 0:35]))
    for _ in range(50):
        x, y = int(rng.integers(0, 30)), int(rng.integers(10, 75))
        w, h = int(rng.integers(0, 35 - x + 1)), int(rng.integers(0, 80 - y + 1))
        assert ii.rect_sum(x, y, w, h) == gray[y:y + h, x:x + w].sum()
    with pytest.raises(IndexError):
        ii.rect_sum(30, 10, 10, 5)  # past the region's right edge


def test_integral_image_reads_strided_views_without_copying() -> None:
    rng = np.random.default_rng(2)
    big = rng.integers(0, 256, size=(60, 80, 3), dtype=np.uint8)
    view = big[::2, 1::3, :]  # non-contiguous
    ii = _core.IntegralImage()
    ii.compute(view, (0, 0, view.shape[1], view.shape[0]))
    np.testing.assert_array_equal(ii.table(), integral_ref(gray_of(np.ascontiguousarray(view))))


def random_bank(rng: np.random.Generator, m: int, box: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    counts = rng.integers(1, 5, size=m)
    starts = np.concatenate([[0], np.cumsum(counts)]).astype(np.int32)
    rects = []
    for _ in range(int(starts[-1])):
        w, h = rng.integers(1, box // 2 + 1, size=2)
        x, y = rng.integers(0, box - w + 1), rng.integers(0, box - h + 1)
        rects.append((x, y, w, h))
    weights = rng.normal(size=len(rects))
    return starts, np.array(rects, dtype=np.int32), weights


def project_ref(gray: np.ndarray, starts: np.ndarray, rects: np.ndarray, weights: np.ndarray,
                xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
    out = np.zeros((starts.size - 1, xs.size))
    for f in range(starts.size - 1):
        for r in range(starts[f], starts[f + 1]):
            x, y, w, h = rects[r]
            for n in range(xs.size):
                out[f, n] += weights[r] * gray[ys[n] + y:ys[n] + y + h, xs[n] + x:xs[n] + x + w].sum()
    return out


def test_projection_matches_numpy() -> None:
    rng = np.random.default_rng(3)
    frame = rng.integers(0, 256, size=(70, 90, 3), dtype=np.uint8)
    starts, rects, weights = random_bank(rng, 12, 16)
    bank = _core.FeatureBank(starts, rects, weights)
    ii = _core.IntegralImage()
    ii.compute(frame, (0, 0, 90, 70))
    xs = rng.integers(0, 90 - 16, size=25).astype(np.int32)
    ys = rng.integers(0, 70 - 16, size=25).astype(np.int32)
    ref = project_ref(gray_of(frame), starts, rects, weights, xs, ys)
    np.testing.assert_allclose(_core.project(ii, bank, xs, ys), ref, rtol=1e-12, atol=1e-9)
    sub = np.array([7, 0, 7], dtype=np.int32)
    np.testing.assert_allclose(_core.project(ii, bank, xs, ys, sub), ref[sub], rtol=1e-12, atol=1e-9)


def test_projection_refuses_boxes_outside_the_integral_image() -> None:
    frame = np.zeros((40, 40), dtype=np.uint8)
    bank = _core.FeatureBank(np.array([0, 1], np.int32), np.array([[0, 0, 10, 10]], np.int32), np.ones(1))
    ii = _core.IntegralImage()
    ii.compute(frame, (0, 0, 20, 20))
    with pytest.raises(IndexError):
        _core.project(ii, bank, np.array([15], np.int32), np.array([0], np.int32))
    with pytest.raises(IndexError):
        _core.project(ii, bank, np.array([0], np.int32), np.array([0], np.int32), np.array([3], np.int32))


def log_ratio_ref(v: np.ndarray, mu1: np.ndarray, s1: np.ndarray, mu0: np.ndarray, s0: np.ndarray,
                  guard: float) -> np.ndarray:
    eps = 1e-30
    p1 = np.exp(-((v - mu1[:, None]) ** 2) / (2 * s1[:, None] ** 2 + eps)) / (s1[:, None] + eps)
    p0 = np.exp(-((v - mu0[:, None]) ** 2) / (2 * s0[:, None] ** 2 + eps)) / (s0[:, None] + eps)
    return np.log(p1 + guard) - np.log(p0 + guard)


@pytest.mark.parametrize("guard", [1e-30, 1e-5])
def test_log_ratio_matches_the_guarded_reference_formula(guard: float) -> None:
    rng = np.random.default_rng(4)
    k, n = 9, 200
    mu1, mu0 = rng.normal(0, 50, k), rng.normal(0, 50, k)
    s1, s0 = rng.uniform(0.5, 40, k), rng.uniform(0.5, 40, k)
    v = rng.normal(0, 120, (k, n))  # includes values far in the tails, where the guard saturates
    ref = log_ratio_ref(v, mu1, s1, mu0, s0, guard)
    got = _core.log_ratio(v, mu1, s1, mu0, s0, guard)
    if guard >= 1e-15:
        # MILTrack's guard: the guarded ratio's exp and log run in float (issue 28), |h| <= ~12
        # here, so within a few float ulps of 12 (and the worst case is measured, not assumed).
        np.testing.assert_allclose(got, ref, rtol=0, atol=4e-6)
        assert np.abs(got - ref).max() > 1e-9, "the float path was expected here"
    else:
        np.testing.assert_allclose(got, ref, rtol=1e-9, atol=1e-9)


def grid_scene(seed: int) -> tuple[np.random.Generator, np.ndarray, tuple[np.ndarray, ...],
                                   _core.FeatureBank, _core.IntegralImage]:
    """A random 150x120 gray frame, a random bank of 6 features for a 20-px box, and the
    frame's integral image (with the generator, to draw the rest from)."""
    rng = np.random.default_rng(seed)
    frame = rng.integers(0, 256, size=(120, 150), dtype=np.uint8)
    arrays = random_bank(rng, 6, 20)
    bank = _core.FeatureBank(*arrays)
    ii = _core.IntegralImage()
    ii.compute(frame, (0, 0, 150, 120))
    return rng, frame, arrays, bank, ii


def test_score_grid_matches_brute_force_first_maximum_in_row_major_order() -> None:
    rng, frame, (starts, rects, weights), bank, ii = grid_scene(5)
    sel = np.array([4, 1, 2], dtype=np.int32)
    mu1, mu0 = rng.normal(0, 300, 3), rng.normal(0, 300, 3)
    s1, s0 = rng.uniform(100, 400, 3), rng.uniform(100, 400, 3)
    gray = gray_of(frame)
    for box, radius, step in [((60, 50, 20, 20), 25, 4), ((60, 50, 20, 20), 10, 1), ((2, 95, 20, 20), 10, 1)]:
        dx, dy, best, n, scores = _core.score_grid(ii, bank, sel, mu1, s1, mu0, s0, 1e-30, box, radius,
                                                   step, (150, 120), True)
        half = -(-radius // step) - 1
        ref = np.full((2 * half + 1, 2 * half + 1), -np.inf)
        for j in range(-half, half + 1):
            for i in range(-half, half + 1):
                ox, oy = i * step, j * step
                x, y = box[0] + ox, box[1] + oy
                if ox * ox + oy * oy >= radius * radius or x < 0 or y < 0 or x + 20 > 150 or y + 20 > 120:
                    continue
                v = project_ref(gray, starts, rects, weights, np.array([x]), np.array([y]))[sel]
                ref[j + half, i + half] = log_ratio_ref(v, mu1, s1, mu0, s0, 1e-30).sum()
        # The search sums each feature's exact-path log ratio in float (issue 28): a few float
        # ulps of each of the 3 terms.
        np.testing.assert_allclose(scores, ref, rtol=1e-5, atol=1e-5)
        assert n == np.isfinite(ref).sum()
        flat = int(np.argmax(scores))  # numpy's argmax keeps the first maximum, row-major
        assert (dy, dx) == ((flat // ref.shape[1] - half) * step, (flat % ref.shape[1] - half) * step)
        assert ref.flat[flat] == pytest.approx(ref.max(), abs=1e-5)  # the best, up to float rounding
        assert best == scores.flat[flat]


def test_score_grid_candidate_counts_follow_the_spec() -> None:
    frame = np.full((400, 400), 100, dtype=np.uint8)
    bank = _core.FeatureBank(np.array([0, 1], np.int32), np.array([[0, 0, 4, 4]], np.int32), np.ones(1))
    ii = _core.IntegralImage()
    ii.compute(frame, (0, 0, 400, 400))
    one = np.ones(1)
    counts = {}
    for radius, step in [(25, 4), (10, 1), (25, 1), (20, 1), (4, 1)]:
        counts[(radius, step)] = _core.score_grid(ii, bank, np.array([0], np.int32), one, one, one, one,
                                                  1e-30, (180, 180, 20, 20), radius, step, (400, 400))[3]
    # spec section 0 and 3: D(25) has 1941 offsets, D(20) 1245, D(10) 305, D(4) 45; the coarse grid 121
    assert counts == {(25, 4): 121, (10, 1): 305, (25, 1): 1941, (20, 1): 1245, (4, 1): 45}


def test_kernels_reject_bad_arguments_with_python_errors() -> None:
    ii = _core.IntegralImage()
    with pytest.raises(TypeError):
        ii.compute(np.zeros((10, 10), dtype=np.float32), (0, 0, 10, 10))
    with pytest.raises(ValueError):
        ii.compute(np.zeros((10, 10, 2), dtype=np.uint8), (0, 0, 10, 10))
    with pytest.raises(ValueError):
        ii.compute(np.zeros((10, 10), dtype=np.uint8), (20, 20, 5, 5))
    with pytest.raises(ValueError):
        _core.FeatureBank(np.array([0, 2], np.int32), np.array([[0, 0, 1, 1]], np.int32), np.ones(1))
    with pytest.raises(ValueError):
        _core.FeatureBank(np.array([0, 1], np.int32), np.array([[0, 0, 0, 1]], np.int32), np.ones(1))
    with pytest.raises(ValueError):
        _core.log_ratio(np.zeros((2, 3)), np.zeros(2), np.zeros(2), np.zeros(2), np.ones(2), 1e-30)


@pytest.mark.parametrize("variant", ["rcwmil", "mil", "ct", "osil"])
def test_one_call_learning_step_equals_the_separate_calls(variant: str) -> None:
    """_core.learn = project, the Gaussian update of each class, log_ratio and (WMIL)
    wmil_select one after the other: the same bits."""
    import wmiltrack
    from wmiltrack import _learn
    from wmiltrack.engine.sampling import instance_weights

    rng = np.random.default_rng(11)
    frame = rng.integers(0, 256, (120, 160, 3), dtype=np.uint8)
    t = wmiltrack.Tracker(variant, seed=1)
    t.init(frame, (60, 40, 32, 28))
    model = t.parts.appearance
    box = tuple(int(v) for v in t.box)
    p, pool, bank, ii = t.params, model.pool, model.bank(box[2], box[3]), model.ii
    pos, dist = model.sampler.positives(box, 160, 120)
    neg = model.sampler.negatives(box, 160, 120, np.random.default_rng(0))
    corners = np.concatenate((pos, neg))
    n = pos.shape[0]
    w = instance_weights(dist, p.instance_weights)
    for select in ("none", "ratios", "wmil"):
        got = _core.learn(_core.LearnRequest(ii, bank, corners[:, 0], corners[:, 1], n, pool.mu1, pool.sigma1,
                          pool.mu0, pool.sigma0, lam=p.learning_rate, first_pos=False,
                          first_neg=False, direct_first=p.first_update == "direct",
                          mil=p.classifier == "mil", sigma_floor=p.sigma_floor, guard=p.guard,
                          select=select, w_pos=w if select == "wmil" else None,
                          k=p.num_selected))
        values = _core.project(ii, bank, corners[:, 0], corners[:, 1])
        args = (p.learning_rate, False, p.first_update == "direct", p.classifier == "mil", p.sigma_floor)
        mu1, s1 = _learn.gaussian_update(values[:, :n], pool.mu1, pool.sigma1, *args)
        mu0, s0 = _learn.gaussian_update(values[:, n:], pool.mu0, pool.sigma0, *args)
        for a, b in zip(got[:4], (mu1, s1, mu0, s0)):
            np.testing.assert_array_equal(a, b)
        h = _core.log_ratio(values, mu1, s1, mu0, s0, p.guard)
        if select == "ratios":
            np.testing.assert_array_equal(got[5], h)
        elif select == "wmil":
            np.testing.assert_array_equal(got[4], _learn.wmil_select(h[:, :n], h[:, n:], w, p.num_selected))
        else:
            assert got[4] is None and got[5] is None
        assert got[6] is None and got[7] is None
    # rcwmil-plus's extras: negatives given as values (appended after the projected ones) and
    # a second target model updated from the positives with its own lambda.
    extra = rng.normal(100, 30, (values.shape[0], 2))
    mu2, s2 = rng.normal(100, 30, values.shape[0]), rng.uniform(5, 20, values.shape[0])
    got = _core.learn(_core.LearnRequest(ii, bank, corners[:, 0], corners[:, 1], n, pool.mu1, pool.sigma1,
                      pool.mu0, pool.sigma0, lam=p.learning_rate, first_pos=False,
                      first_neg=False, direct_first=p.first_update == "direct",
                      mil=p.classifier == "mil", sigma_floor=p.sigma_floor, guard=p.guard,
                      select="wmil", w_pos=w, k=p.num_selected, extra_neg=extra,
                      second=(mu2, s2, 0.975, False)))
    values = np.concatenate((_core.project(ii, bank, corners[:, 0], corners[:, 1]), extra), axis=1)
    mu1, s1 = _learn.gaussian_update(values[:, :n], pool.mu1, pool.sigma1, *args)
    mu0, s0 = _learn.gaussian_update(values[:, n:], pool.mu0, pool.sigma0, *args)
    want_mu2, want_s2 = _learn.gaussian_update(values[:, :n], mu2, s2, 0.975, *args[1:])
    h = _core.log_ratio(values, mu1, s1, mu0, s0, p.guard)
    for a, b in zip(got, (mu1, s1, mu0, s0, _learn.wmil_select(h[:, :n], h[:, n:], w, p.num_selected),
                          None, want_mu2, want_s2)):
        np.testing.assert_array_equal(a, b)
    with pytest.raises(ValueError, match="extra_neg"):
        _core.learn(_core.LearnRequest(ii, bank, corners[:, 0], corners[:, 1], n, pool.mu1, pool.sigma1, pool.mu0,
                    pool.sigma0, lam=0.85, first_pos=False, first_neg=False, direct_first=True,
                    mil=False, sigma_floor=1e-6, guard=1e-30, select="none", extra_neg=extra[1:]))
    with pytest.raises(ValueError, match="select"):
        _core.learn(_core.LearnRequest(ii, bank, corners[:, 0], corners[:, 1], n, pool.mu1, pool.sigma1, pool.mu0,
                    pool.sigma0, lam=0.85, first_pos=False, first_neg=False, direct_first=True,
                    mil=False, sigma_floor=1e-6, guard=1e-30, select="milboost"))


class _Batch:
    """Three rcwmil trackers started on one random frame, and the requests that the tests of
    the batched core calls make for them (searches around each target; learning steps with the
    second target's bank and model, its bag sampler)."""

    def __init__(self) -> None:
        import wmiltrack
        from wmiltrack.engine.sampling import BagSampler

        rng = np.random.default_rng(5)
        self.frame = rng.integers(0, 256, (160, 200, 3), dtype=np.uint8)
        self.trackers = []
        for i, box in enumerate([(30, 30, 30, 26), (120, 90, 28, 32), (80, 50, 24, 24)]):
            t = wmiltrack.Tracker("rcwmil", seed=i)
            t.init(self.frame, box)
            self.trackers.append(t)
        self.t = self.trackers[1]
        self.sampler = BagSampler(self.t.params)
        self.empty = np.zeros((0, 2), np.int32)

    def job_args(self, t, ii):  # noqa: ANN001, ANN201
        p, model = t.params, t.parts.appearance
        pool = model.pool
        roi = (t.box[0] - 40, t.box[1] - 40, t.box[2] + 80, t.box[3] + 80)
        return (ii, model.bank(int(t.box[2]), int(t.box[3])), model.selected, pool.mu1, pool.sigma1,
                pool.mu0, pool.sigma0, p.guard, tuple(int(v) for v in t.box), [(25, 4), (10, 1)],
                (200, 160), self.frame, tuple(int(v) for v in roi), None)

    def job(self, t, ii):  # noqa: ANN001, ANN201
        return _core.SearchRequest(*self.job_args(t, ii))

    def learn(self, ii, corners, n_pos, w):  # noqa: ANN001, ANN201
        t, pool = self.t, self.t.parts.appearance.pool
        return _core.LearnRequest(ii, t.parts.appearance.bank(int(t.box[2]), int(t.box[3])),
                                  corners[:, 0], corners[:, 1], n_pos, pool.mu1, pool.sigma1,
                                  pool.mu0, pool.sigma0, lam=0.85, first_pos=False,
                                  first_neg=False, direct_first=True, mil=False, sigma_floor=1e-3,
                                  guard=1e-30, select="wmil", w_pos=w, k=20)


def test_batched_searches_equal_single_calls_and_refuse_a_shared_target_table() -> None:
    """search_many / learn_many: the results of search / learn called one by one, whatever
    the threads; two jobs may not compute into one IntegralImage; threads >= 1."""
    setup = _Batch()
    trackers, job = setup.trackers, setup.job
    single = [_core.search(job(t, _core.IntegralImage())) for t in trackers]
    for threads in (1, 2, 3):
        many = _core.search_many([job(t, _core.IntegralImage()) for t in trackers], threads)
        assert list(many) == single
    shared = _core.IntegralImage()
    with pytest.raises(ValueError, match="also uses"):
        _core.search_many([job(trackers[0], shared), job(trackers[1], shared)], 2)
    with pytest.raises(ValueError, match="threads"):
        _core.search_many([job(trackers[0], _core.IntegralImage())], 0)
    assert _core.search_many([], 2) == []
    assert _core.learn_many([], 2) == []


def test_frame_step_and_learn_at_equal_their_separate_calls() -> None:
    """frame_step: search, bags sampled where it landed (numpy's draws), learning on them, as
    the separate calls give them; learn_at: the same at a box the caller gives; misuse refused."""
    setup = _Batch()
    t, sampler, empty, job, job_args, learn = (setup.t, setup.sampler, setup.empty, setup.job,
                                               setup.job_args, setup.learn)
    single_1 = _core.search(job(t, _core.IntegralImage()))
    ii, rng = _core.IntegralImage(), np.random.default_rng(3)
    found, learnt, (xs, ys, n_pos) = _core.frame_step(job(t, ii), learn(ii, empty, 0, None),
                                                      _core.BagRequest(rng, *sampler.core_spec("exp")))
    assert found == single_1
    landed = tuple(int(v) for v in t.box)
    landed = (landed[0] + sum(r[0] for r in found), landed[1] + sum(r[1] for r in found), *landed[2:])
    alone, rng_alone = _core.IntegralImage(), np.random.default_rng(3)
    _core.search(job(t, alone))
    pos, dist = sampler.positives(landed, 200, 160)
    neg = sampler.negatives(landed, 200, 160, rng_alone)
    assert n_pos == len(pos) and np.array_equal(np.stack((xs, ys), 1), np.concatenate((pos, neg)))
    assert rng.bit_generator.state == rng_alone.bit_generator.state
    expected = _core.learn(learn(alone, np.concatenate((pos, neg)), len(pos), sampler.weights(dist, "exp")))
    for a, b in zip(learnt, expected):
        assert (a is None and b is None) or np.array_equal(a, b)
    # learn_at: the same bags and learning at a box given by the caller (no search).
    rng_at = np.random.default_rng(3)
    learnt_at, (xs_at, ys_at, n_pos_at) = _core.learn_at(
        learn(alone, empty, 0, None), _core.BagRequest(rng_at, *sampler.core_spec("exp")), landed,
        (200, 160))
    assert n_pos_at == n_pos and np.array_equal(xs_at, xs) and np.array_equal(ys_at, ys)
    for a, b in zip(learnt_at, expected):
        assert (a is None and b is None) or np.array_equal(a, b)
    assert rng_at.bit_generator.state == rng.bit_generator.state
    with pytest.raises(ValueError, match="same generator"):
        same = _core.BagRequest(rng_at, *sampler.core_spec("exp"))
        _core.learn_at_many([(learn(alone, empty, 0, None), same, landed, (200, 160))] * 2, 2)
    with pytest.raises(ValueError, match="positive size"):
        _core.learn_at(learn(alone, empty, 0, None), same, (0, 0, 0, 5), (200, 160))
    bags = _core.BagRequest(rng, *sampler.core_spec("exp"))
    # Without a frame the step reads the integral image as it is (one shared by several
    # targets): computed, it gives the same search; never computed, it is refused.
    no_frame = _core.SearchRequest(*job_args(t, ii)[:11])
    assert _core.frame_step(no_frame, learn(ii, empty, 0, None), bags)[0] == found
    never = _core.IntegralImage()
    with pytest.raises(ValueError, match="not been computed"):
        _core.frame_step(_core.SearchRequest(*job_args(t, never)[:11]), learn(never, empty, 0, None),
                         bags)
    with pytest.raises(ValueError, match="the search's IntegralImage"):
        _core.frame_step(job(t, ii), learn(alone, empty, 0, None), bags)
    with pytest.raises(TypeError, match="BagRequest"):
        _core.frame_step(job(t, ii), learn(ii, empty, 0, None), (rng, *sampler.core_spec("exp")))
    with pytest.raises(TypeError, match="not a SearchRequest"):
        _core.search_many([learn(ii, empty, 0, None)], 1)
    fresh = _core.IntegralImage()  # never computed before: the search computes it first
    assert _core.frame_step(job(t, fresh), learn(fresh, empty, 0, None), bags)[0] == found



def test_frame_step_many_equals_frame_step_alone_whatever_the_threads() -> None:
    """frame_step_many: each job as frame_step alone gives it, its generator left in the same
    state, whatever the number of threads; shared generators or tables and a failing job."""
    setup = _Batch()
    trackers, sampler, empty, job, job_args, learn = (setup.trackers, setup.sampler, setup.empty,
                                                      setup.job, setup.job_args, setup.learn)
    # frame_step_many: each job as frame_step alone gives it, its generator left in the same
    # state, whatever the number of threads.
    tables: list[_core.IntegralImage] = []

    def steps(seed: int) -> tuple[list[tuple[object, ...]], list[np.random.Generator]]:
        rngs = [np.random.default_rng(seed + i) for i in range(len(trackers))]
        jobs = []
        tables.clear()
        for tr, r in zip(trackers, rngs):
            own = _core.IntegralImage()
            tables.append(own)
            jobs.append((job(tr, own), learn(own, empty, 0, None),
                         _core.BagRequest(r, *sampler.core_spec("exp"))))
        return jobs, rngs

    alone_jobs, alone_rngs = steps(10)
    single_steps = [_core.frame_step(*j) for j in alone_jobs]
    for threads in (1, 2, 3):
        jobs, rngs = steps(10)
        many_steps = _core.frame_step_many(jobs, threads)
        assert len(many_steps) == len(single_steps)
        for got, want in zip(many_steps, single_steps):
            assert got[0] == want[0]
            assert all((a is None and b is None) or np.array_equal(a, b) for a, b in zip(got[1], want[1]))
            assert all(np.array_equal(a, b) for a, b in zip(got[2], want[2]))
        assert [r.bit_generator.state for r in rngs] == [r.bit_generator.state for r in alone_rngs]
    jobs, rngs_20 = steps(20)  # (job 1's generator below)
    one_rng = (jobs[0][0], jobs[0][1], _core.BagRequest(rngs_20[1], *sampler.core_spec("exp")))
    with pytest.raises(ValueError, match="same generator"):
        _core.frame_step_many([one_rng, jobs[1]], 2)
    both = (job(trackers[1], tables[0]), learn(tables[0], empty, 0, None), jobs[1][2])
    with pytest.raises(ValueError, match="share an IntegralImage"):
        _core.frame_step_many([jobs[0], both], 2)
    with pytest.raises(ValueError, match="threads"):
        _core.frame_step_many(jobs, 0)
    assert _core.frame_step_many([], 2) == []
    # A job that fails inside the parallel part (its region misses the frame) raises after the
    # others ran, and every generator's lock is released.
    jobs, rngs = steps(30)
    far = _core.IntegralImage()
    args = job_args(trackers[1], far)
    jobs[1] = (_core.SearchRequest(*args[:12], (500, 500, 10, 10), None), learn(far, empty, 0, None),
               jobs[1][2])
    with pytest.raises(ValueError, match="does not meet the frame"):
        _core.frame_step_many(jobs, 2)
    for r in rngs:
        assert r.bit_generator.lock.acquire(blocking=False)
        r.bit_generator.lock.release()


@pytest.mark.parametrize("seed", range(40))
def test_the_cores_draws_continue_numpys_stream(seed: int) -> None:
    """numpy_choice_sorted / numpy_bernoulli_first give the numbers numpy's Generator.choice
    (replace=False) and random() < p give, and leave the generator in the same state (also
    with half of a 64-bit draw buffered by an odd number of 32-bit draws before)."""
    for n, k in [(1320, 50), (2616, 50), (51, 50), (50, 50), (4172, 65), (9999, 199), (10, 3), (1, 1)]:
        a, b = np.random.default_rng(seed), np.random.default_rng(seed)
        a.integers(0, 7, size=seed % 3)
        b.integers(0, 7, size=seed % 3)
        assert _core.numpy_choice_sorted(b, n, k) == sorted(a.choice(n, size=k, replace=False).tolist())
        assert a.bit_generator.state == b.bit_generator.state
    for n, p, limit in [(2616, 0.0133, 50), (4172, 0.012, 65), (100, 0.5, 10), (0, 0.5, 3)]:
        a, b = np.random.default_rng(seed), np.random.default_rng(seed)
        assert _core.numpy_bernoulli_first(b, n, p, limit) == np.flatnonzero(a.random(n) < p)[:limit].tolist()
        assert a.bit_generator.state == b.bit_generator.state
    # numpy's PCG64 is stepped in the core, four draws in flight: every count around the
    # groups of four, and another bit generator (drawn through numpy's next_double) alike.
    assert _core.numpy_pcg64_stepped_here(np.random.default_rng(seed))
    assert not _core.numpy_pcg64_stepped_here(np.random.Generator(np.random.PCG64DXSM(seed)))
    for make in (np.random.default_rng, lambda s: np.random.Generator(np.random.PCG64DXSM(s))):
        a, b = make(seed), make(seed)
        for n in (1, 2, 3, 4, 5, 7, 8, 9, 4171):
            assert _core.numpy_bernoulli_first(b, n, 0.3, 4000) == np.flatnonzero(a.random(n) < 0.3).tolist()
            assert a.bit_generator.state == b.bit_generator.state
    with pytest.raises(ValueError):
        _core.numpy_choice_sorted(np.random.default_rng(0), 5, 6)
    with pytest.raises(TypeError, match="Generator"):
        _core.numpy_choice_sorted(np.random.SeedSequence(0), 5, 2)


def _search(ii, bank, sel, mu1, s1, mu0, s0, box, stages, cues=None):  # noqa: ANN001, ANN202
    return _core.search(_core.SearchRequest(ii, bank, sel, mu1, s1, mu0, s0, 1e-30, box, stages,
                                            (150, 120), cues=cues))


def _box_means(table: np.ndarray, xs: np.ndarray, ys: np.ndarray, side: int) -> np.ndarray:
    return (table[ys + side, xs + side] - table[ys, xs + side] - table[ys + side, xs]
            + table[ys, xs]) / float(side * side)


@pytest.mark.parametrize("relative", [False, True])
@pytest.mark.parametrize("n_cues", [1, 2])
def test_search_with_cues_takes_the_merged_first_maximum(relative: bool, n_cues: int) -> None:
    """search(cues=...) picks, stage by stage, the first maximum in row-major order of
    (1 - W) logistic((raw - ref) / K - offset) + sum of w * (box mean of each cue), W the sum
    of the weights and ref = 0 or (relative) the stage's best raw score; it reports that
    candidate's raw score, and refuses a candidate outside a cue's table."""
    rng, _, _, bank, ii = grid_scene(11)
    sel = np.array([4, 1, 2], dtype=np.int32)
    mu1, mu0 = rng.normal(0, 300, 6), rng.normal(0, 300, 6)
    s1, s0 = rng.uniform(100, 400, 6), rng.uniform(100, 400, 6)
    # the cues' regions start at frame pixels (10, 5) and (4, 2)
    cues = [(cv2.integral(rng.random((100, 130)), sdepth=cv2.CV_64F), 10, 5, 0.5),
            (cv2.integral(rng.random((110, 140)), sdepth=cv2.CV_64F), 4, 2, 0.3)][:n_cues]
    offset = 0.3
    box, stages = (60, 50, 20, 20), [(25, 4), (10, 1)]
    got = _search(ii, bank, sel, mu1, s1, mu0, s0, box, stages, (cues, offset, relative))
    total = sum(w for *_, w in cues)
    at = box
    for (radius, step), (dx, dy, raw, n) in zip(stages, got):
        _, _, _, _, grid = _core.score_grid(ii, bank, sel, mu1[sel], s1[sel], mu0[sel], s0[sel],
                                            1e-30, at, radius, step, (150, 120), True)
        half = (grid.shape[0] - 1) // 2
        rows, cols = np.nonzero(np.isfinite(grid))
        xs, ys = at[0] + (cols - half) * step, at[1] + (rows - half) * step
        ref = grid[rows, cols].max() if relative else 0.0
        conf = 0.5 * (1.0 + np.tanh(0.5 * ((grid[rows, cols] - ref) / 3 - offset)))
        value = (1.0 - total) * conf
        for table, x0, y0, w in cues:
            value = value + w * _box_means(table, xs - x0, ys - y0, 20)
        best = int(np.argmax(value))
        assert (dx, dy) == ((cols[best] - half) * step, (rows[best] - half) * step)
        assert raw == grid[rows[best], cols[best]] and n == rows.size
        at = (at[0] + dx, at[1] + dy, 20, 20)
    # a weight of 0 is the plain choice
    plain = _search(ii, bank, sel, mu1, s1, mu0, s0, box, stages)
    zero = _search(ii, bank, sel, mu1, s1, mu0, s0, box, stages,
                   ([(t, x, y, 0.0) for t, x, y, _ in cues], offset, relative))
    assert [r[:2] for r in zero] == [r[:2] for r in plain]
    table, x0, y0, w = cues[0]
    small = np.ascontiguousarray(table[:60, :60])  # candidates reach beyond it
    with pytest.raises(IndexError, match="cue"):
        _search(ii, bank, sel, mu1, s1, mu0, s0, box, stages, ([*cues[1:], (small, x0, y0, w)], offset, relative))
    with pytest.raises(ValueError, match="weight"):
        _search(ii, bank, sel, mu1, s1, mu0, s0, box, stages, ([(table, x0, y0, 1.5)], offset, relative))
    with pytest.raises(ValueError, match="add up"):
        _search(ii, bank, sel, mu1, s1, mu0, s0, box, stages, ([(table, x0, y0, 0.6)] * 2, offset, relative))
    with pytest.raises(ValueError, match="cues must be"):
        _search(ii, bank, sel, mu1, s1, mu0, s0, box, stages, (cues, offset))
    with pytest.raises(ValueError, match="at least one"):
        _search(ii, bank, sel, mu1, s1, mu0, s0, box, stages, ([], offset, relative))


def test_relative_colour_merge_keeps_the_classifier_when_its_confidence_collapsed() -> None:
    """When every candidate's raw score is far below zero, the absolute merge's confidence is ~0
    everywhere and the cue alone picks the box, whatever its weight; measured from the stage's
    best, the classifier's choice still wins against a cue with little weight."""
    rng, _, _, bank, ii = grid_scene(11)
    sel = np.array([4, 1, 2], dtype=np.int32)
    mu1, mu0 = rng.normal(0, 300, 6), rng.normal(0, 300, 6)
    s1, s0 = np.full(6, 1.0), np.full(6, 1e4)  # a narrow target model: raw << 0 on the grid
    box, stages = (60, 50, 20, 20), [(25, 4)]
    plain = _search(ii, bank, sel, mu1, s1, mu0, s0, box, stages)
    assert plain[0][2] / 3 < -40  # the absolute confidence has collapsed
    # a cue that is highest far from the classifier's choice
    cue_map = np.zeros((100, 130))
    cue_map[:30, :30] = 1.0
    table = cv2.integral(cue_map, sdepth=cv2.CV_64F)
    absolute = _search(ii, bank, sel, mu1, s1, mu0, s0, box, stages, ([(table, 10, 5, 0.05)], 1.4, False))
    relative = _search(ii, bank, sel, mu1, s1, mu0, s0, box, stages, ([(table, 10, 5, 0.05)], 0.0, True))
    assert absolute[0][:2] != plain[0][:2]
    assert relative[0][:2] == plain[0][:2]


def test_template_fit_is_numpy_mean_of_log1p_z_squared() -> None:
    """template_fit = -mean(log1p(((values - mu) / sigma) ** 2)) of the box's features (the
    scale model's fit in rcwmil-plus; numpy's log1p may be a vectorised one, so to rounding),
    and refuses a model of the wrong size."""
    rng = np.random.default_rng(3)
    frame = rng.integers(0, 256, size=(90, 110), dtype=np.uint8)
    starts, rects, weights = random_bank(rng, 100, 24)
    bank = _core.FeatureBank(starts, rects, weights)
    ii = _core.IntegralImage()
    ii.compute(frame, (0, 0, 110, 90))
    mu, sigma = rng.normal(0, 50, 100), rng.uniform(5, 60, 100)
    for x, y in [(0, 0), (40, 30), (86, 66)]:
        v = _core.project(ii, bank, np.array([x]), np.array([y]))[:, 0]
        z = (v - mu) / sigma
        want = -float(np.mean(np.log1p(z * z)))
        assert _core.template_fit(ii, bank, x, y, mu, sigma) == pytest.approx(want, rel=1e-13)
    with pytest.raises(ValueError, match="one entry per feature"):
        _core.template_fit(ii, bank, 0, 0, mu[:-1], sigma[:-1])
    with pytest.raises((IndexError, ValueError)):
        _core.template_fit(ii, bank, 100, 80, mu, sigma)  # the box leaves the table
