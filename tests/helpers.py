"""Helpers that drive the compiled learning kernels the way the engine once did, for tests that
check the kernels' rules one step at a time (the engine itself makes one core call a frame)."""

from __future__ import annotations

import numpy as np

from wmiltrack import _learn
from wmiltrack.engine.classifier import GaussianPool


def _c(a: np.ndarray) -> np.ndarray:
    """float64 without copying a float64 view (the kernels take strided rows)."""
    return np.asarray(a, dtype=np.float64)


def gaussian_pool_update(pool: GaussianPool, positives: np.ndarray, negatives: np.ndarray,
                         learning_rate: float | None = None) -> None:
    """Fold the feature values (M x n) of one frame's positives and negatives into ``pool``
    (spec 1.1, or 1.2 for ``classifier="mil"``); ``learning_rate`` (lambda, the old model's
    weight) defaults to the pool's parameters'. A class without samples keeps its model."""
    p = pool.params
    lam = p.learning_rate if learning_rate is None else learning_rate

    def one(cls: int, mu: np.ndarray, sigma: np.ndarray, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        if values.shape[1] == 0:
            return mu, sigma
        return _learn.gaussian_update(_c(values), mu, sigma, lam, pool.first(cls),
                                      p.first_update == "direct", p.classifier == "mil", p.sigma_floor)

    mu1, sigma1 = one(1, pool.mu1, pool.sigma1, positives)
    mu0, sigma0 = one(0, pool.mu0, pool.sigma0, negatives)
    pool.assign(mu1, sigma1, mu0, sigma0, positives.shape[1] > 0, negatives.shape[1] > 0)


def wmil_select(h_pos: np.ndarray, h_neg: np.ndarray, w_pos: np.ndarray, k: int,
                *, code_gradient: bool = False) -> np.ndarray:
    """The compiled greedy weighted-MIL selection of ``k`` features (spec section 5), as the
    core's learning step runs it: ``(k,)`` int32 feature indices in selection order.

    With H = 0 for every instance at the start, repeat ``k`` times: take the unselected feature
    m maximising ``<h_m, dL/dH>`` where L = ln sum_j w_j sigma(H(x+_j)) + ln sum_j
    (1 - sigma(H(x-_j))), then add h_m to H. ``code_gradient`` uses the reference code's
    w s (1 - w s) / sum(w s) instead of the true derivative.
    """
    return np.asarray(_learn.wmil_select(_c(h_pos), _c(h_neg), _c(w_pos), int(k), bool(code_gradient)))
