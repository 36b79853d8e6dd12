"""Tracker parameters: the public face of every part's settings, one frozen object per variant.

A :class:`Params` is every part's settings class at once (:data:`PARTS`, each in its part's
module), in one flat namespace (``Tracker("fct", num_features=200)``, ``--set key=value``,
``rcwmil:key=value``); each setting is documented and checked by the part class that owns it.
The defaults follow the project's spec of the six paper presets and, for rcwmil, the paper;
:data:`VARIANTS` holds every preset's values.
"""

from __future__ import annotations

import dataclasses
import difflib
from dataclasses import dataclass, field
from typing import Any

from .appearance import AppearanceSettings, SearchSettings
from .classifier import CONFIDENCE_OFFSET, ClassifierSettings
from .colour import ColourSettings
from .cues import check_cue_weights
from .experts import ExpertSettings
from .features import FeatureSettings
from .judge import JudgeSettings
from .motion import MotionSettings
from .policy import ScoreSettings
from .recovery import RecoverySettings
from .sampling import MAX_NEG_RADIUS, MAX_POS_RADIUS, BagSettings
from .scale import ScaleSettings
from .settings import MAX_SEARCH_RADIUS
from .template import TemplateSettings

__all__ = ["CONFIDENCE_OFFSET", "MAX_NEG_RADIUS", "MAX_POS_RADIUS", "MAX_SEARCH_RADIUS", "PARTS",
           "Params", "VARIANTS", "variants"]

#: The part settings a :class:`Params` is made of, in the order their fields are listed.
PARTS: tuple[type[Any], ...] = (FeatureSettings, BagSettings, ClassifierSettings, SearchSettings,
                           ScaleSettings, MotionSettings, ColourSettings, ScoreSettings,
                           TemplateSettings, RecoverySettings, JudgeSettings, ExpertSettings)


@dataclass(frozen=True)
class _Named:
    variant: str = "rcwmil"


@dataclass(frozen=True)
class Params(ExpertSettings, JudgeSettings, RecoverySettings, TemplateSettings, ScoreSettings, ColourSettings,
             MotionSettings, ScaleSettings, AppearanceSettings, _Named):
    """All settings of one tracker variant (defaults: rcwmil, the paper's tracker).

    Every field belongs to one part, which documents and checks it:
    :class:`~wmiltrack.engine.features.FeatureSettings` (the Haar feature bank),
    :class:`~wmiltrack.engine.sampling.BagSettings` (the bags learnt from),
    :class:`~wmiltrack.engine.classifier.ClassifierSettings` (weak classifiers and selection),
    :class:`~wmiltrack.engine.appearance.SearchSettings` (the translation search),
    :class:`~wmiltrack.engine.scale.ScaleSettings` (the scale estimator),
    :class:`~wmiltrack.engine.motion.MotionSettings` (the motion model),
    :class:`~wmiltrack.engine.colour.ColourSettings` (the colour cue),
    :class:`~wmiltrack.engine.policy.ScoreSettings` (the reported score),
    :class:`~wmiltrack.engine.template.TemplateSettings` (the correlation-filter template),
    :class:`~wmiltrack.engine.recovery.RecoverySettings` (the lost state and re-detection),
    :class:`~wmiltrack.engine.judge.JudgeSettings` (the judge of ``ok``) and
    :class:`~wmiltrack.engine.experts.ExpertSettings` (a Siamese network as a second expert).
    The defaults of the last seven leave their part out, so the paper presets run the paper's
    code path.

    Attributes
    ----------
    variant : str
        Name of the variant these settings started from.
    description : str
        One paragraph on the variant (not compared).
    """

    description: str = field(default="", compare=False)

    def __post_init__(self) -> None:
        for part in PARTS:
            part.check(self)  # each part's own checks, on its own fields
        # Settings that tie two parts together.
        if self.selection == "none" and self.num_selected != self.num_features:
            raise ValueError("selection='none' scores every feature: num_selected must equal "
                             "num_features")
        check_cue_weights(self.colour_weight, self.template_weight)
        if self.judge_memory > 0 and not (self.template_weight > 0 or self.template_motion):
            raise ValueError("judge_memory > 0 needs the correlation-filter template "
                             "(template_weight > 0 or template_motion)")
        if (self.judge_gates or self.judge_holds) and self.judge_memory <= 0:
            raise ValueError("judge_gates and judge_holds need the judge (judge_memory > 0)")
        if self.judge_holds and not self.redetect:
            raise ValueError("judge_holds needs the lost state and re-detection (redetect=True)")

    # -- derived values ---------------------------------------------------------------------
    @property
    def search_reach(self) -> int:
        """Largest distance in pixels that one update can move the box from the search origin."""
        reach = self.stage_reach
        if self.scale_steps > 0 and self.scale_model != "dsst":
            reach += self.scale_radius - 1
        return reach

    def replace(self, **changes: Any) -> Params:
        """A copy with some fields changed (validated like the constructor); an unknown name
        is a ``TypeError`` that suggests the nearest valid ones."""
        names = [f.name for f in dataclasses.fields(self) if f.name != "description"]
        unknown = sorted(set(changes) - set(names) - {"description"})
        if unknown:
            hints = []
            for name in unknown:
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
        redetect=True,
        description="rcwmil plus what fast CPU trackers add: a colour likelihood merged into the search "
        "(0.7, against the classifier's confidence relative to the grid's best candidate; "
        "histograms updated at 0.02; on gray video a likelihood of the pixels' luma), a "
        "constant-velocity search "
        "centre, and scale search by scaled Haar rectangles (1.03^-1, 1, 1.03^+1; classifier "
        "score plus a slow target likelihood, penalised away from the current scale, plus 20 x "
        "the box's colour contrast; boxes 1.03^+-2 off learnt as negatives); the reported score"
        " also counts the box's colour and intensity contrast under the first frame's "
        "histograms; the histograms read at most about 16 384 pixels of a region; a lost state "
        "(the classifier's confidence and a grey template's match both fall to 0.6 of their "
        "running means: the last confident box is held with ok False and nothing learns) that "
        "looks for the target over the whole frame by normalised cross-correlation.",
    ),
}
VARIANTS["rcwmil-cf"] = VARIANTS["rcwmil-plus"].replace(
    variant="rcwmil-cf", colour_weight=0.65, template_weight=0.2, template_area=80.0**2,
    template_cell=2, template_channels=10, template_reuse=True, template_gate=0.4,
    scale_dsst=8.0, scale_samples=17, judge_memory=3.0, judge_gates=True, judge_holds=True,
    coarse_radius=37, scale_factor=1.015, scale_steps=2, scale_negatives=4, scale_penalty=0.1,
    scale_min=0.05, scale_max=20.0, template_pool_psr=12.0,
    description="rcwmil-plus with correlation filters on fHOG, for accuracy over speed (about "
    "half its frames per second): a translation filter over the target plus twice its mean side "
    "(Staple's template, 40 x 40 cells of 2 px, its 31 channels compressed to 10 as in ECO, "
    "learning from its own search sample on frames whose score is at least 0.4) merged into the "
    "search at 0.2 beside colour at 0.65 (on frames where the filter's peak-to-sidelobe ratio "
    "is at least 12, each coarse candidate reads the filter's best within half a grid step "
    "of its centre), over a coarse grid of radius 37 (step 4), "
    "and DSST's 1-D scale filter (17 samples over 1.02^-16 .. 1.02^16, as fDSST) voting, at 8 "
    "times its response divided by its peak, in rcwmil-plus's Haar scale search on a finer "
    "ladder (1.015^-2 .. 1.015^2 a frame, penalty 0.1 a step, boxes 1.015^+-4 off learnt as "
    "negatives, sizes 0.05 to 20 times the first box's; learning, as "
    "the translation filter, on frames whose score is at least 0.4); ok is judged with the "
    "first frame's filter as a memory of the target: logistic(8 (score - 0.5) + 3 ln(its peak "
    "/ 0.082)), lost after 3 frames below 0.4, found after 2 above 0.9; while the judge holds "
    "the target for lost nothing learns, and when it turns to lost the tracker enters the lost "
    "state and looks for the target over the whole frame.",
)

VARIANTS["rcwmil-nano"] = VARIANTS["rcwmil-cf"].replace(
    variant="rcwmil-nano", network="nanotrack-v3", likeness_every=3, tracker_every=2,
    description="rcwmil-cf and NanoTrack v3's Siamese network (two ONNX files, run by "
    "onnxruntime or OpenCV's dnn; not shipped: `wmiltrack models fetch nanotrack-v3`) as two "
    "experts under one judge. The network leads; where the two boxes agree (IoU >= 0.3) the box "
    "is 0.8 the network's and 0.2 the tracker's, where they do not the network's; the tracker "
    "learns at that box (moved there at its own size) when the verdict is tracked and the frame "
    "does not count towards lost; after a frame both vouch for where the tracker's own confidence "
    "is at least 0.5, the tracker rests for one frame (the network's box is the frame's, the tracker "
    "is moved there without looking or learning). ok is judged from how alike the network's choice "
    "is to the first frame's target (the cosine of the backbone's feature maps; measured on "
    "every third frame the experts vouch for): lost after 3 frames in a row below 0.45 or below "
    "0.8 of the tracked frames' running mean on which the experts do not agree, found after 2 "
    "above both 0.6 and 0.9 of that mean; while lost, the network keeps its own search, and "
    "after 10 lost frames also searches the tracker's box and 4 windows a frame of a sweep over "
    "the whole frame, moving to one only if it is alike the target and more alike than its "
    "own choice.",
)


def variants() -> dict[str, Params]:
    """The built-in variants and their default parameters, in a new dict."""
    return dict(VARIANTS)
