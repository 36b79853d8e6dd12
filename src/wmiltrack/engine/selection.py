"""Online feature selection by MILBoost (Noisy-OR).

The loop is compiled (``_learn.pyx``); this module documents it. The weighted-MIL selection
(gradient inner product) runs inside the core's learning step (``_core.learn``). Plain numpy
versions of both, written from the spec, live with the tests (``tests/reference_kernels.py``).
"""

from __future__ import annotations

import numpy as np

from .. import _learn


def _c(a: np.ndarray) -> np.ndarray:
    """float64 without copying a float64 view (the kernels take strided rows)."""
    return np.asarray(a, dtype=np.float64)


def milboost_select(h_pos: np.ndarray, h_neg: np.ndarray, k: int, *, guard: float = 1e-5) -> np.ndarray:
    """Greedy MILBoost selection of ``k`` features (spec section 4).

    Minimises, step by step, the negative log-likelihood of a Noisy-OR positive bag
    (divided by its size, as MILTrack's code does) plus one bag per negative.
    """
    return np.asarray(_learn.milboost_select(_c(h_pos), _c(h_neg), int(k), float(guard)))
