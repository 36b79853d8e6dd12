"""Type stubs of wmiltrack's C++/Eigen core (pybind11 module ``wmiltrack._core``)."""

from collections.abc import Sequence
from typing import Final, overload

import numpy as np
import numpy.typing as npt

_F64 = npt.NDArray[np.float64]
# Integer arrays (coordinates, indices): any integer dtype or integral floats, every value in
# the int32 range; out-of-range or fractional values raise ValueError, other dtypes TypeError.
_I32 = npt.ArrayLike

# True when built with WMILTRACK_NATIVE=ON (-march=native): runs only on CPUs like the build
# machine's. The default build is portable (x86-64 baseline) and gives the same bits on any CPU.
BUILD_NATIVE: Final[bool]

# The copy of the vectorised kernels (exp/log/log1p, WMIL scores, MILBoost selection) this CPU
# runs: "avx2" (chosen at run time), "sse2" (the baseline) or "scalar"; every copy computes the
# same bits. set_simd_portable(True) forces the baseline copy, for tests and benchmarks.
def simd_path() -> str: ...
def set_simd_portable(portable: bool) -> None: ...

# Channel ids of IntegralImage.compute_channels; every channel is an integer in 0..255.
# gx, gy: central differences of the luma (neighbours outside the ROI used when the frame
# has them, the frame's edge replicated), y growing downwards.
MAX_RECT_AREA: Final[int]  # largest feature rectangle (pixels): its sums are exact in 32 bits
CH_LUMA: Final[int]  # 0: OpenCV BGR2GRAY, as compute()
CH_GRAD: Final[int]  # 1: (|gx| + |gy|) // 2
CH_OPP_RG: Final[int]  # 2: (R - G + 255) // 2, colour frames only
CH_OPP_YB: Final[int]  # 3: (R + G - 2B + 510) // 4, colour frames only
NUM_CHANNEL_KINDS: Final[int]  # 8

class IntegralImage:
    """Integral image of a frame region, luma from BGR(A) as OpenCV's BGR2GRAY.

    Every method and property but ``computed`` raises ValueError until compute() or
    compute_channels() succeeded. Threads may share one object: readers (project,
    score_grid, rect_sum, table, the properties) each see one complete table, the one
    current when they started, while another thread recomputes it; a failed compute leaves
    the object unchanged."""

    def __init__(self) -> None: ...
    @property
    def computed(self) -> bool:
        """Whether a compute() or compute_channels() succeeded (the other members need one)."""
    def compute(self, frame: npt.NDArray[np.uint8], roi: tuple[int, int, int, int]) -> None:
        """Rebuild over roi = (x, y, w, h), clipped to the frame."""
    def compute_channels(self, frame: npt.NDArray[np.uint8], roi: tuple[int, int, int, int],
                         channels: Sequence[int]) -> None:
        """Rebuild over roi = (x, y, w, h), clipped to the frame, with plane k holding channel
        channels[k] (CH_* ids). ValueError for an unknown id, no channels, or a colour
        channel on a gray frame."""
    @property
    def num_channels(self) -> int: ...
    @property
    def channels(self) -> tuple[int, ...]:
        """The channel id of each plane."""
    @property
    def x0(self) -> int: ...
    @property
    def y0(self) -> int: ...
    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...
    def table(self, plane: int = 0) -> _F64:
        """A copy of plane `plane`'s (height + 1) x (width + 1) table; row and column 0 are zero."""
    def rect_sum(self, x: int, y: int, w: int, h: int, plane: int = 0) -> float:
        """Exact sum over columns [x, x+w) and rows [y, y+h), in frame coordinates, on a plane."""

class FeatureBank:
    """Haar-like features: weighted rectangle sums at offsets from a box corner."""

    def __init__(self, starts: _I32, rects: _I32, weights: npt.ArrayLike,
                 channels: _I32 | None = None) -> None:
        """channels: (R,) integral-image plane of each rectangle (None: all on plane 0)."""
    @property
    def size(self) -> int: ...
    @property
    def num_rects(self) -> int: ...
    @property
    def channels(self) -> npt.NDArray[np.int32]:
        """Integral-image plane of each rectangle (a copy; zeros for a bank built without)."""
    @property
    def planes_needed(self) -> int:
        """Planes an integral image needs for this bank: 1 + the largest."""
    @property
    def extent(self) -> tuple[int, int, int, int]: ...

def project(ii: IntegralImage, bank: FeatureBank, xs: _I32, ys: _I32,
            features: _I32 | None = None) -> _F64:
    """Feature values (features x boxes) for boxes with top-left corners (xs, ys).

    xs, ys and features must hold integers in the int32 range: floats are accepted only
    when integral, anything else raises ValueError (out of range, fractional) or TypeError."""

def log_ratio(values: npt.ArrayLike, mu1: npt.ArrayLike, sigma1: npt.ArrayLike,
              mu0: npt.ArrayLike, sigma0: npt.ArrayLike, guard: float) -> _F64:
    """Per-feature Gaussian log-likelihood ratio h(x) = ln(p1 + guard) - ln(p0 + guard).

    Each value depends on its own inputs only (not on the other samples): the same value
    gives the same bits here and inside score_grid."""

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
def template_fit(ii: IntegralImage, bank: FeatureBank, x: int, y: int, mu: npt.ArrayLike,
                 sigma: npt.ArrayLike) -> float:
    """-mean(log1p(z**2)) of the box's features, z = (value - mu) / sigma."""

_Cues = tuple[Sequence[tuple[_F64, int, int, float] | tuple[_F64, int, int, float, bool]], float, bool]
_Searched = tuple[tuple[int, int, float, int], ...]
_Learnt = tuple[_F64, _F64, _F64, _F64, npt.NDArray[np.int32] | None, _F64 | None, _F64 | None,
                _F64 | None]

class SearchRequest:
    """A coarse-to-fine search's inputs, by name. cues = (tables, offset, relative), tables a
    list of (table, x0, y0, weight): box-mean cues merged into each stage's choice."""
    def __init__(self, ii: IntegralImage, bank: FeatureBank, selected: _I32, mu1: npt.ArrayLike,
                 sigma1: npt.ArrayLike, mu0: npt.ArrayLike, sigma0: npt.ArrayLike, guard: float,
                 box: tuple[int, int, int, int], stages: Sequence[tuple[int, int]],
                 frame_size: tuple[int, int], frame: npt.NDArray[np.uint8] | None = None,
                 roi: tuple[int, int, int, int] | None = None, cues: _Cues | None = None) -> None: ...
    ii: IntegralImage
    bank: FeatureBank
    selected: _I32
    mu1: _F64
    sigma1: _F64
    mu0: _F64
    sigma0: _F64
    guard: float
    box: tuple[int, int, int, int]
    stages: list[tuple[int, int]]
    frame_size: tuple[int, int]
    frame: npt.NDArray[np.uint8] | None
    roi: tuple[int, int, int, int] | None
    cues: _Cues | None

def search(request: SearchRequest) -> _Searched:
    """A coarse-to-fine search in one call: one (dx, dy, best_score, n_candidates) per stage."""


class ColourHistograms:
    """Foreground/background colour histograms blended over frames, and P(target | bin)."""
    def __init__(self, bits: int, rate: float, *, intensity: bool = False) -> None: ...
    def copy(self) -> ColourHistograms:
        """An independent copy (the histograms as they are now)."""
    @property
    def bits(self) -> int: ...
    @property
    def rate(self) -> float: ...
    @property
    def intensity(self) -> bool: ...
    @property
    def learnt(self) -> bool: ...
    def learn(self, frame: npt.NDArray[np.uint8], region: tuple[int, int, int, int],
              inside: tuple[int, int, int, int], core: tuple[int, int, int, int], *,
              step: int = 1) -> None:
        """Fold in one frame (core: target pixels; region outside inside: background; every
        step-th row and column of the frame)."""
    def likelihood_integral(self, frame: npt.NDArray[np.uint8],
                            region: tuple[int, int, int, int]) -> _F64:
        """(h + 1) x (w + 1) integral image of the per-pixel likelihood over region."""
    def likelihood_sums(self, frame: npt.NDArray[np.uint8], region: tuple[int, int, int, int],
                        inner: tuple[int, int, int, int], *, step: int = 1,
                        ) -> tuple[float, float, int, int]:
        """(inner sum, region sum, inner pixels, region pixels) of the per-pixel likelihood over
        the sampled pixels (every step-th row and column of the frame); inner relative to
        region."""
    @property
    def foreground(self) -> _F64: ...
    @property
    def background(self) -> _F64: ...
    @property
    def likelihood(self) -> _F64: ...

class LearnRequest:
    """A learning step's inputs, by name (see _core.learn)."""
    def __init__(self, ii: IntegralImage, bank: FeatureBank, xs: _I32, ys: _I32, n_pos: int,
                 mu1: _F64, sigma1: _F64, mu0: _F64, sigma0: _F64, lam: float, first_pos: bool,
                 first_neg: bool, direct_first: bool, mil: bool, sigma_floor: float, guard: float,
                 select: str, w_pos: _F64 | None = None, k: int = 0, code_gradient: bool = False,
                 extra_neg: _F64 | None = None,
                 second: tuple[_F64, _F64, float, bool] | None = None) -> None: ...
    ii: IntegralImage
    bank: FeatureBank
    xs: _I32
    ys: _I32
    n_pos: int
    mu1: _F64
    sigma1: _F64
    mu0: _F64
    sigma0: _F64
    lam: float
    first_pos: bool
    first_neg: bool
    direct_first: bool
    mil: bool
    sigma_floor: float
    guard: float
    select: str
    w_pos: _F64 | None
    k: int
    code_gradient: bool
    extra_neg: _F64 | None
    second: tuple[_F64, _F64, float, bool] | None

def learn(request: LearnRequest) -> _Learnt:
    """The learning half of a frame step in one call: (mu1, sigma1, mu0, sigma0, selected, h,
    mu2, sigma2); extra_neg adds negatives as feature values, second is a second target model
    (mu, sigma, lam, first) updated from the positives alone."""

class BagRequest:
    """A BagSampler's draw, by name: the negatives drawn from rng as numpy would."""
    def __init__(self, rng: np.random.Generator, pos_offsets: _I32, pos_terms: _F64 | None,
                 weights: str, neg_offsets: _I32, exact: bool, neg_count: int,
                 keep_prob: float) -> None: ...
    rng: np.random.Generator
    pos_offsets: _I32
    pos_terms: _F64 | None
    weights: str
    neg_offsets: _I32
    exact: bool
    neg_count: int
    keep_prob: float

_FrameStep = tuple[_Searched, _Learnt, tuple[npt.NDArray[np.int32], npt.NDArray[np.int32], int]]

def frame_step(search: SearchRequest, learn: LearnRequest, bags: BagRequest) -> _FrameStep:
    """The search, the bags sampled where it landed (numpy's draws from the request's rng),
    then the learning on them, on the integral image the search read: (search's result,
    learn's, (xs, ys, n_pos))."""

def frame_step_many(steps: Sequence[tuple[SearchRequest, LearnRequest, BagRequest]],
                    threads: int) -> list[_FrameStep]:
    """frame_step() for several targets in one call, on up to `threads` threads."""

_Bags = tuple[npt.NDArray[np.int32], npt.NDArray[np.int32], int]

def learn_at(learn: LearnRequest, bags: BagRequest, box: tuple[int, int, int, int],
             frame_size: tuple[int, int]) -> tuple[_Learnt, _Bags]:
    """The bags sampled around box (numpy's draws from the request's rng), then the learning
    on them (its extra negatives kept): (learn's result, (xs, ys, n_pos))."""

def learn_at_many(steps: Sequence[tuple[LearnRequest, BagRequest, tuple[int, int, int, int],
                                        tuple[int, int]]],
                  threads: int) -> list[tuple[_Learnt, _Bags]]:
    """learn_at() for several targets in one call, on up to `threads` threads."""

def numpy_pcg64_stepped_here(rng: np.random.Generator) -> bool:
    """Whether the core steps this generator's PCG64 state itself for Bernoulli draws."""

def numpy_choice_sorted(rng: np.random.Generator, n: int, k: int) -> list[int]:
    """sorted(rng.choice(n, k, replace=False)), drawn as numpy draws it."""

def numpy_bernoulli_first(rng: np.random.Generator, n: int, p: float, limit: int) -> list[int]:
    """The first `limit` indices of rng.random(n) < p, drawn as numpy draws them."""

def search_many(requests: Sequence[SearchRequest], threads: int) -> list[_Searched]:
    """search() for several requests in one call, on up to `threads` threads."""

def learn_many(requests: Sequence[LearnRequest], threads: int) -> list[_Learnt]:
    """learn() for several requests in one call, on up to `threads` threads."""

# --- correlation filters (fhog.hpp, correlation.hpp) ------------------------------------------
_F32 = npt.NDArray[np.float32]
FHOG_CHANNELS: Final[int]  # 31: 18 signed + 9 unsigned orientation bins + 4 block energies

def cf_gray_patch(frame: npt.NDArray[np.uint8], centre: tuple[float, float],
                  size: tuple[float, float], out_size: tuple[int, int]) -> _F32:
    """The region of size (w, h) centred on centre, resampled to out_size = (w, h) pixels of
    luma / 255 (rows x cols; edge pixels replicated outside the frame; a tent over the pixels
    under each output pixel, every floor(span / 2)-th of them where it spans 4 or more)."""
def fhog(patch: npt.ArrayLike, cell: int = 4) -> _F32:
    """fHOG of a gray patch: (31, rows // cell, cols // cell)."""
def fhog_region(frame: npt.NDArray[np.uint8], centre: tuple[float, float],
                size: tuple[float, float], out_size: tuple[int, int], cell: int = 4) -> _F32:
    """fhog(cf_gray_patch(frame, centre, size, out_size), cell)."""
def scale_samples(frame: npt.NDArray[np.uint8], centre: tuple[float, float],
                  size: tuple[float, float], factors: Sequence[float],
                  model_size: tuple[int, int], cell: int = 4) -> _F32:
    """(len(factors), dims): per factor f, fHOG of the region (w f, h f) resampled to
    model_size = (w, h), flattened."""

class TranslationResponse:
    """A translation filter's response and the confidences of its peak."""
    @property
    def values(self) -> _F32:
        """Score per circular shift (rows x cols); [0, 0] is no motion."""
    @property
    def row_shift(self) -> float: ...
    @property
    def col_shift(self) -> float: ...
    @property
    def peak(self) -> float: ...
    @property
    def psr(self) -> float: ...
    @property
    def apce(self) -> float: ...
    def map(self, centre: tuple[float, float], cell: tuple[float, float],
            region: tuple[int, int, int, int]) -> npt.NDArray[np.float64]:
        """The response at every pixel of region (x0, y0, x1, y1) as the target's centre, for
        a search centred at centre with cells of cell frame pixels (bilinear, wrapping),
        divided by a positive peak, clipped to [0, 1]."""

class Spectrum:
    """A sample as one translation filter takes it (windowed, compressed half spectra)."""
    @property
    def channels(self) -> int: ...
    @property
    def rows(self) -> int: ...
    @property
    def cols(self) -> int: ...

class TranslationFilter:
    """A multi-channel linear correlation filter trained and applied in the Fourier domain."""
    def __init__(self, rows: int, cols: int, channels: int, sigma: float, lam: float,
                 compressed: int = 0) -> None: ...
    def copy(self) -> TranslationFilter:
        """An independent copy (the model as it is now)."""
    @property
    def rows(self) -> int: ...
    @property
    def cols(self) -> int: ...
    @property
    def channels(self) -> int: ...
    @property
    def trained(self) -> bool: ...
    @property
    def window(self) -> _F32: ...
    @property
    def label(self) -> _F32: ...
    def learn(self, features: npt.ArrayLike, rate: float) -> None:
        """Fold in (channels, rows, cols) features (the first call replaces the model)."""
    def respond(self, features: npt.ArrayLike, exclusion: int = 5) -> TranslationResponse:
        """The response to (channels, rows, cols) features (ValueError before learn())."""
    @property
    def filter_channels(self) -> int:
        """Channels of the filter itself (compressed, or channels without a projection)."""
    @property
    def projection(self) -> _F32:
        """(filter_channels, channels); no rows without a projection or before learn()."""
    def sample(self, frame: npt.NDArray[np.uint8], centre: tuple[float, float],
               size: tuple[float, float], out_size: tuple[int, int], cell: int = 4) -> Spectrum:
        """transform(fhog_region(frame, centre, size, out_size, cell)) in one call."""
    def transform(self, features: npt.ArrayLike) -> Spectrum:
        """The sample as this filter takes it (window, projection, half spectra)."""
    def learn_spectrum(self, spectrum: Spectrum, rate: float,
                       shift: tuple[float, float] = (0.0, 0.0)) -> None:
        """Fold in a transformed sample whose target sits shift = (rows, cols) cells from its
        centre (moved so that the target is centred)."""
    def respond_spectrum(self, spectrum: Spectrum, exclusion: int = 5) -> TranslationResponse:
        """respond() to a transformed sample."""

class ScaleResponse:
    """A scale filter's response."""
    @property
    def values(self) -> _F32: ...
    @property
    def best(self) -> int: ...
    @property
    def offset(self) -> float: ...

class ScaleFilter:
    """DSST's 1-D correlation filter over num_scales samples of dims features."""
    def __init__(self, num_scales: int, dims: int, sigma: float, lam: float) -> None: ...
    def copy(self) -> ScaleFilter:
        """An independent copy (the model as it is now)."""
    @property
    def num_scales(self) -> int: ...
    @property
    def dims(self) -> int: ...
    @property
    def trained(self) -> bool: ...
    def learn(self, samples: npt.ArrayLike, rate: float) -> None:
        """Fold in (num_scales, dims) samples (the first call replaces the model)."""
    def respond(self, samples: npt.ArrayLike) -> ScaleResponse:
        """The response to (num_scales, dims) samples (ValueError before learn())."""
    def sample(self, frame: npt.NDArray[np.uint8], centre: tuple[float, float],
               size: tuple[float, float], factors: Sequence[float], model_size: tuple[int, int],
               cell: int = 4) -> Spectrum:
        """scale_samples(...) as this filter takes them, in one call."""
    def learn_spectrum(self, spectrum: Spectrum, rate: float, shift: float = 0.0) -> None:
        """Fold in transformed samples whose target size sits shift samples from the middle."""
    def respond_spectrum(self, spectrum: Spectrum) -> ScaleResponse:
        """respond() to transformed samples."""
