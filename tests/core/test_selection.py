"""Feature selection: compiled loops against numpy and against brute-force likelihoods."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import wmil_select
from reference_kernels import (
    milboost_nll,
    milboost_select_reference,
    wmil_log_likelihood,
    wmil_select_reference,
)

from wmiltrack.engine.selection import milboost_select


def bags(seed: int, m: int = 12, p: int = 9, n: int = 11, scale: float = 2.0):
    rng = np.random.default_rng(seed)
    h_pos = rng.normal(0.5, scale, (m, p))
    h_neg = rng.normal(-0.5, scale, (m, n))
    d = rng.uniform(0, 4, p)
    w = np.exp(-d) / np.exp(-d).sum()
    return h_pos, h_neg, w


@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize("code_gradient", [False, True])
def test_wmil_selection_matches_numpy_reference(seed: int, code_gradient: bool) -> None:
    h_pos, h_neg, w = bags(seed)
    got = wmil_select(h_pos, h_neg, w, 6, code_gradient=code_gradient)
    want = wmil_select_reference(h_pos, h_neg, w, 6, code_gradient=code_gradient)
    np.testing.assert_array_equal(got, want)
    assert len(set(got.tolist())) == 6


@pytest.mark.parametrize("seed", range(5))
def test_wmil_selection_follows_the_bag_likelihood_gradient(seed: int) -> None:
    """Each pick maximises the directional derivative of the bag log-likelihood, measured by
    central finite differences of L(H + t h_m) with no use of the analytic gradient."""
    h_pos, h_neg, w = bags(seed, scale=0.7)
    chosen = wmil_select(h_pos, h_neg, w, 5)
    H_pos, H_neg = np.zeros(h_pos.shape[1]), np.zeros(h_neg.shape[1])
    t = 1e-6
    for pick in chosen:
        deriv = np.array([
            (wmil_log_likelihood(H_pos + t * h_pos[m], H_neg + t * h_neg[m], w)
             - wmil_log_likelihood(H_pos - t * h_pos[m], H_neg - t * h_neg[m], w)) / (2 * t)
            for m in range(h_pos.shape[0])
        ])
        used = [c for c in chosen[: list(chosen).index(pick)]]
        deriv[used] = -np.inf
        assert int(np.argmax(deriv)) == pick
        H_pos, H_neg = H_pos + h_pos[pick], H_neg + h_neg[pick]


def test_wmil_selection_survives_saturated_responses() -> None:
    # Responses of +-69 per feature (the 1e-30 guard) drive sigma to exactly 0 or 1 in
    # double precision; the gradient must stay finite and the picks distinct.
    h_pos, h_neg, w = bags(7, m=30, scale=1.0)
    h_pos = np.sign(h_pos) * 69.0
    h_neg = np.sign(h_neg) * 69.0
    got = wmil_select(h_pos, h_neg, w, 20)
    assert len(set(got.tolist())) == 20


def test_wmil_selection_without_negatives() -> None:
    h_pos, _, w = bags(8)
    got = wmil_select(h_pos, np.zeros((h_pos.shape[0], 0)), w, 3)
    want = wmil_select_reference(h_pos, np.zeros((h_pos.shape[0], 0)), w, 3)
    np.testing.assert_array_equal(got, want)


@pytest.mark.parametrize("seed", range(4))
def test_milboost_selection_matches_brute_force_nll(seed: int) -> None:
    h_pos, h_neg, _ = bags(seed, m=15, p=10, n=14, scale=3.0)
    got = milboost_select(h_pos, h_neg, 5)
    want = milboost_select_reference(h_pos, h_neg, 5)
    np.testing.assert_array_equal(got, want)
    # the first pick really has the smallest bag NLL of all features
    nll = [milboost_nll(h_pos[m], h_neg[m]) for m in range(15)]
    assert got[0] == int(np.argmin(nll))


def test_selection_rejects_bad_k() -> None:
    h_pos, h_neg, w = bags(0)
    with pytest.raises(ValueError):
        wmil_select(h_pos, h_neg, w, 0)
    with pytest.raises(ValueError):
        wmil_select(h_pos, h_neg, w, 13)
    with pytest.raises(ValueError):
        milboost_select(h_pos, h_neg, 99)


@pytest.mark.parametrize("w, expected", [([0.8, 0.1, 0.1], 1), ([0.2, 0.4, 0.4], 2)])
def test_wmil_gradient_stays_exact_when_the_bags_are_confidently_classified(w, expected) -> None:
    """After feature 0, H = +50 on every positive and -50 on every negative, so every
    gradient entry is ~e^-50. In double precision 1 - sigma(50) rounds to 0; the true
    positive-bag gradient w_j sigma(H)(1 - sigma(H)) / sum(w sigma) ~ w_j e^-50 must still be
    compared with the negative one (~ e^-50 / 2): feature 1 helps positive instance 0
    (gain w_0 e^-50), feature 2 pushes negative 0 further down (gain e^-50 / 2)."""
    h_pos = np.array([[50.0, 50, 50], [1, 0, 0], [0, 0, 0]])
    h_neg = np.array([[-50.0, -50], [0, 0], [-1, 0]])
    picks = wmil_select(h_pos, h_neg, np.array(w), 2)
    assert picks[0] == 0 and picks[1] == expected


@pytest.mark.parametrize("m", [5, 8, 37, 100])
def test_selection_reads_column_slices_of_one_array(m: int) -> None:
    """The tracker keeps both bags' log ratios in one array and passes column slices; the
    kernels must pick what they pick from contiguous copies (and M need not be a multiple
    of the eight features scored at a time)."""
    rng = np.random.default_rng(m)
    h = rng.normal(size=(m, 45 + 50)) * 3
    w = np.exp(-rng.uniform(0, 4, 45))
    w /= w.sum()
    h_pos, h_neg = h[:, :45], h[:, 45:]
    k = min(m, 20)
    np.testing.assert_array_equal(wmil_select(h_pos, h_neg, w, k),
                                  wmil_select(h_pos.copy(), h_neg.copy(), w, k))
    np.testing.assert_array_equal(wmil_select(h_pos, h_neg, w, k),
                                  wmil_select_reference(h_pos, h_neg, w, k))
    np.testing.assert_array_equal(milboost_select(h_pos, h_neg, k),
                                  milboost_select(h_pos.copy(), h_neg.copy(), k))
