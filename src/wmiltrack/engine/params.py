"""Tracker parameters: one frozen object per variant, every constant of the spec overridable.

The six variants share one engine; what distinguishes them is only the values below. The
defaults follow ``ALGORITHMS.md`` (the project's spec) and, for rcwmil, the paper; the table
in the README is generated from :data:`VARIANTS`.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any, Literal

FeatureKind = Literal["subregion", "random"]
WeightMode = Literal["sign", "sign_sqrt", "uniform"]
NegSampling = Literal["exact", "bernoulli"]
ClassifierKind = Literal["gaussian", "mil"]
FirstUpdate = Literal["direct", "blend"]
SelectionKind = Literal["wmil", "milboost", "none"]
InstanceWeights = Literal["exp", "exp_sq", "uniform"]
GradientForm = Literal["paper", "code"]
SubregionMode = Literal["grid", "random"]
MotionModel = Literal["none", "velocity"]
ScaleModel = Literal["ratio", "likelihood", "both"]
ScoreColourModel = Literal["current", "first"]
LostSignal = Literal["classifier", "score"]
ZeroDC = Literal["none", "box", "subregion"]

_CHOICES: dict[str, tuple[str, ...]] = {
    "feature_kind": ("subregion", "random"),
    "weight_mode": ("sign", "sign_sqrt", "uniform"),
    "neg_sampling": ("exact", "bernoulli"),
    "classifier": ("gaussian", "mil"),
    "first_update": ("direct", "blend"),
    "selection": ("wmil", "milboost", "none"),
    "instance_weights": ("exp", "exp_sq", "uniform"),
    "gradient": ("paper", "code"),
    "subregion_mode": ("grid", "random"),
    "motion": ("none", "velocity"),
    "scale_model": ("ratio", "likelihood", "both"),
    "score_colour_model": ("current", "first"),
    "lost_signal": ("classifier", "score"),
    "zero_dc": ("none", "box", "subregion"),
}


MAX_POS_RADIUS = 100
"""Largest positive-bag radius (``pos_radius``, ``init_pos_radius``): ~31 000 positives."""
MAX_NEG_RADIUS = 500
"""Largest outer negative radius (``neg_outer``, ``init_neg_outer``)."""
MAX_SEARCH_RADIUS = 1000
"""Largest search radius (``coarse_radius``, ``fine_radius``)."""


#: Default of ``Params.confidence_offset``: the mean weak-classifier log ratio at which a frame
#: is as likely tracked (IoU > 0) as lost. A class-balanced logistic fit of "IoU > 0" on the mean
#: log ratio over 17 OTB sequences and 6 generated full-occlusion/vanishing sequences gave
#: offsets 1.25-1.63 and gains 0.8-1.1 for five variants (``scripts/score_study.py``).
CONFIDENCE_OFFSET = 1.4


@dataclass(frozen=True)
class Params:
    """All settings of one tracker variant (defaults: rcwmil, the paper's tracker).

    Attributes
    ----------
    variant : str
        Name of the variant these settings started from.
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
        features (CT, FCT).
    instance_weights : {"exp", "exp_sq", "uniform"}
        Positive-bag weights: exp(-d) normalised (paper), exp(-d^2) unnormalised (WMIL
        reference code), or equal weights (OSIL).
    gradient : {"paper", "code"}
        WMIL selection gradient w s (1 - s) / sum(w s) (paper) or the reference code's
        w s (1 - w s) / sum(w s).
    coarse_radius, coarse_step : int
        Search grid: offsets (i, j) * step with |offset| < radius.
    fine_radius, fine_step : int
        Second, finer search around the coarse winner (``fine_radius=0``: none).
    lost_threshold : float
        ``TrackResult.ok`` is False when the confidence falls below this.
    min_box_size : int
        Smallest box side accepted (after clipping to the frame).
    confidence_offset : float
        Offset of the confidence ``logistic(raw / K - offset)`` (see
        :func:`wmiltrack.engine.tracker.confidence`).

    The fields below are the ``rcwmil-plus`` components; their defaults switch each one off,
    so the paper presets run the paper's code path.

    channels : tuple of str
        Image channels the features are drawn on, each feature on one: any of ``"luma"``,
        ``"grad"`` (gradient magnitude), ``"orient0"`` .. ``"orient3"`` (the gradient
        magnitude where the unsigned gradient angle is nearest 0, 45, 90, 135 degrees, else
        0: integral channel features, a four-bin histogram of oriented gradients summed by
        rectangles), ``"opp_rg"``, ``"opp_yb"`` (colour opponents; they drop out for gray
        frames), ``"logluma"`` (the luma on a log scale through a 256-entry table, so that a
        change of brightness by a factor is about an added constant; see ``zero_dc``).
        Empty (the paper): luma only, one integral image.
    scale_steps : int
        Scale search: after the translation search, also try the box scaled by
        ``scale_factor ** j`` for ``j = -scale_steps..scale_steps`` (0: the box keeps its
        first size). The Haar rectangles are scaled, not the image.
    scale_factor : float
        Ratio between neighbouring scales (> 1).
    scale_model : {"ratio", "likelihood"}
        How scales are compared: ``ratio``, the strong classifier's mean log ratio (best of a
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
        With the colour model on (``colour_weight > 0`` on colour frames) and
        ``scale_model`` ``"ratio"`` or ``"both"``: add this weight times each tried box's
        colour contrast (:func:`wmiltrack.engine.colour.colour_contrast`: the mean
        ``P(target | colour)`` inside the box minus that over a ring around it, under the
        colour model the search uses, read from the search's likelihood table) to that
        scale's value (0: off). The classifier prefers smaller boxes and the target
        likelihood larger ones; the contrast is largest for the box that holds the target's
        colours and no more. A contrast changes by about 0.01 between neighbouring scales,
        so a weight of 20 makes it count about as much as one step's ``scale_penalty`` (0.2).
    motion : {"none", "velocity"}
        Centre the search on the last box (``none``) or on a constant-velocity prediction
        of the box centre (``velocity``; falls back to the last box when the last frame's
        confidence was below ``lost_threshold``).
    motion_smoothing : float
        Weight of the old velocity in the exponential velocity estimate, in [0, 1).
    motion_max : float
        The predicted displacement is clipped to this many pixels per frame.
    colour_weight : float
        Weight of a colour likelihood (``engine.colour``: foreground/background colour
        histograms, the mean P(target | colour) over a candidate box) merged into every
        translation search stage: ``(1 - w) * confidence + w * colour`` per candidate (0: off;
        also off for gray frames and BGR frames whose three channels are equal).
    colour_relative : float or None
        How the classifier's side of that merge is read. None: its absolute confidence
        ``logistic(raw / K - confidence_offset)``. A number ``c``: its confidence relative to
        the search grid's best candidate, ``logistic((raw - best raw) / K + c)``, so that the
        best candidate of every frame scores ``logistic(c)``. After a sudden change of
        appearance the absolute confidence can fall to ~0 over the whole grid (a classifier
        learnt from a few frames is narrow), and the colour cue alone then picks the box;
        measured from the grid's best, the classifier keeps its say.
    colour_learning_rate : float
        Weight of each new frame's histograms in the search's colour model, in (0, 1] (Staple:
        0.04). The first frame's copies that the reported score reads never change.
    colour_sample : int
        The colour and intensity histograms' learning and the reported score's contrasts read
        about this many pixels of a region at most (``engine.colour.ColourModel``'s
        ``sample``: a region of ``A`` pixels at every ``ceil(sqrt(A / colour_sample))``-th
        frame row and column; 0: every pixel). A large box's histograms then cost what a
        small box's do. The search's colour cue always reads every pixel.
    score_colour : float
        With the colour model on, the reported confidence (``TrackResult.score``, and ``ok``
        from it) is ``(1 - w) * logistic(raw / K - offset) + w * clip(0.5 + contrast, 0, 1)``
        with ``w`` this weight and ``contrast`` the colour contrast of the box, the mean
        ``P(target | colour)`` inside it minus that over a ring around it
        (:func:`wmiltrack.engine.colour.colour_contrast`): a box on the target holds its
        colours and its surroundings do not, while a lost box sees background on both
        sides. Only the report changes: ``motion``, the gates and ``recovery_radius`` still
        read the classifier's confidence. 0: off. (With ``score_luma`` the classifier's
        weight is ``1 - w - score_luma``.)
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
        w * clip(0.5 + colour contrast, 0, 1) + v * clip(0.5 + luma contrast, 0, 1)`` (``w``:
        ``score_colour``); on frames without colour the colour term reads the luma contrast.
        Only the report changes, as for ``score_colour``. 0: off.
    lost_signal : {"classifier", "score"}
        What the lost state (``motion``'s reset, ``recovery_radius``) and the gates
        (``gate_threshold``, ``gate_learning_rate``) read: the classifier's confidence, or the
        reported score (``TrackResult.score``, with ``score_colour`` / ``score_luma``).
    gate_threshold : float
        Learn only from frames whose confidence is at least this (0: always learn).
    gate_drop : float
        Also learn only when the best candidate's mean log ratio is no more than this below
        its running mean over the frames learnt from (a drop relative to the sequence's own
        level, which differs between targets; 0: off).
    gate_learning_rate : float or None
        The learning rate (lambda) used for frames whose confidence is at least
        ``gate_threshold`` but below ``lost_threshold`` (slow learning); ``None``: the same
        ``learning_rate`` as for confidently tracked frames.
    recovery_radius, recovery_step : int
        While lost (confidence below ``lost_threshold``), the coarse search is centred on
        the last confidently tracked box with this radius and step (``recovery_radius=0``:
        no recovery search).
    zero_dc : {"none", "box", "subregion"}
        Make every feature blind to an intensity offset added to the whole box (``box``) or
        to the feature's sub-region (``subregion``; the box for ``random`` features): a
        rectangle over that reference region is added to each feature with the weight that
        makes the feature's weights times areas sum to zero, so the feature measures its
        rectangles' means relative to the reference region's mean. On a log-intensity
        channel (``"logluma"``) an offset is a multiplicative change of brightness (a
        shadow). ``none``: the features as drawn.
    zero_dc_channels : tuple of str
        With ``zero_dc`` and ``channels``: only the features on these channels are made
        blind to an offset (empty: every feature).
    anchor_weight : float
        Before every update, the target's Gaussians (mu1, sigma1) are pulled towards the
        first frame's by this fraction (``mu1 <- (1 - a) mu1 + a mu1_first``, likewise
        sigma1), so that a few frames of learning the wrong thing cannot rewrite what the
        target looks like (0: off).
    gray_channels : tuple of str
        On frames without colour (gray, or BGR with three equal channels: where the colour
        likelihood is off), use these channels instead of ``channels`` (empty: ``channels``
        on every frame). Decided on the first frame.
    gray_anchor_weight : float or None
        On frames without colour, this ``anchor_weight`` instead (``None``: ``anchor_weight``).
    gray_colour : bool
        On frames without colour, the colour likelihood (``colour_weight``, ``scale_contrast``,
        ``score_colour``) reads histograms of the pixels' luma instead of being off: how bright
        the target is against its surroundings is the colour cue that a gray video has.
        Decided on the first frame.
    """

    variant: str = "rcwmil"
    feature_kind: FeatureKind = "subregion"
    num_features: int = 100
    num_selected: int = 20
    rects_min: int = 2
    rects_max: int = 4
    num_subregions: int = 4
    subregion_mode: SubregionMode = "grid"
    positive_prob: float = 0.78
    rect_min_size: int = 2
    beta_min: float = 0.2
    beta_max: float = 0.8
    rect_bounds: tuple[int, int, int, int] = (1, 6, 2, 3)
    weight_mode: WeightMode = "sign"
    area_normalize: bool = True
    pos_radius: float = 4.0
    neg_inner: float = 8.0
    neg_outer: float = 22.0
    neg_count: int = 50
    neg_sampling: NegSampling = "exact"
    init_pos_radius: float | None = None
    init_neg_inner: float | None = None
    init_neg_outer: float | None = None
    init_neg_count: int | None = None
    learning_rate: float = 0.9
    classifier: ClassifierKind = "gaussian"
    first_update: FirstUpdate = "direct"
    sigma_floor: float = 1e-6
    guard: float = 1e-30
    selection: SelectionKind = "wmil"
    instance_weights: InstanceWeights = "exp"
    gradient: GradientForm = "paper"
    coarse_radius: int = 25
    coarse_step: int = 4
    fine_radius: int = 10
    fine_step: int = 1
    lost_threshold: float = 0.5
    min_box_size: int = 4
    confidence_offset: float = CONFIDENCE_OFFSET
    channels: tuple[str, ...] = ()
    scale_steps: int = 0
    scale_factor: float = 1.03
    scale_model: ScaleModel = "ratio"
    scale_learning_rate: float = 0.975
    scale_mix: float = 1.0
    scale_penalty: float = 0.0
    scale_radius: int = 2
    scale_min: float = 0.2
    scale_max: float = 5.0
    scale_negatives: int = 0
    scale_contrast: float = 0.0
    motion: MotionModel = "none"
    motion_smoothing: float = 0.5
    motion_max: float = 30.0
    colour_weight: float = 0.0
    colour_relative: float | None = None
    colour_learning_rate: float = 0.04
    colour_sample: int = 0
    score_colour: float = 0.0
    score_colour_model: ScoreColourModel = "current"
    score_luma: float = 0.0
    lost_signal: LostSignal = "classifier"
    gate_threshold: float = 0.0
    gate_drop: float = 0.0
    gate_learning_rate: float | None = None
    recovery_radius: int = 0
    recovery_step: int = 4
    zero_dc: ZeroDC = "none"
    zero_dc_channels: tuple[str, ...] = ()
    anchor_weight: float = 0.0
    gray_channels: tuple[str, ...] = ()
    gray_anchor_weight: float | None = None
    gray_colour: bool = False
    description: str = field(default="", compare=False)

    def __post_init__(self) -> None:
        for name, choices in _CHOICES.items():
            value = getattr(self, name)
            if value not in choices:
                raise ValueError(f"{name} must be one of {', '.join(choices)}; got {value!r}")

        def need(ok: bool, message: str) -> None:
            if not ok:
                raise ValueError(message)

        def is_int(v: Any) -> bool:
            return isinstance(v, int) and not isinstance(v, bool)

        for name in ("num_features", "num_selected", "rects_min", "rects_max", "num_subregions",
                     "rect_min_size", "neg_count", "coarse_radius", "coarse_step",
                     "fine_radius", "fine_step", "min_box_size", "scale_steps", "scale_radius",
                     "scale_negatives", "recovery_radius", "recovery_step"):
            need(is_int(getattr(self, name)), f"{name} must be an int, got {getattr(self, name)!r}")
        need(self.num_features >= 1, f"num_features must be >= 1, got {self.num_features}")
        need(1 <= self.num_selected <= self.num_features,
             f"num_selected (K) must be in 1..num_features ({self.num_features}), got {self.num_selected}")
        if self.selection == "none":
            need(self.num_selected == self.num_features,
                 "selection='none' scores every feature: num_selected must equal num_features")
        need(1 <= self.rects_min <= self.rects_max,
             f"need 1 <= rects_min <= rects_max, got {self.rects_min}, {self.rects_max}")
        need(self.num_subregions in (1, 4, 9, 16) if self.subregion_mode == "grid"
             else self.num_subregions >= 1,
             f"num_subregions for a grid must be a square (1, 4, 9, 16), got {self.num_subregions}")
        need(0.0 <= self.positive_prob <= 1.0, f"positive_prob must be in [0, 1], got {self.positive_prob}")
        need(self.rect_min_size >= 1, f"rect_min_size must be >= 1, got {self.rect_min_size}")
        need(0.0 < self.beta_min <= self.beta_max <= 1.0,
             f"need 0 < beta_min <= beta_max <= 1, got {self.beta_min}, {self.beta_max}")
        need(len(self.rect_bounds) == 4 and all(is_int(v) and v >= 0 for v in self.rect_bounds),
             f"rect_bounds must be four ints >= 0, got {self.rect_bounds}")
        need(self.rect_bounds[2] >= 1, "rect_bounds[2] (smallest rectangle side) must be >= 1")
        # A rectangle starts at most rect_bounds[1] pixels before the box's far edge and is at
        # least rect_bounds[2] wide: it only stays inside the box if the latter fits.
        need(self.rect_bounds[2] <= self.rect_bounds[1],
             f"rect_bounds[2] (smallest rectangle side, {self.rect_bounds[2]}) must be <= "
             f"rect_bounds[1] (room left after a rectangle's start, {self.rect_bounds[1]})")
        for name in ("pos_radius", "neg_inner", "neg_outer", "learning_rate", "sigma_floor", "guard",
                     "lost_threshold"):
            v = getattr(self, name)
            need(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v),
                 f"{name} must be a finite number, got {v!r}")
        need(self.pos_radius > 0, f"pos_radius must be > 0, got {self.pos_radius}")
        need(0 <= self.neg_inner < self.neg_outer,
             f"need 0 <= neg_inner < neg_outer, got {self.neg_inner}, {self.neg_outer}")
        need(self.neg_count >= 0, f"neg_count must be >= 0, got {self.neg_count}")
        for name in ("init_pos_radius", "init_neg_inner", "init_neg_outer", "colour_relative"):
            v = getattr(self, name)
            need(v is None or (isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)),
                 f"{name} must be None or a finite number, got {v!r}")
        if self.init_pos_radius is not None:
            need(self.init_pos_radius > 0, "init_pos_radius must be > 0")
        # Upper limits keep the enumerated offsets (and the memory they take) bounded.
        for name in ("pos_radius", "init_pos_radius"):
            v = getattr(self, name)
            need(v is None or v <= MAX_POS_RADIUS, f"{name} must be <= {MAX_POS_RADIUS}, got {v}")
        for name in ("neg_outer", "init_neg_outer"):
            v = getattr(self, name)
            need(v is None or v <= MAX_NEG_RADIUS, f"{name} must be <= {MAX_NEG_RADIUS}, got {v}")
        inner = self.neg_inner if self.init_neg_inner is None else self.init_neg_inner
        outer = self.neg_outer if self.init_neg_outer is None else self.init_neg_outer
        need(0 <= inner < outer, f"need 0 <= init_neg_inner < init_neg_outer, got {inner}, {outer}")
        if self.init_neg_count is not None:
            need(is_int(self.init_neg_count) and self.init_neg_count >= 0,
                 "init_neg_count must be an int >= 0")
        need(0.0 <= self.learning_rate < 1.0,
             f"learning_rate (lambda) must be in [0, 1), got {self.learning_rate}")
        need(self.sigma_floor > 0, f"sigma_floor must be > 0, got {self.sigma_floor}")
        need(self.guard > 0, f"guard must be > 0, got {self.guard}")
        need(self.coarse_radius >= 1 and self.coarse_step >= 1,
             f"coarse_radius and coarse_step must be >= 1, got {self.coarse_radius}, {self.coarse_step}")
        need(self.coarse_radius <= MAX_SEARCH_RADIUS and self.fine_radius <= MAX_SEARCH_RADIUS,
             f"coarse_radius and fine_radius must be <= {MAX_SEARCH_RADIUS}, got "
             f"{self.coarse_radius}, {self.fine_radius}")
        need(self.fine_radius >= 0 and self.fine_step >= 1,
             f"fine_radius must be >= 0 and fine_step >= 1, got {self.fine_radius}, {self.fine_step}")
        need(0.0 <= self.lost_threshold <= 1.0,
             f"lost_threshold must be in [0, 1], got {self.lost_threshold}")
        need(self.min_box_size >= 2, f"min_box_size must be >= 2, got {self.min_box_size}")
        for name in ("confidence_offset", "scale_factor", "scale_penalty", "scale_min", "scale_max",
                     "motion_smoothing", "motion_max", "gate_threshold", "gate_drop", "scale_mix",
                     "colour_weight", "scale_contrast", "colour_learning_rate"):
            v = getattr(self, name)
            need(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v),
                 f"{name} must be a finite number, got {v!r}")
        known = ("luma", "grad", "orient0", "orient1", "orient2", "orient3", "opp_rg", "opp_yb",
                 "logluma", "grad_x", "grad_y")
        need(isinstance(self.channels, tuple) and all(c in known for c in self.channels)
             and len(set(self.channels)) == len(self.channels),
             f"channels must be a tuple of distinct names from {', '.join(known)}; got {self.channels!r}")
        need(self.channels == () or any(c not in ("opp_rg", "opp_yb") for c in self.channels),
             "channels needs a gray channel: luma, logluma, grad or orient0..3 (the colour channels drop "
             "out for gray frames)")
        need(isinstance(self.zero_dc_channels, tuple)
             and all(c in self.channels + self.gray_channels for c in self.zero_dc_channels),
             f"zero_dc_channels must be a tuple of names from channels; got {self.zero_dc_channels!r}")
        need(0 <= self.scale_steps <= 10, f"scale_steps must be in 0..10, got {self.scale_steps}")
        need(isinstance(self.scale_learning_rate, (int, float))
             and not isinstance(self.scale_learning_rate, bool)
             and 0.0 <= self.scale_learning_rate < 1.0,
             f"scale_learning_rate must be in [0, 1), got {self.scale_learning_rate}")
        need(0 <= self.scale_negatives <= 20,
             f"scale_negatives must be in 0..20, got {self.scale_negatives}")
        need(self.scale_negatives == 0 or self.scale_steps > 0,
             "scale_negatives needs the scale search (scale_steps > 0)")
        need(1.0 < self.scale_factor <= 2.0, f"scale_factor must be in (1, 2], got {self.scale_factor}")
        need(self.scale_penalty >= 0, f"scale_penalty must be >= 0, got {self.scale_penalty}")
        need(self.scale_contrast >= 0, f"scale_contrast must be >= 0, got {self.scale_contrast}")
        need(1 <= self.scale_radius <= 50, f"scale_radius must be in 1..50, got {self.scale_radius}")
        need(0 < self.scale_min <= 1.0 <= self.scale_max <= 100.0,
             f"need 0 < scale_min <= 1 <= scale_max <= 100, got {self.scale_min}, {self.scale_max}")
        need(0.0 <= self.motion_smoothing < 1.0,
             f"motion_smoothing must be in [0, 1), got {self.motion_smoothing}")
        need(0.0 <= self.motion_max <= MAX_SEARCH_RADIUS,
             f"motion_max must be in [0, {MAX_SEARCH_RADIUS}], got {self.motion_max}")
        need(0.0 <= self.colour_weight <= 1.0,
             f"colour_weight must be in [0, 1], got {self.colour_weight}")
        need(0.0 < self.colour_learning_rate <= 1.0,
             f"colour_learning_rate must be in (0, 1], got {self.colour_learning_rate!r}")
        need(isinstance(self.colour_sample, int) and not isinstance(self.colour_sample, bool)
             and self.colour_sample >= 0,
             f"colour_sample must be an integer >= 0, got {self.colour_sample!r}")
        need(isinstance(self.score_colour, (int, float)) and not isinstance(self.score_colour, bool)
             and 0.0 <= self.score_colour <= 1.0,
             f"score_colour must be in [0, 1], got {self.score_colour!r}")
        need(isinstance(self.score_luma, (int, float)) and not isinstance(self.score_luma, bool)
             and 0.0 <= self.score_luma <= 1.0 and self.score_colour + self.score_luma <= 1.0,
             f"score_luma must be in [0, 1 - score_colour], got {self.score_luma!r}")
        need(isinstance(self.gray_colour, bool),
             f"gray_colour must be True or False, got {self.gray_colour!r}")
        need(self.gray_anchor_weight is None
             or (isinstance(self.gray_anchor_weight, (int, float))
                 and not isinstance(self.gray_anchor_weight, bool)
                 and 0.0 <= self.gray_anchor_weight <= 1.0),
             f"gray_anchor_weight must be None or in [0, 1], got {self.gray_anchor_weight!r}")
        need(isinstance(self.gray_channels, tuple) and all(c in known for c in self.gray_channels)
             and len(set(self.gray_channels)) == len(self.gray_channels)
             and all(c not in ("opp_rg", "opp_yb") for c in self.gray_channels),
             f"gray_channels must be a tuple of distinct gray channel names from {', '.join(known)}; "
             f"got {self.gray_channels!r}")
        need(isinstance(self.anchor_weight, (int, float)) and not isinstance(self.anchor_weight, bool)
             and 0.0 <= self.anchor_weight <= 1.0,
             f"anchor_weight must be in [0, 1], got {self.anchor_weight!r}")
        need(self.gate_drop >= 0.0, f"gate_drop must be >= 0, got {self.gate_drop}")
        need(0.0 <= self.gate_threshold <= 1.0,
             f"gate_threshold must be in [0, 1], got {self.gate_threshold}")
        need(self.gate_learning_rate is None
             or (isinstance(self.gate_learning_rate, (int, float))
                 and not isinstance(self.gate_learning_rate, bool)
                 and 0.0 <= self.gate_learning_rate < 1.0),
             f"gate_learning_rate must be in [0, 1), got {self.gate_learning_rate}")
        need(0 <= self.recovery_radius <= MAX_SEARCH_RADIUS and self.recovery_step >= 1,
             f"recovery_radius must be in 0..{MAX_SEARCH_RADIUS} and recovery_step >= 1, got "
             f"{self.recovery_radius}, {self.recovery_step}")

    # -- derived values ---------------------------------------------------------------------
    @property
    def search_reach(self) -> int:
        """Largest distance in pixels that one update can move the box from the search origin."""
        reach = max(self.coarse_radius, self.recovery_radius) - 1
        if self.fine_radius > 0:
            reach += self.fine_radius - 1
        if self.scale_steps > 0:
            reach += self.scale_radius - 1
        return reach

    def replace(self, **changes: Any) -> Params:
        """A copy with some fields changed (validated like the constructor)."""
        unknown = set(changes) - {f.name for f in dataclasses.fields(self)}
        if unknown:
            import difflib

            names = [f.name for f in dataclasses.fields(self) if f.name != "description"]
            hints = []
            for name in sorted(unknown):
                close = difflib.get_close_matches(name, names, n=3)
                hints.append(f"{name!r}" + (f" (did you mean {' or '.join(map(repr, close))}?)"
                                            if close else ""))
            raise TypeError(f"unknown parameter(s) {', '.join(hints)}; `wmiltrack variants "
                            f"{self.variant}` lists the {len(names)} parameters")
        return dataclasses.replace(self, **changes)

    @classmethod
    def for_variant(cls, variant: str = "rcwmil", **overrides: Any) -> Params:
        """The defaults of ``variant`` with ``overrides`` applied."""
        if not isinstance(variant, str) or variant.lower() not in VARIANTS:
            raise ValueError(f"unknown variant {variant!r}; choose one of {', '.join(VARIANTS)}")
        return VARIANTS[variant.lower()].replace(**overrides)

    def as_dict(self) -> dict[str, Any]:
        """Every field as a plain dict (JSON-friendly)."""
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}


VARIANTS: dict[str, Params] = {
    "rcwmil": Params(
        description="Sengar's robust compressive WMIL tracker: sub-region features (2x2 grid, "
        "+1/-1 at 0.78/0.22), weighted-MIL selection of 20 of 100, coarse-to-fine search.",
    ),
    "ct": Params(
        variant="ct", feature_kind="random", num_features=50, num_selected=50, rects_min=2,
        rects_max=3, rect_bounds=(0, 4, 1, 2), weight_mode="sign_sqrt", area_normalize=False,
        neg_inner=8.0, neg_outer=30.0, neg_count=50, neg_sampling="bernoulli",
        learning_rate=0.85, selection="none", coarse_radius=20, coarse_step=1, fine_radius=0,
        description="Compressive tracking (Zhang et al., ECCV 2012): 50 random-rectangle features "
        "on raw sums, all scored; exhaustive search of radius 20.",
    ),
    "fct": Params(
        variant="fct", feature_kind="random", num_features=100, num_selected=100, rects_min=2,
        rects_max=4, rect_bounds=(1, 6, 2, 3), weight_mode="sign", area_normalize=True,
        neg_inner=8.0, neg_outer=30.0, neg_count=50, neg_sampling="bernoulli",
        learning_rate=0.85, selection="none", coarse_radius=25, coarse_step=4, fine_radius=10,
        fine_step=1,
        description="Fast compressive tracking (Zhang et al., TPAMI 2014): 100 area-normalised "
        "features, all scored; coarse (25/4) then fine (10/1) search.",
    ),
    "mil": Params(
        variant="mil", feature_kind="random", num_features=250, num_selected=50, rects_min=2,
        rects_max=6, rect_bounds=(0, 3, 1, 2), weight_mode="uniform", area_normalize=False,
        pos_radius=4.0, neg_inner=9.0, neg_outer=37.5, neg_count=65, neg_sampling="bernoulli",
        init_pos_radius=3.0, init_neg_inner=4.5, init_neg_outer=50.0, init_neg_count=65,
        learning_rate=0.85, classifier="mil", guard=1e-5, selection="milboost",
        instance_weights="uniform", coarse_radius=25, coarse_step=1, fine_radius=0,
        description="Babenko's MILTrack: online MILBoost with a Noisy-OR bag, 50 of 250 Haar "
        "features, exhaustive search of radius 25.",
    ),
    "wmil": Params(
        variant="wmil", feature_kind="random", num_features=150, num_selected=15, rects_min=2,
        rects_max=3, rect_bounds=(0, 4, 1, 3), weight_mode="uniform", area_normalize=False,
        neg_inner=8.0, neg_outer=37.5, neg_count=50, neg_sampling="bernoulli",
        init_neg_inner=6.0, init_neg_outer=50.0, init_neg_count=50, learning_rate=0.85,
        selection="wmil", instance_weights="exp", coarse_radius=25, coarse_step=1, fine_radius=0,
        description="Weighted MIL (Zhang & Song, PR 2013): 15 of 150 features by the weighted "
        "bag's gradient, exhaustive search of radius 25.",
    ),
    "osil": Params(
        variant="osil", instance_weights="uniform", learning_rate=0.85, coarse_radius=20,
        coarse_step=1, fine_radius=0,
        description="Online sparse instance learning (Yan et al.) as the paper describes it: "
        "sub-region features, MIL selection without instance weights, CT's exhaustive search.",
    ),
    "rcwmil-plus": Params(
        variant="rcwmil-plus", colour_weight=0.7, colour_relative=0.0, motion="velocity",
        scale_steps=1,
        scale_factor=1.03, scale_model="both", scale_mix=3.0, scale_penalty=0.2,
        scale_negatives=2, scale_contrast=20.0, score_colour=0.33, score_colour_model="first",
        score_luma=0.33, colour_learning_rate=0.02, colour_sample=16384, gray_colour=True,
        description="rcwmil plus what fast CPU trackers add: a colour likelihood merged into the search "
        "(0.7, against the classifier's confidence relative to the grid's best candidate; "
        "histograms updated at 0.02; on gray video a likelihood of the pixels' luma), a "
        "constant-velocity search "
        "centre, and scale search by scaled Haar rectangles (1.03^-1, 1, 1.03^+1; classifier "
        "score plus a slow target likelihood, penalised away from the current scale, plus 20 x "
        "the box's colour contrast; boxes 1.03^+-2 off learnt as negatives); the reported score"
        " also counts the box's colour and intensity contrast under the first frame's "
        "histograms; the histograms read at most about 16 384 pixels of a region.",
    ),
}


def variants() -> dict[str, Params]:
    """The built-in variants and their default parameters, in a new dict."""
    return dict(VARIANTS)
