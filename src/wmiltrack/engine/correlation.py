"""A correlation-filter template (translation) and a DSST scale filter on fHOG features.

Two parts a tracker can compose: :class:`CorrelationFilter` says where the target moved
(a multi-channel linear correlation filter over a fixed-size template around it, as Staple
and DSST use) and how sure it is (peak, PSR, APCE); :class:`ScaleFilter` says by which
factor its size changed (a 1-D filter over a pyramid of scale samples, DSST). Both learn at
their own rate when the caller says so; neither decides when. The pixel, FFT and filter
work runs in the compiled core (``_core.fhog_region``, ``_core.TranslationFilter``,
``_core.scale_samples``, ``_core.ScaleFilter``).

Coordinates are those of boxes: pixel ``(row, col)`` covers ``[col, col + 1) x [row, row + 1)``,
so the centre of a box ``(x, y, w, h)`` is ``(x + w / 2, y + h / 2)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Generic, Protocol, TypeVar

import numpy as np
import numpy.typing as npt

from .. import _core
from .frames import as_frame
from .settings import is_int, need

__all__ = [
    "CorrelationFilter",
    "CorrelationSettings",
    "FilterLearning",
    "FilterSchedule",
    "Location",
    "NO_GATE",
    "ScaleEstimate",
    "ScaleFilter",
    "ScaleFilterSettings",
    "smooth_size",
    "SparseUpdates",
]


class FilterSchedule(Protocol):
    """The settings a :class:`FilterLearning` is made from: the template's
    (:class:`~wmiltrack.engine.template.TemplateSettings`), or the scale estimator's
    (:class:`~wmiltrack.engine.scale.ScaleSettings`), which share them."""

    @property
    def template_every(self) -> int: ...

    @property
    def template_gate(self) -> float: ...

    @property
    def template_reuse(self) -> bool: ...


@dataclass(frozen=True)
class FilterLearning:
    """When the correlation filters learn, the one rule the translation template
    (:class:`~wmiltrack.engine.template.CorrelationTemplate`) and the DSST scale filters
    (:class:`~wmiltrack.engine.scale.DSSTScale`, the Haar scale search's vote) share: every
    ``every``-th frame, among frames whose reported score is at least ``above``; with
    ``reuse``, from the sample the frame's search already took. Made from the template's
    settings by :meth:`of` (``template_every``, ``template_gate``, ``template_reuse``)."""

    every: int = 1
    above: float = 0.0
    reuse: bool = False

    @classmethod
    def of(cls, template: FilterSchedule) -> FilterLearning:
        """The rule that the ``template_*`` settings give (the template's, or those the
        scale settings share)."""
        return cls(every=template.template_every, above=template.template_gate,
                   reuse=template.template_reuse)


#: The filters' learning rule of the default settings: every frame, whatever its score.
NO_GATE = FilterLearning()


Box = tuple[float, float, float, float]


def smooth_size(n: int) -> int:
    """The 2-, 3- and 5-smooth number nearest ``n`` (>= 1), the larger one on a tie.

    Template grids get such sizes so that their FFTs split into small radices.
    """
    if n < 1:
        raise ValueError(f"n must be >= 1, got {n}")

    def smooth(m: int) -> bool:
        for p in (2, 3, 5):
            while m % p == 0:
                m //= p
        return m == 1

    for d in range(n):
        if smooth(n + d):
            return n + d
        if n - d >= 1 and smooth(n - d):
            return n - d
    return n  # pragma: no cover - 1 is smooth


class SparseUpdates:
    """Learning every ``every``-th frame (ECO's sparse updates: each learning step of a filter
    costs a feature extraction and a transform per channel) at a rate raised to
    ``1 - (1 - rate) ** every``, so that the model keeps the same memory as learning every
    frame at ``rate``."""

    def __init__(self, rate: float, every: int) -> None:
        self.every = every
        self.rate = 1.0 - (1.0 - rate) ** every
        self._count = 0

    def due(self) -> bool:
        """Whether this frame's learning step is one to take (counts the call)."""
        self._count += 1
        if self._count >= self.every:
            self._count = 0
            return True
        return False


def _check_box(box: Any) -> Box:
    try:
        x, y, w, h = (float(v) for v in box)
    except (TypeError, ValueError):
        raise TypeError(f"box must be four numbers (x, y, w, h), got {box!r}") from None
    need(all(math.isfinite(v) for v in (x, y, w, h)), f"box must be finite, got {box!r}")
    need(w > 0 and h > 0, f"box must have a positive width and height, got {box!r}")
    return x, y, w, h


def _check_point(name: str, value: Any) -> tuple[float, float]:
    try:
        a, b = (float(v) for v in value)
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be two numbers, got {value!r}") from None
    need(math.isfinite(a) and math.isfinite(b), f"{name} must be finite, got {value!r}")
    return a, b


def _check_target(centre: Any, size: Any) -> tuple[tuple[float, float], tuple[float, float]]:
    """``centre`` and ``size`` as checked pairs (a positive size)."""
    c = _check_point("centre", centre)
    sz = _check_point("size", size)
    need(sz[0] > 0 and sz[1] > 0, f"size must be positive, got {size!r}")
    return c, sz


def _check_rate(rate: float) -> float:
    need(isinstance(rate, (int, float)) and not isinstance(rate, bool) and 0.0 < float(rate) <= 1.0,
         f"rate must be in (0, 1], got {rate!r}")
    return float(rate)


@dataclass(frozen=True)
class CorrelationSettings:
    """Settings of the translation filter (defaults: Staple's ``params.txt``).

    Attributes
    ----------
    cell : int
        fHOG cell size in template pixels.
    template_area : float
        Pixels of the template the search region is resampled to (150**2).
    padding : float
        The search region is the target plus ``padding * (w + h) / 2`` in each dimension.
    sigma_factor : float
        The Gaussian label's sigma is ``sqrt(w h) * sigma_factor`` template pixels.
    lam : float
        Regularisation added to the filter's denominator.
    learning_rate : float
        Default rate of :meth:`CorrelationFilter.learn`.
    exclusion : int
        Half-width (cells) of the window around the peak that PSR leaves out.
    compressed : int
        Channels the 31 fHOG channels are projected onto (ECO: the principal axes of the
        first sample's features, fixed from then on); 0 keeps all of them.
    """

    cell: int = 4
    template_area: float = 150.0**2
    padding: float = 2.0
    sigma_factor: float = 1.0 / 16.0
    lam: float = 1e-3
    learning_rate: float = 0.01
    exclusion: int = 5
    compressed: int = 0

    def __post_init__(self) -> None:
        """Check every value (ValueError naming the setting)."""
        need(is_int(self.cell) and 1 <= self.cell <= 16, f"cell must be an int in 1..16, got {self.cell!r}")
        need(is_int(self.exclusion) and self.exclusion >= 0,
             f"exclusion must be an int >= 0, got {self.exclusion!r}")
        need(is_int(self.compressed) and 0 <= self.compressed <= _core.FHOG_CHANNELS,
             f"compressed must be an int in 0..{_core.FHOG_CHANNELS}, got {self.compressed!r}")
        need(math.isfinite(self.template_area) and self.template_area >= (4 * self.cell) ** 2,
             f"template_area must be at least (4 cell)**2 = {(4 * self.cell) ** 2}, "
             f"got {self.template_area!r}")
        need(math.isfinite(self.padding) and self.padding >= 0.0,
             f"padding must be >= 0, got {self.padding!r}")
        need(math.isfinite(self.sigma_factor) and self.sigma_factor > 0.0,
             f"sigma_factor must be > 0, got {self.sigma_factor!r}")
        need(math.isfinite(self.lam) and self.lam >= 0.0, f"lam must be >= 0, got {self.lam!r}")
        need(0.0 < self.learning_rate <= 1.0, f"learning_rate must be in (0, 1], got {self.learning_rate!r}")


@dataclass(frozen=True)
class ScaleFilterSettings:
    """Settings of the DSST scale filter (defaults: DSST's and Staple's).

    Attributes
    ----------
    num_scales : int
        Scale samples, odd; the middle one is the current size.
    step : float
        Ratio of neighbouring samples' sizes.
    sigma_factor : float
        The label's sigma is ``sqrt(num_scales) * sigma_factor`` samples.
    lam : float
        Regularisation added to the filter's denominator.
    learning_rate : float
        Default rate of :meth:`ScaleFilter.learn`.
    max_area : float
        Each scale sample is resampled to at most this many pixels (the target's aspect).
    cell : int
        fHOG cell size of the scale samples.
    """

    num_scales: int = 33
    step: float = 1.02
    sigma_factor: float = 0.25
    lam: float = 1e-3
    learning_rate: float = 0.025
    max_area: float = 512.0
    cell: int = 4

    def __post_init__(self) -> None:
        """Check every value (ValueError naming the setting)."""
        need(is_int(self.num_scales) and self.num_scales >= 3 and self.num_scales % 2 == 1,
             f"num_scales must be an odd int >= 3, got {self.num_scales!r}")
        need(math.isfinite(self.step) and self.step > 1.0, f"step must be > 1, got {self.step!r}")
        need(math.isfinite(self.sigma_factor) and self.sigma_factor > 0.0,
             f"sigma_factor must be > 0, got {self.sigma_factor!r}")
        need(math.isfinite(self.lam) and self.lam >= 0.0, f"lam must be >= 0, got {self.lam!r}")
        need(0.0 < self.learning_rate <= 1.0, f"learning_rate must be in (0, 1], got {self.learning_rate!r}")
        need(is_int(self.cell) and 1 <= self.cell <= 16, f"cell must be an int in 1..16, got {self.cell!r}")
        need(math.isfinite(self.max_area) and self.max_area >= self.cell**2,
             f"max_area must be at least cell**2, got {self.max_area!r}")

    @classmethod
    def spanning(cls, num_scales: int, learning_rate: float = 0.025) -> ScaleFilterSettings:
        """Settings with ``num_scales`` samples over DSST's range (33 samples 1.02 apart:
        sizes 1.02**-16 .. 1.02**16) and a label as wide in log-size as DSST's, so that
        fewer samples (fDSST's 17) cost less and answer about the same."""
        need(is_int(num_scales) and num_scales >= 3 and num_scales % 2 == 1,
             f"num_scales must be an odd int >= 3, got {num_scales!r}")
        base = cls(learning_rate=learning_rate)
        if num_scales == base.num_scales:
            return base
        ratio = (base.num_scales - 1) / (num_scales - 1)  # DSST's steps per new step
        sigma = math.sqrt(base.num_scales) * base.sigma_factor / ratio  # in new samples
        return cls(num_scales=num_scales, step=base.step**ratio,
                   sigma_factor=sigma / math.sqrt(num_scales), learning_rate=learning_rate)


@dataclass(frozen=True)
class Location:
    """Where the translation filter puts the target, relative to the centre it searched at.

    ``dx``, ``dy``: the target's shift in frame pixels; ``peak``, ``psr``, ``apce``: the
    response's maximum, peak-to-sidelobe ratio and average peak-to-correlation energy (higher
    is surer); ``response``: the response per circular shift of the template grid, entry
    ``[r, c]`` for a shift of ``(c * cell[0], r * cell[1])`` frame pixels (``r``, ``c`` modulo
    the grid's rows and columns), so another cue can read the filter's score of any
    candidate centre (:meth:`map`); ``centre``: the centre searched at.
    """

    dx: float
    dy: float
    peak: float
    psr: float
    apce: float
    response: npt.NDArray[np.float32]
    cell: tuple[float, float]
    centre: tuple[float, float]
    raw: _core.TranslationResponse = field(repr=False, compare=False)

    def map(self, region: tuple[int, int, int, int]) -> npt.NDArray[np.float64]:
        """The response at every pixel of ``region = (x0, y0, x1, y1)`` taken as the target's
        centre (bilinear between cells, wrapping around), divided by the peak and clipped to
        [0, 1]: a cue's map over the region."""
        return self.raw.map(self.centre, self.cell, region)


@dataclass(frozen=True)
class _Sample:
    """A filter's last transformed sample (a search's or an estimate's) and where it was taken,
    for the filter's learning step on the same frame to reuse instead of sampling again."""

    frame: Any
    centre: tuple[float, float]
    size: tuple[float, float]
    spectrum: _core.Spectrum


@dataclass(frozen=True)
class ScaleEstimate:
    """The scale filter's answer: multiply the target's size by ``factor``; ``response`` is
    the score per scale sample (``factors`` of :class:`ScaleFilter`)."""

    factor: float
    response: npt.NDArray[np.float32]


_CoreFilter = TypeVar("_CoreFilter", _core.TranslationFilter, _core.ScaleFilter)


class _Trained(Generic[_CoreFilter]):
    """What both filters share: the compiled filter, made by ``init``."""

    _filter: _CoreFilter | None = None

    def _require(self) -> _CoreFilter:
        if self._filter is None:
            raise RuntimeError("call init() first")
        return self._filter

    def _filter_copy(self) -> _CoreFilter | None:
        return None if self._filter is None else self._filter.copy()


class CorrelationFilter(_Trained[_core.TranslationFilter]):
    """A translation correlation filter on fHOG over a fixed-size template (Staple/DSST).

    :meth:`init` fixes the template: the search region (the target plus padding) is mapped to
    about ``template_area`` pixels, i.e. a grid of cells whose sides are 2-, 3- and 5-smooth.
    The region follows the target's size (``size`` of :meth:`locate` and :meth:`learn`), the
    grid does not, so the cost per frame is the same for every target.
    """

    def __init__(self, settings: CorrelationSettings | None = None) -> None:
        """A filter with these settings (defaults if None); call :meth:`init` before use."""
        self.settings = settings if settings is not None else CorrelationSettings()
        self._filter = None
        self._base_size = (0.0, 0.0)  # the target's size at init
        self._base_region = (0.0, 0.0)  # the search region's size at init (frame pixels)
        self._out_size = (0, 0)  # template pixels (w, h)
        self._size = (0.0, 0.0)  # the size last learnt
        self._searched: _Sample | None = None
        self.reused = 0  # learning steps that reused their frame's search sample

    @property
    def initialised(self) -> bool:
        """Whether :meth:`init` ran."""
        return self._filter is not None

    @property
    def grid(self) -> tuple[int, int]:
        """Template cells ``(rows, cols)``."""
        f = self._require()
        return f.rows, f.cols

    @property
    def size(self) -> tuple[float, float]:
        """The target's size ``(w, h)`` last learnt (the default of :meth:`locate`)."""
        return self._size

    def copy(self) -> CorrelationFilter:
        """An independent copy (template geometry and model as they are now), e.g. to keep
        the last model a tracker trusted."""
        out = CorrelationFilter(self.settings)
        out._filter = self._filter_copy()
        out._base_size, out._base_region = self._base_size, self._base_region
        out._out_size, out._size = self._out_size, self._size
        return out

    def init(self, frame: Any, box: Any) -> None:
        """Fix the template for a target ``box = (x, y, w, h)`` and learn it (rate 1)."""
        frame = as_frame(frame)
        x, y, w, h = _check_box(box)
        s = self.settings
        extra = s.padding * (w + h) / 2.0
        rw, rh = w + extra, h + extra
        resize = math.sqrt(s.template_area / (rw * rh))
        cols = smooth_size(max(4, round(rw * resize / s.cell)))
        rows = smooth_size(max(4, round(rh * resize / s.cell)))
        # The region maps onto the grid exactly; its aspect moves by the rounding only.
        self._out_size = (cols * s.cell, rows * s.cell)
        self._base_region = (cols * s.cell / resize, rows * s.cell / resize)
        self._base_size = (w, h)
        sigma = math.sqrt(w * h) * resize * s.sigma_factor / s.cell
        self._filter = _core.TranslationFilter(rows, cols, _core.FHOG_CHANNELS, sigma, s.lam,
                                               s.compressed)
        self._searched = None
        self.learn(frame, (x, y, w, h), 1.0)

    def _region(self, size: tuple[float, float]) -> tuple[float, float]:
        scale = math.sqrt(size[0] * size[1] / (self._base_size[0] * self._base_size[1]))
        return self._base_region[0] * scale, self._base_region[1] * scale

    def _features(self, frame: np.ndarray, centre: tuple[float, float],
                  size: tuple[float, float]) -> npt.NDArray[np.float32]:
        return _core.fhog_region(frame, centre, self._region(size), self._out_size,
                                 self.settings.cell)

    def locate(self, frame: Any, centre: Any, size: Any = None) -> Location:
        """Search the region around ``centre = (cx, cy)`` for a target of ``size = (w, h)``
        (default: the size last learnt); returns its shift in frame pixels and the
        confidences."""
        f = self._require()
        given = frame
        frame = as_frame(frame)
        c, sz = _check_target(centre, self._size if size is None else size)
        region = self._region(sz)
        spectrum = f.sample(frame, c, region, self._out_size, self.settings.cell)
        r = f.respond_spectrum(spectrum, self.settings.exclusion)
        cell_w = region[0] / f.cols  # frame pixels per cell
        cell_h = region[1] / f.rows
        loc = Location(dx=r.col_shift * cell_w, dy=r.row_shift * cell_h, peak=r.peak,
                       psr=r.psr, apce=r.apce, response=r.values, cell=(cell_w, cell_h),
                       centre=c, raw=r)
        self._searched = _Sample(given, c, sz, spectrum)
        return loc

    def recall(self, other: CorrelationFilter) -> tuple[float, float]:
        """This filter's response peak and PSR on the sample that ``other``'s last
        :meth:`locate` took (before ``other`` learnt from it), e.g. a copy kept from the first
        frame judging where the live filter searched: a filter that never learnt since does
        not follow the live one onto a distractor. Both filters must share their template
        (one a :meth:`copy` of the other); NaN when ``other`` has no search sample."""
        f = self._require()
        searched = other._searched
        if searched is None:
            return math.nan, math.nan
        r = f.respond_spectrum(searched.spectrum, self.settings.exclusion)
        return float(r.peak), float(r.psr)

    def learn(self, frame: Any, box: Any, rate: float | None = None, *,
              from_search: bool = False) -> None:
        """Fold in the template around ``box`` at ``rate`` (default: the settings').

        With ``from_search``, the sample of the last :meth:`locate` on this same frame is
        moved to ``box`` and learnt instead of a new one (ECO), when ``box``'s centre is
        within a quarter of the grid of the searched centre and its area within 10% of the
        searched size's; otherwise a new sample is taken."""
        f = self._require()
        searched, self._searched = self._searched, None
        x, y, w, h = _check_box(box)
        r = self.settings.learning_rate if rate is None else _check_rate(rate)
        if from_search and searched is not None and searched.frame is frame:
            region = self._region(searched.size)  # frame pixels per cell: region / grid
            col = (x + w / 2.0 - searched.centre[0]) / (region[0] / f.cols)
            row = (y + h / 2.0 - searched.centre[1]) / (region[1] / f.rows)
            ratio = w * h / (searched.size[0] * searched.size[1])
            if abs(col) <= f.cols / 4 and abs(row) <= f.rows / 4 and 1 / 1.1 <= ratio <= 1.1:
                f.learn_spectrum(searched.spectrum, r, (row, col))
                self._size = (w, h)
                self.reused += 1
                return
        frame = as_frame(frame)
        f.learn(self._features(frame, (x + w / 2.0, y + h / 2.0), (w, h)), r)
        self._size = (w, h)


class ScaleFilter(_Trained[_core.ScaleFilter]):
    """DSST's scale filter: fHOG of ``num_scales`` resampled regions around the target, sizes
    ``step**k`` times its size (``k`` from ``-(n-1)/2`` to ``(n-1)/2``), each resampled to
    the same at most ``max_area`` pixels, and a 1-D correlation filter along the scales."""

    def __init__(self, settings: ScaleFilterSettings | None = None) -> None:
        """An estimator with these settings (defaults if None); call :meth:`init` first."""
        self.settings = settings if settings is not None else ScaleFilterSettings()
        s = self.settings
        half = (s.num_scales - 1) // 2
        self.factors: tuple[float, ...] = tuple(s.step ** (k - half) for k in range(s.num_scales))
        self._filter = None
        self._model_size = (0, 0)
        self._estimated: _Sample | None = None

    def copy(self) -> ScaleFilter:
        """An independent copy (sample size and model as they are now)."""
        out = ScaleFilter(self.settings)
        out._filter = self._filter_copy()
        out._model_size = self._model_size
        return out

    def init(self, frame: Any, box: Any) -> None:
        """Fix the sample size for a target ``box = (x, y, w, h)`` and learn it (rate 1)."""
        frame = as_frame(frame)
        x, y, w, h = _check_box(box)
        s = self.settings
        shrink = min(1.0, math.sqrt(s.max_area / (w * h)))
        self._model_size = (max(s.cell, math.floor(w * shrink)), max(s.cell, math.floor(h * shrink)))
        dims = _core.FHOG_CHANNELS * (self._model_size[0] // s.cell) * (self._model_size[1] // s.cell)
        sigma = math.sqrt(s.num_scales) * s.sigma_factor
        self._filter = _core.ScaleFilter(s.num_scales, dims, sigma, s.lam)
        self.learn(frame, (x + w / 2.0, y + h / 2.0), (w, h), 1.0)

    def _samples(self, frame: np.ndarray, centre: tuple[float, float],
                 size: tuple[float, float]) -> npt.NDArray[np.float32]:
        return _core.scale_samples(frame, centre, size, list(self.factors), self._model_size,
                                   self.settings.cell)

    def estimate(self, frame: Any, centre: Any, size: Any) -> ScaleEstimate:
        """By which factor the target of ``size = (w, h)`` at ``centre`` changed size (the
        best sample, refined by a parabola through its neighbours)."""
        f = self._require()
        given = frame
        c, sz = _check_target(centre, size)
        spectrum = f.sample(as_frame(frame), c, sz, list(self.factors), self._model_size,
                            self.settings.cell)
        r = f.respond_spectrum(spectrum)
        self._estimated = _Sample(given, c, sz, spectrum)
        half = (self.settings.num_scales - 1) // 2
        factor = self.settings.step ** (r.best + r.offset - half)
        return ScaleEstimate(factor=float(factor), response=r.values)

    def learn(self, frame: Any, centre: Any, size: Any, rate: float | None = None, *,
              from_estimate: bool = False) -> None:
        """Fold in the scale samples around ``centre`` for a target of ``size`` at ``rate``
        (default: the settings').

        With ``from_estimate``, the samples of the last :meth:`estimate` on this same frame
        and centre are learnt with their label moved to ``size`` instead of new ones, when
        ``size`` lies within the samples' scales; otherwise new samples are taken."""
        f = self._require()
        r = self.settings.learning_rate if rate is None else _check_rate(rate)
        estimated, self._estimated = self._estimated, None
        c, sz = _check_target(centre, size)
        if from_estimate and estimated is not None and estimated.frame is frame:
            ec, esz = estimated.centre, estimated.size
            shift = 0.5 * math.log(sz[0] * sz[1] / (esz[0] * esz[1])) / math.log(self.settings.step)
            half = (self.settings.num_scales - 1) // 2
            if abs(c[0] - ec[0]) < 0.5 and abs(c[1] - ec[1]) < 0.5 and abs(shift) <= half:
                f.learn_spectrum(estimated.spectrum, r, shift)
                return
        f.learn(self._samples(as_frame(frame), c, sz), r)
