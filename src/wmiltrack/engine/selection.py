"""Online feature selection: weighted MIL (gradient inner product) and MILBoost (Noisy-OR).

The loops are compiled (``_learn.pyx``); this module documents them and keeps plain numpy
references that the tests compare them with.
"""

from __future__ import annotations

import numpy as np

from .. import _learn


def _c(a: np.ndarray) -> np.ndarray:
    """float64 without copying a float64 view (the kernels take strided rows)."""
    return np.asarray(a, dtype=np.float64)


def wmil_select(h_pos: np.ndarray, h_neg: np.ndarray, w_pos: np.ndarray, k: int,
                *, code_gradient: bool = False) -> np.ndarray:
    """Greedy weighted-MIL selection of ``k`` features (spec section 5).

    With H = 0 for every instance at the start, repeat ``k`` times: take the unselected
    feature m maximising ``<h_m, dL/dH>`` where L = ln sum_j w_j sigma(H(x+_j)) +
    ln sum_j (1 - sigma(H(x-_j))), then add h_m to H.

    Parameters
    ----------
    h_pos, h_neg : (M, P) and (M, N) arrays
        Weak-classifier log ratios on the positive and negative instances.
    w_pos : (P,) array
        Positive instance weights.
    k : int
        Number of features to select, 1 <= k <= M.
    code_gradient : bool
        Use the reference code's w s (1 - w s) / sum(w s) instead of the true derivative.

    Returns
    -------
    (k,) int32 array of feature indices, in selection order.
    """
    return np.asarray(_learn.wmil_select(_c(h_pos), _c(h_neg), _c(w_pos), int(k), bool(code_gradient)))


def milboost_select(h_pos: np.ndarray, h_neg: np.ndarray, k: int, *, guard: float = 1e-5) -> np.ndarray:
    """Greedy MILBoost selection of ``k`` features (spec section 4).

    Minimises, step by step, the negative log-likelihood of a Noisy-OR positive bag
    (divided by its size, as MILTrack's code does) plus one bag per negative.
    """
    return np.asarray(_learn.milboost_select(_c(h_pos), _c(h_neg), int(k), float(guard)))


# -- numpy references ---------------------------------------------------------------------
def _sigmoid(z: np.ndarray) -> np.ndarray:
    return 0.5 * (1.0 + np.tanh(0.5 * z))


def wmil_log_likelihood(H_pos: np.ndarray, H_neg: np.ndarray, w_pos: np.ndarray) -> float:
    """L = ln sum_j w_j sigma(H+_j) + ln sum_j (1 - sigma(H-_j)) (the weighted bag model)."""
    total = 0.0
    if H_pos.size:
        total += float(np.log(np.sum(w_pos * _sigmoid(H_pos))))
    if H_neg.size:
        total += float(np.log(np.sum(1.0 - _sigmoid(H_neg))))
    return total


def wmil_select_reference(h_pos: np.ndarray, h_neg: np.ndarray, w_pos: np.ndarray, k: int,
                          *, code_gradient: bool = False) -> np.ndarray:
    """Plain numpy version of :func:`wmil_select` (for tests; not numerically hardened)."""
    m = h_pos.shape[0]
    H_pos = np.zeros(h_pos.shape[1])
    H_neg = np.zeros(h_neg.shape[1])
    chosen: list[int] = []
    for _ in range(k):
        sp = _sigmoid(H_pos)
        ws = w_pos * sp
        g_pos = ws * (1.0 - (ws if code_gradient else sp)) / ws.sum() if H_pos.size else H_pos
        sn = _sigmoid(H_neg)
        g_neg = -sn * (1.0 - sn) / (1.0 - sn).sum() if H_neg.size else H_neg
        score = h_pos @ g_pos + h_neg @ g_neg
        score[chosen] = -np.inf
        best = int(np.argmax(score))
        chosen.append(best)
        H_pos = H_pos + h_pos[best]
        H_neg = H_neg + h_neg[best]
    assert len(set(chosen)) == len(chosen) <= m
    return np.array(chosen, dtype=np.int32)


def milboost_nll(H_pos: np.ndarray, H_neg: np.ndarray, guard: float = 1e-5) -> float:
    """MILTrack's bag negative log-likelihood for strong-classifier outputs H."""
    pos = -np.log(1.0 - np.prod(1.0 - _sigmoid(H_pos)) + guard) / max(H_pos.size, 1)
    neg = -np.sum(np.log(guard + 1.0 - _sigmoid(H_neg))) / max(H_neg.size, 1)
    return float(pos + neg)


def milboost_select_reference(h_pos: np.ndarray, h_neg: np.ndarray, k: int, *,
                              guard: float = 1e-5) -> np.ndarray:
    """Plain numpy version of :func:`milboost_select`: evaluates the NLL for every candidate."""
    H_pos = np.zeros(h_pos.shape[1])
    H_neg = np.zeros(h_neg.shape[1])
    chosen: list[int] = []
    for _ in range(k):
        nll = np.array([
            np.inf if m in chosen else milboost_nll(H_pos + h_pos[m], H_neg + h_neg[m], guard)
            for m in range(h_pos.shape[0])
        ])
        best = int(np.argmin(nll))
        chosen.append(best)
        H_pos = H_pos + h_pos[best]
        H_neg = H_neg + h_neg[best]
    return np.array(chosen, dtype=np.int32)
