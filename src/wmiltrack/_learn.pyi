"""Type stubs of the Cython learning kernels (``wmiltrack._learn``)."""

import numpy as np
import numpy.typing as npt

def wmil_select(h_pos: npt.NDArray[np.float64], h_neg: npt.NDArray[np.float64],
                w_pos: npt.NDArray[np.float64], k: int,
                code_gradient: bool = False) -> npt.NDArray[np.int32]:
    """Greedy WMIL selection by the functional-gradient inner product (see selection.py)."""

def milboost_select(h_pos: npt.NDArray[np.float64], h_neg: npt.NDArray[np.float64], k: int,
                    guard: float = 1e-5) -> npt.NDArray[np.int32]:
    """Greedy MILBoost selection: Noisy-OR positive bag, each negative its own bag."""

def gaussian_update(values: npt.NDArray[np.float64], mu: npt.NDArray[np.float64],
                    sigma: npt.NDArray[np.float64], lam: float, first: bool, direct_first: bool,
                    mil: bool, sigma_floor: float
                    ) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """One class's Gaussians after a frame's samples ``values`` (M x n, n >= 1): (mu, sigma)."""
