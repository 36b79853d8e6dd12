"""The settings of each part of a tracker: one small frozen dataclass per part, each checking
its own values.

A tracker is made of parts (:mod:`~wmiltrack.engine.appearance`, :mod:`~wmiltrack.engine.cues`,
:mod:`~wmiltrack.engine.scale`, :mod:`~wmiltrack.engine.motion`,
:mod:`~wmiltrack.engine.policy`); each reads only its own settings class below.
:class:`~wmiltrack.Params`, the public face, is all of them at once (it inherits every class
here), so ``Tracker("fct", num_features=200)`` and ``--set key=value`` keep one flat namespace
while every setting is documented and checked in exactly one place: the class that owns it.

Every default is rcwmil's (the paper's tracker); a part whose defaults leave it off (scale,
motion, colour, the reported score's contrasts) is not built at all, so the paper presets run
the paper's code path.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, Literal, TypeVar

from ..networks.backends import RUNTIMES
from ..networks.families import siamese_networks

__all__ = ["AppearanceSettings", "BagSettings", "ClassifierSettings", "ColourSettings", "FeatureSettings",
           "FilterLearning", "JudgeSettings", "NO_GATE", "RecoverySettings", "own",
           "MotionSettings", "ScaleSettings", "ScoreSettings", "SearchSettings",
           "TemplateSettings", "CONFIDENCE_OFFSET", "CHANNELS", "MAX_NEG_RADIUS", "MAX_POS_RADIUS",
           "MAX_SEARCH_RADIUS"]

MAX_POS_RADIUS = 100
"""Largest positive-bag radius (``pos_radius``, ``init_pos_radius``): ~31 000 positives."""
MAX_NEG_RADIUS = 500
"""Largest outer negative radius (``neg_outer``, ``init_neg_outer``)."""
MAX_SEARCH_RADIUS = 1000
"""Largest search radius (``coarse_radius``, ``fine_radius``)."""

#: Default of ``confidence_offset``: the mean weak-classifier log ratio at which a frame is as
#: likely tracked (IoU > 0) as lost. A class-balanced logistic fit of "IoU > 0" on the mean log
#: ratio over 17 OTB sequences and 6 generated full-occlusion/vanishing sequences gave offsets
#: 1.25-1.63 and gains 0.8-1.1 for five variants (``scripts/score_study.py``).
CONFIDENCE_OFFSET = 1.4

#: The image channels a feature may read (``FeatureSettings.channels``).
CHANNELS = ("luma", "grad", "opp_rg", "opp_yb")


_S = TypeVar("_S")


def own(cls: type[_S], params: Any) -> _S:
    """The settings of one part: a ``cls`` (a settings class below) holding ``params``'s values
    of ``cls``'s fields and nothing else. :func:`~wmiltrack.engine.tracker.compose` builds each
    part with its own, so a part cannot read another part's settings."""
    return cls(**{f.name: getattr(params, f.name) for f in dataclasses.fields(cls)})  # type: ignore[arg-type]


def _need(ok: bool, message: str) -> None:
    if not ok:
        raise ValueError(message)


def _check_memory(obj: Any) -> None:
    """``recover_memory``, which the judge's and the recovery's settings share, checked."""
    _check_numbers(obj, "recover_memory")
    _need(0.0 <= obj.recover_memory < 1.0,
          f"recover_memory must be in [0, 1), got {obj.recover_memory}")


def _check_colour_model(obj: Any) -> None:
    """``colour_learning_rate`` and ``colour_sample``, which the colour cue's and the reported
    score's settings share, checked."""
    _check_numbers(obj, "colour_learning_rate")
    _need(0.0 < obj.colour_learning_rate <= 1.0,
          f"colour_learning_rate must be in (0, 1], got {obj.colour_learning_rate!r}")
    _need(_is_int(obj.colour_sample) and obj.colour_sample >= 0,
          f"colour_sample must be an integer >= 0, got {obj.colour_sample!r}")


def _is_int(v: Any) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


def _is_number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def _check_choices(obj: Any, choices: dict[str, tuple[str, ...]]) -> None:
    for name, allowed in choices.items():
        value = getattr(obj, name)
        _need(value in allowed, f"{name} must be one of {', '.join(map(repr, allowed))}; got {value!r}")


def _check_ints(obj: Any, *names: str) -> None:
    for name in names:
        _need(_is_int(getattr(obj, name)), f"{name} must be an int, got {getattr(obj, name)!r}")


def _check_numbers(obj: Any, *names: str) -> None:
    for name in names:
        v = getattr(obj, name)
        _need(_is_number(v), f"{name} must be a finite number, got {v!r}")


@dataclass(frozen=True)
class FeatureSettings:
    """The Haar-like feature bank and its classifier's size (the appearance model).

    Attributes
    ----------
    feature_kind : {"subregion", "random"}
        ``subregion``: rectangles drawn inside a grid of sub-regions of the box with size
        limits (rcwmil, OSIL). ``random``: rectangles anywhere in the box (CT, FCT, MIL, WMIL).
    num_features : int
        M, the size of the feature pool.
    num_selected : int
        K, how many features the strong classifier uses (== M when ``selection="none"``).
    rects_min, rects_max : int
        Rectangles per feature, drawn uniformly in ``rects_min..rects_max`` (inclusive).
    num_subregions : int
        Sub-regions for ``subregion`` features: 4 = 2x2 grid (``subregion_mode="grid"``).
    subregion_mode : {"grid", "random"}
        ``grid``: quadrant ``i mod 4`` for feature i; ``random``: a W/2 x H/2 window at a
        random place per feature (spec section 8 #3).
    positive_prob : float
        Probability of a +1 entry of the measurement matrix (0.78; -1 otherwise).
    rect_min_size : int
        Smallest rectangle side in pixels (w_min = h_min = 2).
    beta_min, beta_max : float
        Rectangle side limits as fractions of the sub-region side (0.2, 0.8).
    rect_bounds : tuple of 4 int
        For ``random`` features: ``(x_lo, x_hi_off, w_lo, w_end_off)``: a rectangle's x is
        drawn in ``x_lo .. W - x_hi_off`` and its width in ``w_lo .. W - x - w_end_off``
        (same for y and h), matching each reference implementation's ranges.
    weight_mode : {"sign", "sign_sqrt", "uniform"}
        Rectangle weights of ``random`` features: fair +-1, +-1/sqrt(#rects) (CT), U[-1, 1].
    area_normalize : bool
        Divide each rectangle's sum by its area (FCT eq. 8; rcwmil) or use raw sums.
    min_box_size : int
        Smallest box side accepted (after clipping to the frame).
    channels : tuple of str
        Image channels the features are drawn on, each feature on one: any of ``"luma"``,
        ``"grad"`` (gradient magnitude), ``"opp_rg"``, ``"opp_yb"`` (colour opponents; they
        drop out for gray frames). Empty (the paper): luma only, one integral image.
    """

    feature_kind: Literal["subregion", "random"] = "subregion"
    num_features: int = 100
    num_selected: int = 20
    rects_min: int = 2
    rects_max: int = 4
    num_subregions: int = 4
    subregion_mode: Literal["grid", "random"] = "grid"
    positive_prob: float = 0.78
    rect_min_size: int = 2
    beta_min: float = 0.2
    beta_max: float = 0.8
    rect_bounds: tuple[int, int, int, int] = (1, 6, 2, 3)
    weight_mode: Literal["sign", "sign_sqrt", "uniform"] = "sign"
    area_normalize: bool = True
    min_box_size: int = 4
    channels: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        FeatureSettings.check(self)

    def check(self) -> None:
        """``ValueError`` naming the first setting out of range."""
        _check_choices(self, {"feature_kind": ("subregion", "random"),
                              "subregion_mode": ("grid", "random"),
                              "weight_mode": ("sign", "sign_sqrt", "uniform")})
        _check_ints(self, "num_features", "num_selected", "rects_min", "rects_max",
                    "num_subregions", "rect_min_size", "min_box_size")
        _need(self.num_features >= 1, f"num_features must be >= 1, got {self.num_features}")
        _need(1 <= self.num_selected <= self.num_features,
              f"num_selected (K) must be in 1..num_features ({self.num_features}), got {self.num_selected}")
        _need(1 <= self.rects_min <= self.rects_max,
              f"need 1 <= rects_min <= rects_max, got {self.rects_min}, {self.rects_max}")
        _need(self.num_subregions in (1, 4, 9, 16) if self.subregion_mode == "grid"
              else self.num_subregions >= 1,
              f"num_subregions for a grid must be a square (1, 4, 9, 16), got {self.num_subregions}")
        _need(0.0 <= self.positive_prob <= 1.0,
              f"positive_prob must be in [0, 1], got {self.positive_prob}")
        _need(self.rect_min_size >= 1, f"rect_min_size must be >= 1, got {self.rect_min_size}")
        _need(0.0 < self.beta_min <= self.beta_max <= 1.0,
              f"need 0 < beta_min <= beta_max <= 1, got {self.beta_min}, {self.beta_max}")
        _need(len(self.rect_bounds) == 4 and all(_is_int(v) and v >= 0 for v in self.rect_bounds),
              f"rect_bounds must be four ints >= 0, got {self.rect_bounds}")
        _need(self.rect_bounds[2] >= 1, "rect_bounds[2] (smallest rectangle side) must be >= 1")
        # A rectangle starts at most rect_bounds[1] pixels before the box's far edge and is at
        # least rect_bounds[2] wide: it only stays inside the box if the latter fits.
        _need(self.rect_bounds[2] <= self.rect_bounds[1],
              f"rect_bounds[2] (smallest rectangle side, {self.rect_bounds[2]}) must be <= "
              f"rect_bounds[1] (room left after a rectangle's start, {self.rect_bounds[1]})")
        _need(self.min_box_size >= 2, f"min_box_size must be >= 2, got {self.min_box_size}")
        _need(isinstance(self.channels, tuple) and all(c in CHANNELS for c in self.channels)
              and len(set(self.channels)) == len(self.channels),
              f"channels must be a tuple of distinct names from {', '.join(CHANNELS)}; "
              f"got {self.channels!r}")
        _need(self.channels == () or any(c not in ("opp_rg", "opp_yb") for c in self.channels),
              "channels needs a gray channel: luma or grad (the colour channels drop out for "
              "gray frames)")


@dataclass(frozen=True)
class BagSettings:
    """Where the positive and negative bags are sampled around the box (spec section 0).

    Attributes
    ----------
    pos_radius : float
        alpha: positives are every offset with d < alpha (45 for 4).
    neg_inner, neg_outer : float
        zeta, beta: negatives come from the annulus zeta <= d < beta.
    neg_count : int
        Number of negatives (exact draw without replacement, or the Bernoulli maximum).
    neg_sampling : {"exact", "bernoulli"}
        ``exact``: exactly ``neg_count`` distinct offsets; ``bernoulli``: the references'
        thinning with keep probability ``neg_count / (2 floor(beta) + 1)^2``, truncated.
    init_pos_radius, init_neg_inner, init_neg_outer, init_neg_count : float or None
        The first frame's bags when they differ from tracking (MIL, WMIL); ``None`` = same.
    """

    pos_radius: float = 4.0
    neg_inner: float = 8.0
    neg_outer: float = 22.0
    neg_count: int = 50
    neg_sampling: Literal["exact", "bernoulli"] = "exact"
    init_pos_radius: float | None = None
    init_neg_inner: float | None = None
    init_neg_outer: float | None = None
    init_neg_count: int | None = None

    def __post_init__(self) -> None:
        BagSettings.check(self)

    def check(self) -> None:
        """``ValueError`` naming the first setting out of range."""
        _check_choices(self, {"neg_sampling": ("exact", "bernoulli")})
        _check_ints(self, "neg_count")
        _check_numbers(self, "pos_radius", "neg_inner", "neg_outer")
        _need(self.pos_radius > 0, f"pos_radius must be > 0, got {self.pos_radius}")
        _need(0 <= self.neg_inner < self.neg_outer,
              f"need 0 <= neg_inner < neg_outer, got {self.neg_inner}, {self.neg_outer}")
        _need(self.neg_count >= 0, f"neg_count must be >= 0, got {self.neg_count}")
        for name in ("init_pos_radius", "init_neg_inner", "init_neg_outer"):
            v = getattr(self, name)
            _need(v is None or _is_number(v), f"{name} must be None or a finite number, got {v!r}")
        if self.init_pos_radius is not None:
            _need(self.init_pos_radius > 0, "init_pos_radius must be > 0")
        # Upper limits keep the enumerated offsets (and the memory they take) bounded.
        for name in ("pos_radius", "init_pos_radius"):
            v = getattr(self, name)
            _need(v is None or v <= MAX_POS_RADIUS, f"{name} must be <= {MAX_POS_RADIUS}, got {v}")
        for name in ("neg_outer", "init_neg_outer"):
            v = getattr(self, name)
            _need(v is None or v <= MAX_NEG_RADIUS, f"{name} must be <= {MAX_NEG_RADIUS}, got {v}")
        inner = self.neg_inner if self.init_neg_inner is None else self.init_neg_inner
        outer = self.neg_outer if self.init_neg_outer is None else self.init_neg_outer
        _need(0 <= inner < outer, f"need 0 <= init_neg_inner < init_neg_outer, got {inner}, {outer}")
        if self.init_neg_count is not None:
            _need(_is_int(self.init_neg_count) and self.init_neg_count >= 0,
                  "init_neg_count must be an int >= 0")


@dataclass(frozen=True)
class ClassifierSettings:
    """The online Gaussian weak classifiers and how the strong classifier's features are chosen.

    Attributes
    ----------
    learning_rate : float
        lambda in [0, 1): weight of the old model in the Gaussian update.
    classifier : {"gaussian", "mil"}
        ``gaussian``: std-based update of CT/FCT/WMIL (spec 1.1); ``mil``: MILTrack's
        variance-based update (spec 1.2).
    first_update : {"direct", "blend"}
        ``direct``: the first frame sets mu and sigma from the samples; ``blend``: the
        references' quirk of blending them into (0, 1).
    sigma_floor : float
        Lower bound of every sigma.
    guard : float
        The epsilon added to each likelihood before the log (1e-30 CT family, 1e-5 MIL).
    selection : {"wmil", "milboost", "none"}
        Weighted-MIL gradient selection, MILBoost's Noisy-OR likelihood selection, or all
        features (CT, FCT; then ``num_selected`` must equal ``num_features``).
    instance_weights : {"exp", "exp_sq", "uniform"}
        Positive-bag weights: exp(-d) normalised (paper), exp(-d^2) unnormalised (WMIL
        reference code), or equal weights (OSIL).
    gradient : {"paper", "code"}
        WMIL selection gradient w s (1 - s) / sum(w s) (paper) or the reference code's
        w s (1 - w s) / sum(w s).
    confidence_offset : float
        Offset of the confidence ``logistic(raw / K - offset)`` (see
        :func:`wmiltrack.engine.policy.confidence`).
    """

    learning_rate: float = 0.9
    classifier: Literal["gaussian", "mil"] = "gaussian"
    first_update: Literal["direct", "blend"] = "direct"
    sigma_floor: float = 1e-6
    guard: float = 1e-30
    selection: Literal["wmil", "milboost", "none"] = "wmil"
    instance_weights: Literal["exp", "exp_sq", "uniform"] = "exp"
    gradient: Literal["paper", "code"] = "paper"
    confidence_offset: float = CONFIDENCE_OFFSET

    def __post_init__(self) -> None:
        ClassifierSettings.check(self)

    def check(self) -> None:
        """``ValueError`` naming the first setting out of range."""
        _check_choices(self, {"classifier": ("gaussian", "mil"), "first_update": ("direct", "blend"),
                              "selection": ("wmil", "milboost", "none"),
                              "instance_weights": ("exp", "exp_sq", "uniform"),
                              "gradient": ("paper", "code")})
        _check_numbers(self, "learning_rate", "sigma_floor", "guard", "confidence_offset")
        _need(0.0 <= self.learning_rate < 1.0,
              f"learning_rate (lambda) must be in [0, 1), got {self.learning_rate}")
        _need(self.sigma_floor > 0, f"sigma_floor must be > 0, got {self.sigma_floor}")
        _need(self.guard > 0, f"guard must be > 0, got {self.guard}")


@dataclass(frozen=True)
class SearchSettings:
    """The translation search: a coarse grid, then an optional fine one around its winner.

    Attributes
    ----------
    coarse_radius, coarse_step : int
        Search grid: offsets (i, j) * step with |offset| < radius.
    fine_radius, fine_step : int
        Second, finer search around the coarse winner (``fine_radius=0``: none).
    """

    coarse_radius: int = 25
    coarse_step: int = 4
    fine_radius: int = 10
    fine_step: int = 1

    def __post_init__(self) -> None:
        SearchSettings.check(self)

    def check(self) -> None:
        """``ValueError`` naming the first setting out of range."""
        _check_ints(self, "coarse_radius", "coarse_step", "fine_radius", "fine_step")
        _need(self.coarse_radius >= 1 and self.coarse_step >= 1,
              f"coarse_radius and coarse_step must be >= 1, got {self.coarse_radius}, {self.coarse_step}")
        _need(self.coarse_radius <= MAX_SEARCH_RADIUS and self.fine_radius <= MAX_SEARCH_RADIUS,
              f"coarse_radius and fine_radius must be <= {MAX_SEARCH_RADIUS}, got "
              f"{self.coarse_radius}, {self.fine_radius}")
        _need(self.fine_radius >= 0 and self.fine_step >= 1,
              f"fine_radius must be >= 0 and fine_step >= 1, got {self.fine_radius}, {self.fine_step}")

    @property
    def stage_reach(self) -> int:
        """Largest distance in pixels that the coarse and fine grids move the box."""
        reach = self.coarse_radius - 1
        if self.fine_radius > 0:
            reach += self.fine_radius - 1
        return reach


@dataclass(frozen=True)
class ScaleSettings:
    """The scale estimator (:mod:`wmiltrack.engine.scale`): Haar rectangles scaled, not the image.

    Attributes
    ----------
    scale_steps : int
        After the translation search, also try the box scaled by ``scale_factor ** j`` for
        ``j = -scale_steps..scale_steps`` (0: no scale estimator; the box keeps its first size).
    scale_factor : float
        Ratio between neighbouring scales (> 1).
    scale_model : {"ratio", "likelihood", "both", "dsst"}
        ``dsst``: a separate 1-D correlation filter along 33 scales 1.02 apart on fHOG
        (DSST; :class:`wmiltrack.engine.scale.DSSTScale`), run after the translation
        search; ``scale_steps`` must be > 0 to switch it on, and the other ``scale_*``
        settings but ``scale_min``/``scale_max`` do not apply. Otherwise scales are compared
        by Haar features: ``ratio``, the strong classifier's mean log ratio (best of a
        ``scale_radius`` translation search at each scale); ``likelihood``, how well all M
        features of the box at each scale fit the target's Gaussians: minus the mean of
        ``log(1 + z^2)`` with ``z = (value - mu1) / sigma1`` (a generative template over the
        whole pool, which the background model cannot bias), with a target model of its
        own updated at ``scale_learning_rate``; ``both``: the sum of the two, the
        likelihood weighted by ``scale_mix`` (the classifier alone favours smaller boxes,
        the likelihood alone larger ones).
    scale_mix : float
        Weight of the likelihood term for ``scale_model="both"``.
    scale_learning_rate : float
        lambda of the ``likelihood`` scale model (slow, as DSST's 0.025 update: 0.975).
    scale_penalty : float
        Subtracted from a scale's mean weak-classifier log ratio per step away from the
        current scale (favours the current scale, as KCF's 0.95 factor does).
    scale_radius : int
        Translation search radius (step 1) at each tried scale other than the current one.
    scale_min, scale_max : float
        Limits of the scale relative to the first box.
    scale_negatives : int
        Also learn, as negatives, the box centred on the target but scaled by
        ``scale_factor ** +-scale_negatives`` (so the classifier learns what a wrong size
        looks like; 0: none).
    scale_contrast : float
        With a colour cue (``colour_weight > 0``) and ``scale_model`` ``"ratio"`` or
        ``"both"``: add this weight times each tried box's colour contrast
        (:func:`wmiltrack.engine.colour.colour_contrast`: the mean ``P(target | colour)``
        inside the box minus that over a ring around it, read from the search's likelihood
        table) to that scale's value (0: off). The classifier prefers smaller boxes and the
        target likelihood larger ones; the contrast is largest for the box that holds the
        target's colours and no more. A contrast changes by about 0.01 between neighbouring
        scales, so a weight of 20 makes it count about as much as one step's
        ``scale_penalty`` (0.2).
    scale_samples : int
        DSST's scale samples (``scale_model="dsst"`` and ``scale_dsst``), odd, always over
        DSST's range of sizes (33 samples 1.02 apart) with a label as wide: fewer cost less
        (fDSST uses 17).
    scale_veto : bool
        With ``scale_model="dsst"`` and a colour cue: the size DSST prefers is taken only if
        its box's colour contrast (as for ``scale_contrast``) is at least the current box's,
        else the size is kept. DSST's fHOG scale samples cannot tell a low-textured or
        deforming target from its surroundings and let the box grow into them (a bag on a
        street: 0.70 -> 0.24 AUC); the colour contrast falls as soon as background enters.
    template_gate, template_every, template_reuse
        Shared with :class:`TemplateSettings`: the DSST scale filters (``scale_model="dsst"``
        and ``scale_dsst``'s vote) learn on the translation filter's schedule.
    min_box_size
        Shared with :class:`FeatureSettings`: DSST gives no box side below it (nor below 4).
    """

    scale_steps: int = 0
    scale_factor: float = 1.03
    scale_model: Literal["ratio", "likelihood", "both", "dsst"] = "ratio"
    scale_learning_rate: float = 0.975
    scale_mix: float = 1.0
    scale_penalty: float = 0.0
    scale_radius: int = 2
    scale_min: float = 0.2
    scale_max: float = 5.0
    scale_negatives: int = 0
    scale_contrast: float = 0.0
    scale_dsst: float = 0.0
    scale_samples: int = 33
    scale_veto: bool = False
    template_gate: float = 0.0
    template_every: int = 1
    template_reuse: bool = False
    min_box_size: int = 4

    def __post_init__(self) -> None:
        ScaleSettings.check(self)

    def check(self) -> None:
        """``ValueError`` naming the first setting out of range."""
        _check_choices(self, {"scale_model": ("ratio", "likelihood", "both", "dsst")})
        _check_ints(self, "scale_steps", "scale_radius", "scale_negatives")
        _check_numbers(self, "scale_factor", "scale_penalty", "scale_min", "scale_max", "scale_mix",
                       "scale_contrast", "scale_dsst")
        _need(self.scale_dsst >= 0, f"scale_dsst must be >= 0, got {self.scale_dsst}")
        _need(_is_int(self.scale_samples) and 3 <= self.scale_samples <= 65
              and self.scale_samples % 2 == 1,
              f"scale_samples must be an odd int in 3..65, got {self.scale_samples!r}")
        _need(isinstance(self.scale_veto, bool),
              f"scale_veto must be True or False, got {self.scale_veto!r}")
        _need(0 <= self.scale_steps <= 10, f"scale_steps must be in 0..10, got {self.scale_steps}")
        _need(_is_number(self.scale_learning_rate) and 0.0 <= self.scale_learning_rate < 1.0,
              f"scale_learning_rate must be in [0, 1), got {self.scale_learning_rate}")
        _need(0 <= self.scale_negatives <= 20,
              f"scale_negatives must be in 0..20, got {self.scale_negatives}")
        _need(self.scale_negatives == 0 or self.scale_steps > 0,
              "scale_negatives needs the scale search (scale_steps > 0)")
        _need(1.0 < self.scale_factor <= 2.0, f"scale_factor must be in (1, 2], got {self.scale_factor}")
        _need(self.scale_penalty >= 0, f"scale_penalty must be >= 0, got {self.scale_penalty}")
        _need(self.scale_contrast >= 0, f"scale_contrast must be >= 0, got {self.scale_contrast}")
        _need(1 <= self.scale_radius <= 50, f"scale_radius must be in 1..50, got {self.scale_radius}")
        _need(0 < self.scale_min <= 1.0 <= self.scale_max <= 100.0,
              f"need 0 < scale_min <= 1 <= scale_max <= 100, got {self.scale_min}, {self.scale_max}")


@dataclass(frozen=True)
class MotionSettings:
    """The motion model (:mod:`wmiltrack.engine.motion`): where the search is centred.

    Attributes
    ----------
    motion : {"none", "velocity"}
        Centre the search on the last box (``none``: no motion model) or on a
        constant-velocity prediction of the box centre (``velocity``; falls back to the last
        box when the last frame's confidence was below ``lost_threshold``).
    motion_smoothing : float
        Weight of the old velocity in the exponential velocity estimate, in [0, 1).
    motion_max : float
        The predicted displacement is clipped to this many pixels per frame.
    """

    motion: Literal["none", "velocity"] = "none"
    motion_smoothing: float = 0.5
    motion_max: float = 30.0

    def __post_init__(self) -> None:
        MotionSettings.check(self)

    def check(self) -> None:
        """``ValueError`` naming the first setting out of range."""
        _check_choices(self, {"motion": ("none", "velocity")})
        _check_numbers(self, "motion_smoothing", "motion_max")
        _need(0.0 <= self.motion_smoothing < 1.0,
              f"motion_smoothing must be in [0, 1), got {self.motion_smoothing}")
        _need(0.0 <= self.motion_max <= MAX_SEARCH_RADIUS,
              f"motion_max must be in [0, {MAX_SEARCH_RADIUS}], got {self.motion_max}")


@dataclass(frozen=True)
class ColourSettings:
    """The colour cue (:class:`wmiltrack.engine.cues.ColourCue`): a likelihood of the target's
    colours merged into every translation search stage (Staple-style).

    Attributes
    ----------
    colour_weight : float
        Weight ``w`` of the cue in the merge: ``(1 - w) * confidence + w * colour`` per
        candidate (0: no colour cue; also off for gray frames and BGR frames whose three
        channels are equal, unless ``gray_colour``).
    colour_relative : float or None
        How the classifier's side of the merge is read (for every cue merged into the
        search). None: its absolute confidence ``logistic(raw / K - confidence_offset)``. A
        number ``c``: its confidence relative to the search grid's best candidate,
        ``logistic((raw - best raw) / K + c)``, so that the best candidate of every frame
        scores ``logistic(c)``. After a sudden change of appearance the absolute confidence
        can fall to ~0 over the whole grid (a classifier learnt from a few frames is narrow),
        and the cue alone then picks the box; measured from the grid's best, the classifier
        keeps its say.
    colour_learning_rate : float
        Weight of each new frame's histograms in the search's colour model, in (0, 1]
        (Staple: 0.04). The first frame's copies that the reported score reads never change.
    colour_sample : int
        The colour and intensity histograms' learning and the reported score's contrasts read
        about this many pixels of a region at most (``engine.colour.ColourModel``'s
        ``sample``: a region of ``A`` pixels at every ``ceil(sqrt(A / colour_sample))``-th
        frame row and column; 0: every pixel). The search's cue always reads every pixel.
    gray_colour : bool
        On frames without colour, the colour cue (``colour_weight``, ``scale_contrast``,
        ``score_colour``) reads histograms of the pixels' luma instead of being off: how
        bright the target is against its surroundings is the colour cue that a gray video
        has. Decided on the first frame.
    """

    colour_weight: float = 0.0
    colour_relative: float | None = None
    colour_learning_rate: float = 0.04
    colour_sample: int = 0
    gray_colour: bool = False

    def __post_init__(self) -> None:
        ColourSettings.check(self)

    def check(self) -> None:
        """``ValueError`` naming the first setting out of range."""
        _check_numbers(self, "colour_weight")
        _need(self.colour_relative is None or _is_number(self.colour_relative),
              f"colour_relative must be None or a finite number, got {self.colour_relative!r}")
        _need(0.0 <= self.colour_weight <= 1.0,
              f"colour_weight must be in [0, 1], got {self.colour_weight}")
        _check_colour_model(self)
        _need(isinstance(self.gray_colour, bool),
              f"gray_colour must be True or False, got {self.gray_colour!r}")


@dataclass(frozen=True)
class ScoreSettings:
    """The reported score (:mod:`wmiltrack.engine.policy`).

    Attributes
    ----------
    score_colour : float
        Weight ``w`` of the box's colour contrast in the reported confidence
        (``TrackResult.score``): ``(1 - w) * logistic(raw / K - offset) + w * clip(0.5 +
        contrast, 0, 1)``, ``contrast`` being the mean ``P(target | colour)`` inside the box
        minus that over a ring around it (:func:`wmiltrack.engine.colour.colour_contrast`):
        a box on the target holds its colours and its surroundings do not, while a lost box
        sees background on both sides. Needs the colour cue. Only the report changes. 0: off.
    score_colour_model : {"current", "first"}
        Which colour histograms ``score_colour``'s contrast reads: ``current``, the ones the
        search uses (updated every frame, so they follow the box wherever it goes), or
        ``first``, the histograms learnt on the first frame and never updated (a memory of
        what the target looked like: a box that drifted onto background keeps a high
        classifier confidence, since the classifier learns the background it sits on, but
        its colours no longer stand out under the first frame's model).
    score_luma : float
        Weight ``v`` of a second contrast in the reported confidence: the box's contrast under
        a histogram of the first frame's intensities (luma, 32 levels), learnt once and never
        updated, on colour and gray frames alike. The score becomes ``(1 - w - v) * conf +
        w * clip(0.5 + colour contrast, 0, 1) + v * clip(0.5 + luma contrast, 0, 1)``; on
        frames without colour the colour term reads the luma contrast. 0: off.
    colour_learning_rate, colour_sample : float, int
        The colour cue's (:class:`ColourSettings`, which documents them), shared: the
        reported score keeps histograms of its own, learnt as the cue's are (with
        ``score_colour_model="current"``, learnt on the same frames as the cue's, so equal to
        them).
    """

    score_colour: float = 0.0
    score_colour_model: Literal["current", "first"] = "current"
    score_luma: float = 0.0
    colour_learning_rate: float = 0.04
    colour_sample: int = 0

    def __post_init__(self) -> None:
        ScoreSettings.check(self)

    def check(self) -> None:
        """``ValueError`` naming the first setting out of range."""
        _check_colour_model(self)
        _check_choices(self, {"score_colour_model": ("current", "first")})
        _need(_is_number(self.score_colour) and 0.0 <= self.score_colour <= 1.0,
              f"score_colour must be in [0, 1], got {self.score_colour!r}")
        _need(_is_number(self.score_luma) and 0.0 <= self.score_luma <= 1.0
              and self.score_colour + self.score_luma <= 1.0,
              f"score_luma must be in [0, 1 - score_colour], got {self.score_luma!r}")


@dataclass(frozen=True)
class TemplateSettings:
    """The correlation-filter template (:class:`wmiltrack.engine.template.CorrelationTemplate`):
    a translation filter on fHOG over a fixed-size template (Staple), merged into the search as
    a cue read at each candidate's centre, and optionally the motion model.

    Attributes
    ----------
    template_weight : float
        Weight of the filter's response (divided by its peak, clipped to [0, 1]) in the
        search's merge, beside the colour cue's (0: no template).
    template_motion : bool
        Centre the search on the filter's peak (searched over the target plus twice its mean
        side around the last box) instead of the motion model's prediction.
    template_area : float
        Template pixels the search region is resampled to (Staple: 150**2).
    template_learning_rate : float
        Weight of each new frame in the filter (Staple: 0.01).
    template_gate : float
        The correlation filters (the template and DSST's scale filter) learn only from frames
        whose reported score is at least this (0: every frame), so that an occluder or a drift
        the score notices stays out of them.
    template_every : int
        The correlation filters (the template and DSST's scale filter) learn from every
        ``template_every``-th frame they may learn from (ECO's sparse updates: each learning
        step costs a feature extraction and a transform per channel), their rates raised to
        keep the same memory.
    template_channels : int
        The template's 31 fHOG channels projected onto this many (ECO's compression: the
        principal axes of the first frame's features, fixed from then on), so that each
        frame transforms fewer planes; 0 keeps all 31.
    template_cell : int
        fHOG cell side in template pixels (Staple: 4); with ``template_area`` it sets the
        filter's grid, ``sqrt(template_area) / template_cell`` cells a side.
    template_reuse : bool
        The template learns from the frame's search sample, moved to the frame's final box
        (ECO: one feature extraction and one transform a frame instead of two), when that box
        is near the searched centre and of about the searched size; otherwise, and without
        this, from a new sample around the final box.
    template_pool_psr : float
        On frames where the filter's response has a peak-to-sidelobe ratio of at least this,
        a coarse search grid (step s) reads the filter's map at its best within s / 2 pixels
        of each candidate's centre instead of at the centre alone: the peak of a filter on
        2-pixel cells is narrower than the grid's step, and read at the grid's points a wide
        secondary hill can outscore it (0: never). A response without a clear peak (the
        target gone) is read at the centres, where its noise counts least.
    """

    template_weight: float = 0.0
    template_motion: bool = False
    template_area: float = 150.0**2
    template_learning_rate: float = 0.01
    template_gate: float = 0.0
    template_every: int = 1
    template_channels: int = 0
    template_cell: int = 4
    template_reuse: bool = False
    template_pool_psr: float = 0.0

    def __post_init__(self) -> None:
        TemplateSettings.check(self)

    def check(self) -> None:
        """``ValueError`` naming the first setting out of range."""
        _check_numbers(self, "template_weight", "template_area", "template_learning_rate",
                       "template_gate", "template_pool_psr")
        _need(0.0 <= self.template_weight <= 1.0,
              f"template_weight must be in [0, 1], got {self.template_weight}")
        _need(isinstance(self.template_motion, bool),
              f"template_motion must be True or False, got {self.template_motion!r}")
        _need(self.template_area >= 32.0**2, f"template_area must be >= 1024, got {self.template_area}")
        _need(0.0 < self.template_learning_rate <= 1.0,
              f"template_learning_rate must be in (0, 1], got {self.template_learning_rate}")
        _need(0.0 <= self.template_gate <= 1.0,
              f"template_gate must be in [0, 1], got {self.template_gate}")
        _need(_is_int(self.template_every) and 1 <= self.template_every <= 100,
              f"template_every must be an int in 1..100, got {self.template_every!r}")
        _need(self.template_pool_psr >= 0.0,
              f"template_pool_psr must be >= 0, got {self.template_pool_psr}")
        _need(_is_int(self.template_channels) and 0 <= self.template_channels <= 31,
              f"template_channels must be an int in 0..31, got {self.template_channels!r}")
        _need(_is_int(self.template_cell) and 1 <= self.template_cell <= 16
              and self.template_area >= (4 * self.template_cell) ** 2,
              f"template_cell must be an int in 1..16 with template_area >= (4 cell)**2, "
              f"got {self.template_cell!r}")
        _need(isinstance(self.template_reuse, bool),
              f"template_reuse must be True or False, got {self.template_reuse!r}")


@dataclass(frozen=True)
class RecoverySettings:
    """The re-detection of a lost target (:class:`wmiltrack.engine.recovery.Redetector`; the
    judge's ``redetect``, ``lost_drop`` and ``recover_warmup`` start the lost state).

    A target that is hidden (a full occlusion) or gone (out of view) must not be learnt: the
    classifier, the cues and the scale model would adopt the occluder or the background, and the
    score would climb back as if the target were there. With ``redetect``, a frame whose
    classifier confidence drops below ``lost_drop`` times its running mean over tracked frames
    starts the lost state: the box is held at the last confident one, ``ok`` is False and
    nothing learns. Each lost frame searches the whole frame for the target's grey template
    (kept from the tracked frames) by normalised cross-correlation, and takes the best place
    back once its correlation reaches both ``recover_floor`` and ``recover_ratio`` times the
    tracked boxes' running correlation (the latter lowered by ``recover_decay`` per lost
    frame); a fine search there gives the box. A lost frame whose usual search around the
    held box finds the classifier's confidence back above ``lost_drop`` times its running mean
    ends the lost state there.

    Attributes
    ----------
    recover_ratio : float
        A re-detected place is taken when its correlation with the template is at least this
        fraction of the tracked boxes' running correlation.
    recover_decay : float
        ``recover_ratio`` is multiplied by this for every frame lost so far (1: never lowered).
    recover_floor : float
        The least correlation a re-detected place needs in any case: people, cars and textures
        of one kind reach 0.7-0.77 at the wrong place on the shared sequences.
    recover_memory : float
        Weight of the old value in the running mean of the tracked boxes' correlation with the
        template, in [0, 1) (the judge's running means take the same weight:
        :class:`JudgeSettings`).
    recover_template_rate : float
        Weight of each tracked frame's patch in the grey template, in (0, 1].
    recover_template_area : float
        The template holds at most this many pixels (the box's aspect): a larger target is
        matched on frames shrunk by the same factor, and the fine search after a re-detection
        places the box to the pixel. Keeps a large target's per-frame cost and whole-frame
        search small.
    recover_search_area : float
        The whole-frame pass of the re-detection matches a template of at most this many
        pixels (the frame shrunk alike); the place it finds is checked at the template's
        resolution.
    """

    recover_ratio: float = 0.9
    recover_decay: float = 1.0
    recover_floor: float = 0.9
    recover_memory: float = 0.9
    recover_template_rate: float = 0.05
    recover_template_area: float = 1600.0
    recover_search_area: float = 256.0

    def __post_init__(self) -> None:
        RecoverySettings.check(self)

    def check(self) -> None:
        """``ValueError`` naming the first setting out of range."""
        _check_numbers(self, "recover_ratio", "recover_decay", "recover_floor")
        _need(0.0 < self.recover_ratio <= 1.0,
              f"recover_ratio must be in (0, 1], got {self.recover_ratio}")
        _need(0.0 < self.recover_decay <= 1.0,
              f"recover_decay must be in (0, 1], got {self.recover_decay}")
        _need(-1.0 <= self.recover_floor <= 1.0,
              f"recover_floor must be in [-1, 1], got {self.recover_floor}")
        _check_numbers(self, "recover_memory", "recover_template_rate", "recover_template_area",
                       "recover_search_area")
        _check_memory(self)
        _need(0.0 < self.recover_template_rate <= 1.0,
              f"recover_template_rate must be in (0, 1], got {self.recover_template_rate}")
        _need(self.recover_template_area >= 1.0 and self.recover_search_area >= 1.0,
              "recover_template_area and recover_search_area must be >= 1")


@dataclass(frozen=True)
class JudgeSettings:
    """The judge (:class:`wmiltrack.engine.judge.FrameJudge`): each frame's verdict (tracked,
    doubtful, lost, found), hence ``TrackResult.ok``, the lost state and what learns.

    Without its memory (``judge_memory = 0``), ``ok`` is the reported score against
    ``lost_threshold``, frame by frame.
    A tracker that drifted onto a distractor keeps a high score there (everything it learns
    follows it), so on the 34 development sequences that rule flags 12.8 % of well-tracked
    frames and misses 28 % of the frames off the target. The judge adds a memory and a delay:

    * a memory of the target: the correlation filter as it was on the first frame, never
      trained again, answers the live filter's search sample each frame; its response peak
      stays up on the target and falls on whatever the live filter drifted to;
    * the judged confidence is ``logistic(judge_score * (score - lost_threshold) +
      judge_memory * ln(first_peak / judge_peak))``;
    * hysteresis: the target counts as lost after ``judge_enter`` frames in a row judged below
      ``judge_low``, and as found again after ``judge_leave`` frames in a row above
      ``judge_high``.

    Only ``ok`` changes: the boxes are the same with the memory or without it. Needs the
    correlation-filter template (``template_weight > 0`` or ``template_motion``).

    With ``redetect``, the judge also starts the lost state: a frame whose classifier
    confidence drops below ``lost_drop`` times its running mean over tracked frames, while the
    cues' own confidences and the box's correlation with the recovery's grey template fell
    alike, is lost: the box is held at the last confident one, ``ok`` is False and nothing
    learns; each lost frame the target is found again where the usual search around the held
    box sees the confidence back, or where the recovery finds it over the whole frame
    (:class:`RecoverySettings`).

    Attributes
    ----------
    lost_threshold : float
        ``TrackResult.ok`` is False when the reported score falls below this; the motion
        model takes a frame's move as a velocity only when the classifier's confidence is at
        least this.
    redetect : bool
        Whether a lost target is held, not learnt, and searched for over the whole frame.
    lost_drop : float
        A frame counts as lost when its confidence is below this fraction of the running mean
        confidence of the tracked frames (in (0, 1)).
    recover_memory : float
        Weight of the old value in the running means of the confidence and the cues' own
        confidences, in [0, 1) (shared with :class:`RecoverySettings`: one rate for the
        running means of the lost state).
    recover_warmup : int
        Tracked frames before the first judgement: the first frames' confidence is inflated
        (the classifier has just been trained on the first box) and their running mean not yet
        formed.
    judge_memory : float
        Weight of the log of the first-frame filter's peak; 0 leaves the judge out.
    judge_score : float
        Weight of the reported score's distance from ``lost_threshold``.
    judge_peak : float
        The first-frame filter's peak at which that term is 0.
    judge_low, judge_high : float
        The judged confidence below which a frame counts against the target, and above which
        it counts for it, in (0, 1) with ``judge_low <= judge_high``.
    judge_enter, judge_leave : int
        Frames in a row that start and end the lost state (>= 1).
    judge_gates : bool
        While the judge holds the target for lost, no part learns (the boxes then change).
    judge_holds : bool
        When the judge's verdict turns to lost, the tracker enters the recovery's lost state
        (``redetect``): the box is held, nothing learns, and the target is looked for over
        the whole frame until the classifier or the re-detection finds it again.
    """

    lost_threshold: float = 0.5
    redetect: bool = False
    lost_drop: float = 0.6
    recover_memory: float = 0.9
    recover_warmup: int = 10
    judge_memory: float = 0.0
    judge_score: float = 8.0
    judge_peak: float = 0.082
    judge_low: float = 0.4
    judge_high: float = 0.9
    judge_enter: int = 3
    judge_leave: int = 2
    judge_gates: bool = False
    judge_holds: bool = False

    def __post_init__(self) -> None:
        JudgeSettings.check(self)

    def check(self) -> None:
        """``ValueError`` naming the first setting out of range."""
        _check_numbers(self, "lost_threshold")
        _need(0.0 <= self.lost_threshold <= 1.0,
              f"lost_threshold must be in [0, 1], got {self.lost_threshold}")
        _need(isinstance(self.redetect, bool), f"redetect must be True or False, got {self.redetect!r}")
        _check_numbers(self, "lost_drop")
        _need(0.0 < self.lost_drop < 1.0, f"lost_drop must be in (0, 1), got {self.lost_drop}")
        _check_memory(self)
        _check_ints(self, "recover_warmup")
        _need(self.recover_warmup >= 0, f"recover_warmup must be >= 0, got {self.recover_warmup}")
        _check_numbers(self, "judge_memory", "judge_score", "judge_peak", "judge_low", "judge_high")
        _check_ints(self, "judge_enter", "judge_leave")
        _need(self.judge_memory >= 0.0, f"judge_memory must be >= 0, got {self.judge_memory}")
        _need(self.judge_score >= 0.0, f"judge_score must be >= 0, got {self.judge_score}")
        _need(self.judge_peak > 0.0, f"judge_peak must be > 0, got {self.judge_peak}")
        _need(0.0 < self.judge_low <= self.judge_high < 1.0,
              f"judge_low and judge_high must satisfy 0 < judge_low <= judge_high < 1, got "
              f"{self.judge_low} and {self.judge_high}")
        _need(self.judge_enter >= 1, f"judge_enter must be >= 1, got {self.judge_enter}")
        _need(self.judge_leave >= 1, f"judge_leave must be >= 1, got {self.judge_leave}")
        _need(isinstance(self.judge_gates, bool),
              f"judge_gates must be True or False, got {self.judge_gates!r}")
        _need(isinstance(self.judge_holds, bool),
              f"judge_holds must be True or False, got {self.judge_holds!r}")


@dataclass(frozen=True)
class AppearanceSettings(SearchSettings, ClassifierSettings, BagSettings, FeatureSettings):
    """The appearance model's settings (:class:`~wmiltrack.engine.appearance.HaarAppearance`):
    the feature bank, the bags, the weak classifiers and their selection, and the search; the
    four classes above at once (no field of its own)."""

    def __post_init__(self) -> None:
        AppearanceSettings.check(self)

    def check(self) -> None:
        """``ValueError`` naming the first setting out of range."""
        for part in (FeatureSettings, BagSettings, ClassifierSettings, SearchSettings):
            part.check(self)


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
    def of(cls, template: TemplateSettings | ScaleSettings) -> FilterLearning:
        """The rule that the ``template_*`` settings give (the template's, or those the
        scale settings share)."""
        return cls(every=template.template_every, above=template.template_gate,
                   reuse=template.template_reuse)


#: The filters' learning rule of the default settings: every frame, whatever its score.
NO_GATE = FilterLearning()


NETWORKS: tuple[str, ...] = ("", *siamese_networks())
"""The Siamese networks :class:`ExpertSettings` can add ("" for none): the model sets of
:func:`wmiltrack.networks.families.siamese_networks`."""


@dataclass(frozen=True)
class ExpertSettings:
    """A Siamese network as a second expert beside the tracker, and the judge between the two
    (:class:`wmiltrack.engine.experts.TwoExperts`; rcwmil-nano).

    The network (NanoTrack, :mod:`wmiltrack.networks.nanotrack`) leads: it is the more accurate
    locator on the development set, and its first-frame template is a memory of the target
    that never learns. Each frame the judge compares the two experts' boxes and asks the
    network's backbone how alike the network's box is to the first frame's target (the cosine
    of their feature maps, the *likeness*). Where the boxes agree (IoU >= ``expert_agree``) the
    box is their mix, the filter's share ``expert_blend``; where they do not, the network's box
    is taken and the filter is moved there (keeping what it learnt). ``ok`` comes from the
    likeness with hysteresis: lost after ``lost_frames`` frames in a row below ``like_low``,
    found again after ``found_frames`` frames in a row above ``like_high``. While lost, the
    network searches, after ``redetect_after`` lost frames, ``redetect_windows`` more windows a
    frame over the whole frame (nearest first, then sweeping) besides its own and the
    tracker's box, and moves to one that is alike the target and more alike than its own.

    Attributes
    ----------
    network : str
        ``"nanotrack-v3"`` or ``"nanotrack-v2"``; ``""`` leaves the network out.
    backbone, head : str
        The model files' paths; ``""`` finds them (:func:`wmiltrack.networks.files.nanotrack_files`:
        ``WMILTRACK_NANO_BACKBONE`` / ``WMILTRACK_NANO_HEAD``, then the models folder).
    network_runtime : str
        ``"auto"`` (onnxruntime when installed, else OpenCV's dnn), ``"onnxruntime"`` or
        ``"opencv"``.
    network_threads : int
        Threads of the network's runtime.
    expert_agree : float
        The two boxes' IoU at which the experts agree.
    expert_blend : float
        The filter's share of the box where they agree, in [0, 1].
    like_low, like_high : float
        The likeness below which a frame counts against the target and above which it counts
        for it.
    like_drop : float
        The share of the running mean below which a frame counts against the target (0: never).
    like_found : float
        The share of the running mean above which a lost frame counts for the target (with
        ``like_high``), at least ``like_drop``.
    like_rate : float
        The running mean's learning rate, in (0, 1].
    lost_frames, found_frames : int
        Frames in a row that start and end the lost state.
    redetect_windows : int
        Whole-frame search windows a lost frame tries besides the network's own (0: none).
    redetect_after : int
        Lost frames before the whole-frame windows start: a short spell (a turn, a brief
        occlusion) is better left to the network's own search than risked on a far place that
        looks like the target's surroundings.
    likeness_every : int
        On frames where the experts agree and the tracker says ``ok`` (which never count
        against the target), the likeness is measured only every ``likeness_every``-th such
        frame (it costs one more pass of the backbone); the reported score repeats the last
        measured one in between. 1: every frame.
    """

    network: str = ""
    backbone: str = ""
    head: str = ""
    network_runtime: str = "auto"
    network_threads: int = 1
    expert_agree: float = 0.3
    expert_blend: float = 0.2
    like_low: float = 0.45
    like_high: float = 0.6
    like_drop: float = 0.8
    like_found: float = 0.9
    like_rate: float = 0.05
    lost_frames: int = 3
    found_frames: int = 2
    redetect_windows: int = 4
    redetect_after: int = 10
    likeness_every: int = 1

    def __post_init__(self) -> None:
        ExpertSettings.check(self)

    def check(self) -> None:
        """``ValueError`` naming the first setting out of range."""
        _check_choices(self, {"network": NETWORKS,
                              "network_runtime": RUNTIMES})
        _need(isinstance(self.backbone, str) and isinstance(self.head, str),
              "backbone and head must be paths as strings ('' to find them)")
        _check_ints(self, "network_threads", "lost_frames", "found_frames", "redetect_windows",
                    "redetect_after", "likeness_every")
        _need(self.redetect_after >= 0, f"redetect_after must be >= 0, got {self.redetect_after}")
        _need(self.likeness_every >= 1, f"likeness_every must be >= 1, got {self.likeness_every}")
        _check_numbers(self, "expert_agree", "expert_blend", "like_low", "like_high", "like_drop",
                       "like_found", "like_rate")
        _need(0.0 <= self.like_drop <= self.like_found <= 1.0,
              f"like_drop and like_found must satisfy 0 <= like_drop <= like_found <= 1, got "
              f"{self.like_drop} and {self.like_found}")
        _need(0.0 < self.like_rate <= 1.0, f"like_rate must be in (0, 1], got {self.like_rate}")
        _need(self.network_threads >= 1, f"network_threads must be >= 1, got {self.network_threads}")
        _need(0.0 <= self.expert_agree <= 1.0, f"expert_agree must be in [0, 1], got {self.expert_agree}")
        _need(0.0 <= self.expert_blend <= 1.0, f"expert_blend must be in [0, 1], got {self.expert_blend}")
        _need(-1.0 <= self.like_low <= self.like_high <= 1.0,
              f"like_low and like_high must satisfy -1 <= like_low <= like_high <= 1, got "
              f"{self.like_low} and {self.like_high}")
        _need(self.lost_frames >= 1, f"lost_frames must be >= 1, got {self.lost_frames}")
        _need(self.found_frames >= 1, f"found_frames must be >= 1, got {self.found_frames}")
        _need(self.redetect_windows >= 0,
              f"redetect_windows must be >= 0, got {self.redetect_windows}")
