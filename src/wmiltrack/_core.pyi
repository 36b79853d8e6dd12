"""Type stubs of wmiltrack's C++/Eigen core (pybind11 module ``wmiltrack._core``)."""

from typing import overload

import numpy as np
import numpy.typing as npt

_F64 = npt.NDArray[np.float64]
_I32 = npt.ArrayLike

class IntegralImage:
    """Integral image of a frame region, luma from BGR(A) as OpenCV's BGR2GRAY."""

    def __init__(self) -> None: ...
    def compute(self, frame: npt.NDArray[np.uint8], roi: tuple[int, int, int, int]) -> None:
        """Rebuild over roi = (x, y, w, h), clipped to the frame."""
    @property
    def x0(self) -> int: ...
    @property
    def y0(self) -> int: ...
    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...
    def table(self) -> _F64:
        """A copy of the (height + 1) x (width + 1) table; row and column 0 are zero."""
    def rect_sum(self, x: int, y: int, w: int, h: int) -> float:
        """Exact pixel sum over columns [x, x+w) and rows [y, y+h), in frame coordinates."""

class FeatureBank:
    """Haar-like features: weighted rectangle sums at offsets from a box corner."""

    def __init__(self, starts: _I32, rects: _I32, weights: npt.ArrayLike) -> None: ...
    @property
    def size(self) -> int: ...
    @property
    def num_rects(self) -> int: ...
    @property
    def extent(self) -> tuple[int, int, int, int]: ...

def project(ii: IntegralImage, bank: FeatureBank, xs: _I32, ys: _I32,
            features: _I32 | None = None) -> _F64:
    """Feature values (features x boxes) for boxes with top-left corners (xs, ys)."""

def log_ratio(values: npt.ArrayLike, mu1: npt.ArrayLike, sigma1: npt.ArrayLike,
              mu0: npt.ArrayLike, sigma0: npt.ArrayLike, guard: float) -> _F64:
    """Per-feature Gaussian log-likelihood ratio h(x) = ln(p1 + guard) - ln(p0 + guard)."""

@overload
def score_grid(ii: IntegralImage, bank: FeatureBank, selected: _I32, mu1: npt.ArrayLike,
               sigma1: npt.ArrayLike, mu0: npt.ArrayLike, sigma0: npt.ArrayLike, guard: float,
               box: tuple[int, int, int, int], radius: int, step: int,
               frame_size: tuple[int, int]) -> tuple[int, int, float, int]: ...
@overload
def score_grid(ii: IntegralImage, bank: FeatureBank, selected: _I32, mu1: npt.ArrayLike,
               sigma1: npt.ArrayLike, mu0: npt.ArrayLike, sigma0: npt.ArrayLike, guard: float,
               box: tuple[int, int, int, int], radius: int, step: int,
               frame_size: tuple[int, int], return_scores: bool,
               ) -> tuple[int, int, float, int] | tuple[int, int, float, int, _F64]: ...
