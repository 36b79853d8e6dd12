"""Online feature selection: weighted MIL (gradient inner product) and MILBoost (Noisy-OR).

The loops are compiled (``_learn.pyx``); this module documents them. Plain numpy versions
written from the spec live with the tests (``tests/reference_kernels.py``).
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
