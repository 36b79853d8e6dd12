"""The Gaussian weak-classifier update (spec sections 1.1 and 1.2)."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import gaussian_pool_update

from wmiltrack.engine.classifier import GaussianPool
from wmiltrack.engine.params import Params


def stats(v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return v.mean(axis=1), np.sqrt(((v - v.mean(axis=1, keepdims=True)) ** 2).mean(axis=1))


def test_direct_first_update_then_blend_with_lambda_weighting_the_old_model() -> None:
    rng = np.random.default_rng(0)
    p = Params(num_features=3, num_selected=3)
    pool = GaussianPool(p)
    a_pos, a_neg = rng.normal(5, 2, (3, 45)), rng.normal(-1, 3, (3, 50))
    gaussian_pool_update(pool, a_pos, a_neg)
    m, s = stats(a_pos)
    assert np.allclose(pool.mu1, m) and np.allclose(pool.sigma1, s)
    b_pos, b_neg = rng.normal(7, 1, (3, 45)), rng.normal(0, 1, (3, 50))
    gaussian_pool_update(pool, b_pos, b_neg)
    lam = 0.9
    m2, s2 = stats(b_pos)
    sigma = np.sqrt(lam * s**2 + (1 - lam) * s2**2 + lam * (1 - lam) * (m - m2) ** 2)  # old mu
    assert np.allclose(pool.sigma1, sigma)
    assert np.allclose(pool.mu1, lam * m + (1 - lam) * m2)
    n1, t1 = stats(a_neg)
    n2, t2 = stats(b_neg)
    assert np.allclose(pool.mu0, lam * n1 + (1 - lam) * n2)


def test_reference_blend_at_init_shrinks_the_mean() -> None:
    p = Params(num_features=2, num_selected=2, first_update="blend", learning_rate=0.85)
    pool = GaussianPool(p)
    v = np.array([[10.0, 12.0, 14.0], [1.0, 1.0, 1.0]])
    gaussian_pool_update(pool, v, v)
    assert np.allclose(pool.mu1, 0.15 * v.mean(axis=1))
    m, s = stats(v)
    assert np.allclose(pool.sigma1, np.sqrt(0.85 * 1 + 0.15 * s**2 + 0.85 * 0.15 * m**2))


def test_sigma_floor() -> None:
    pool = GaussianPool(Params(num_features=1, num_selected=1))
    gaussian_pool_update(pool, np.full((1, 45), 3.0), np.full((1, 50), 3.0))
    assert pool.sigma1[0] == pytest.approx(1e-6)


def test_miltrack_rule_stores_a_variance_around_the_updated_mean() -> None:
    rng = np.random.default_rng(1)
    p = Params.for_variant("mil").replace(num_features=2, num_selected=2)
    pool = GaussianPool(p)
    a = rng.normal(3, 2, (2, 40))
    gaussian_pool_update(pool, a, a)
    assert np.allclose(pool.mu1, a.mean(axis=1))
    assert np.allclose(pool.sigma1**2, a.var(axis=1) + 1e-9)
    b = rng.normal(4, 1, (2, 40))
    v_old = pool.sigma1**2
    gaussian_pool_update(pool, b, b)
    mu = 0.85 * a.mean(axis=1) + 0.15 * b.mean(axis=1)
    assert np.allclose(pool.mu1, mu)
    assert np.allclose(pool.sigma1**2, 0.85 * v_old + 0.15 * ((b - mu[:, None]) ** 2).mean(axis=1))


def test_a_class_without_samples_keeps_its_model() -> None:
    pool = GaussianPool(Params(num_features=2, num_selected=2))
    gaussian_pool_update(pool, np.ones((2, 5)), np.zeros((2, 0)))
    assert np.all(pool.mu0 == 0) and np.all(pool.sigma0 == 1)


@pytest.mark.parametrize("variant", ["rcwmil", "mil", "ct", "fct"])
@pytest.mark.parametrize("first", [True, False])
def test_compiled_update_is_numpy_bit_for_bit(variant: str, first: bool) -> None:
    """The compiled update reproduces numpy's mean/std (pairwise sums, two passes) exactly,
    for every sample count (numpy changes summation scheme at 8 and above 128 samples) and
    for the column slices the tracker passes (both bags live in one array)."""
    from reference_kernels import reference_update

    from wmiltrack import _learn

    p = Params.for_variant(variant)
    rng = np.random.default_rng(3)
    for n in [1, 2, 7, 8, 9, 15, 16, 17, 45, 50, 95, 127, 128, 129, 255, 256, 300, 1000]:
        m = 23
        values = rng.standard_normal((m, n)) * 10 ** rng.uniform(-2, 4, (m, 1)) + rng.uniform(-99, 99, (m, 1))
        mu, sigma = rng.standard_normal(m) * 40, rng.uniform(0.01, 30, m)
        want = reference_update(mu, sigma, values, p.learning_rate, first, p)
        both = np.concatenate([values, rng.standard_normal((m, 5))], axis=1)
        for v in (values, both[:, :n]):
            got = _learn.gaussian_update(v, mu, sigma, p.learning_rate, first,
                                         p.first_update == "direct", p.classifier == "mil", p.sigma_floor)
            np.testing.assert_array_equal(got[0], want[0], err_msg=f"mu, n={n}")
            np.testing.assert_array_equal(got[1], want[1], err_msg=f"sigma, n={n}")
