"""The tracker: an appearance model composed with optional cues, a scale estimator, a motion
model and an update policy.

One frame walks one way: the motion model says where to centre the search -> the cues map the
search region -> the appearance model's coarse and fine candidate scoring (C++), with the cues
merged in -> the scale estimator tries the neighbouring sizes -> the policy scores the frame ->
the appearance model learns from the bags around the new box (C++) -> the cues and the motion
model learn. A preset is a composition plus values (:func:`compose`); one made of the appearance
model alone runs the whole frame in one call to the core.
"""

from __future__ import annotations

import functools
import math
import threading
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Callable, TypeVar

import numpy as np

from .. import _core
from . import copying as _copying  # noqa: F401 (installs deepcopy for the core's objects)
from .appearance import HaarAppearance, roi_around
from .colour import ColourModel
from .cues import ColourCue, Cue, check_cue_weights
from .experts import TwoExperts
from .features import min_box_size
from .frames import IntBox, as_frame, clip_box, frame_size
from .judge import LostJudge
from .motion import VelocityMotion
from .params import Params
from .parts import PART_KINDS, Judge, MotionModel, PartFactory, Recovery, ScaleEstimator
from .policy import ContrastScore, UpdatePolicy, confidence
from .recovery import Redetector
from .requests import Search, Steps, drive, run_batches
from .result import TrackResult
from .scale import HaarScale
from .settings import (
    AppearanceSettings,
    ColourSettings,
    ExpertSettings,
    FeatureSettings,
    FilterLearning,
    JudgeSettings,
    MotionSettings,
    RecoverySettings,
    ScaleSettings,
    ScoreSettings,
    TemplateSettings,
    own,
)
from .template import CorrelationTemplate, DSSTScale, dsst_min_side

__all__ = ["NotInitializedError", "Parts", "Tracker", "check_part_factories", "compose", "confidence",
           "update_many"]


class NotInitializedError(ValueError):
    """``update`` was called before ``init``."""


_F = TypeVar("_F", bound=Callable[..., Any])


def _one_thread_at_a_time(method: _F) -> _F:
    """RuntimeError when another thread is inside a guarded method of the same tracker."""
    @functools.wraps(method)
    def guarded(self: Tracker, *args: Any, **kwargs: Any) -> Any:
        if not self._busy.acquire(False):  # (not blocking; positional: no keyword matching)
            raise RuntimeError(
                "this Tracker is in use by another thread: a Tracker may be used by one thread "
                "at a time (use one Tracker per thread)")
        try:
            return method(self, *args, **kwargs)
        finally:
            self._busy.release()
    return guarded  # type: ignore[return-value]


@dataclass
class Parts:
    """The parts of one started tracker (what :func:`compose` built for its first frame)."""

    appearance: HaarAppearance
    cues: list[Cue]
    scale: ScaleEstimator | None
    motion: MotionModel | None
    policy: UpdatePolicy
    recovery: Recovery | None = None
    judge: Judge | None = None
    template: CorrelationTemplate | None = None  # (the judge reads its first-frame filter)
    experts: TwoExperts | None = None  # a second expert and the judge between the two

    @property
    def appearance_only(self) -> bool:
        """Whether nothing but the appearance model (and the paper's policy) makes up the
        tracker, so that a frame can run as one core call."""
        return (not self.cues and self.scale is None and self.motion is None
                and self.recovery is None and self.policy.plain and self.judge is None
                and self.experts is None)

    @property
    def lost(self) -> bool:
        """Whether the recovery part holds the target for lost (never without one)."""
        return self.recovery is not None and self.recovery.lost

    def others(self) -> list[Any]:
        """The parts besides the appearance model and the policy, each once (a correlation
        template may be both a cue and the motion model), in the order they start."""
        out: list[Any] = []
        for part in (*self.cues, self.motion, self.scale, self.recovery):
            if part is not None and not any(part is seen for seen in out):
                out.append(part)
        return out


def compose(params: Params, seed: int, frame: np.ndarray, box: IntBox,
            cues: Sequence[Cue] = (), parts: Mapping[str, PartFactory] | None = None) -> Parts:
    """The parts that ``params`` asks for, for a tracker started on ``frame`` at ``box``, with
    ``cues`` added after the preset's own and each kind of part in ``parts`` (``"scale"``,
    ``"motion"``, ``"recovery"``: a factory, see :data:`~wmiltrack.engine.parts.PartFactory`)
    made by its factory instead of from ``params``. The appearance model is created but not
    started."""
    appearance = HaarAppearance(own(AppearanceSettings, params), seed, variant=params.variant)
    learning = FilterLearning.of(own(TemplateSettings, params))  # the filters' one rule
    all_cues: list[Cue] = []
    colour: ColourCue | None = None
    if ColourCue.wanted(own(ColourSettings, params), frame):
        colour = ColourCue(own(ColourSettings, params), intensity=not ColourModel.usable(frame))
        all_cues.append(colour)
    template = None
    if params.template_weight > 0 or params.template_motion:
        template = CorrelationTemplate(own(TemplateSettings, params),
                                       remembers=params.judge_memory > 0)
        if params.template_weight > 0:
            all_cues.append(template)
    all_cues.extend(cues)
    fw, fh = frame_size(frame)
    scale: ScaleEstimator | None = None
    if params.scale_steps > 0:
        if params.scale_model == "dsst":
            scale = DSSTScale(own(ScaleSettings, params), (box[2], box[3]), (fw, fh),
                              min_side=dsst_min_side(params.min_box_size), learning=learning)
        else:
            scale = HaarScale(own(ScaleSettings, params), (box[2], box[3]), (fw, fh),
                              min_box=min_box_size(own(FeatureSettings, params)),
                              num_features=params.num_features, learning=learning)
    motion: MotionModel | None = None
    if params.template_motion:
        motion = template
    elif params.motion == "velocity":
        motion = VelocityMotion(own(MotionSettings, params))
    report = None
    if (params.score_colour > 0 and colour is not None) or params.score_luma > 0:
        report = ContrastScore(own(ScoreSettings, params),
                               colour.model if colour is not None else None, None)
    recovery: Recovery | None = (Redetector(own(RecoverySettings, params)) if params.redetect
                                 else None)
    judge = (LostJudge(own(JudgeSettings, params), threshold=params.lost_threshold)
             if params.judge_memory > 0 else None)
    if parts:
        scale = _made(parts, "scale", params, frame, box, scale)
        motion = _made(parts, "motion", params, frame, box, motion)
        recovery = _made(parts, "recovery", params, frame, box, recovery)
    experts = TwoExperts(own(ExpertSettings, params)) if params.network else None
    return Parts(appearance, all_cues, scale, motion,
                 UpdatePolicy(own(ScoreSettings, params), report), recovery, judge, template,
                 experts)


def _made(parts: Mapping[str, PartFactory], kind: str, params: Params, frame: np.ndarray,
          box: IntBox, default: Any) -> Any:
    """The part of ``kind`` made by the user's factory in ``parts`` (checked against the kind's
    interface), else ``default``, the one ``params`` asks for."""
    if kind not in parts:
        return default
    part = parts[kind](params, frame, box)
    if part is not None and not isinstance(part, PART_KINDS[kind]):
        missing = [m for m in _members(PART_KINDS[kind]) if not hasattr(part, m)]
        raise TypeError(f"the {kind} part {part!r} lacks {', '.join(missing)} (see "
                        f"wmiltrack.engine.parts.{PART_KINDS[kind].__name__})")
    return part


def _members(protocol: type[Any]) -> list[str]:
    """The attributes and methods an object needs to be a ``protocol``."""
    names = set(getattr(protocol, "__annotations__", {}))
    names |= {n for n, v in vars(protocol).items() if not n.startswith("_")
              and (callable(v) or isinstance(v, property))}
    return sorted(names)


def check_part_factories(parts: Mapping[str, Any] | None) -> dict[str, PartFactory]:
    """``Tracker(parts=...)`` checked: known kinds, each a callable factory."""
    if parts is None:
        return {}
    if not isinstance(parts, Mapping):
        raise TypeError(f"parts must be a mapping of kind to factory, got {type(parts).__name__}")
    unknown = sorted(set(parts) - set(PART_KINDS))
    if unknown:
        raise ValueError(f"unknown part kind(s) {', '.join(map(repr, unknown))}; the kinds are "
                         f"{', '.join(map(repr, PART_KINDS))}")
    for kind, factory in parts.items():
        if not callable(factory):
            raise TypeError(f"parts[{kind!r}] must be a factory (params, frame, box) -> part, "
                            f"got {factory!r}")
    return dict(parts)


def _start_report(report: ContrastScore, params: Params, frame: np.ndarray, box: IntBox) -> None:
    """Give the reported score its first-frame histograms (after the cues learnt the frame)."""
    if report.colour is not None and params.score_colour > 0 and params.score_colour_model == "first":
        report.colour = report.colour.copy()
    if params.score_luma > 0:
        report.luma = ColourModel(intensity=True, sample=params.colour_sample)
        report.luma.learn(frame, box)


class Tracker:
    """A single-object tracker.

    Parameters
    ----------
    variant : str
        A preset: a key of :func:`wmiltrack.variants`, the preset registry (default
        ``"rcwmil"``, the paper's tracker; ``wmiltrack variants`` lists them all).
    seed : int
        Seed of the random feature bank and negative sampling. The same seed and the same
        frames give identical boxes.
    params : Params, optional
        Start from these parameters instead of the variant's defaults.
    cues : sequence of Cue, optional
        More cues merged into the search (:class:`~wmiltrack.engine.cues.Cue`), after the
        preset's own; their weights, ``colour_weight`` and ``template_weight`` add up to at
        most 1 (:func:`~wmiltrack.engine.cues.check_cue_weights`).
    parts : mapping, optional
        Parts of your own instead of the preset's: ``{"scale": factory, "motion": factory,
        "recovery": factory}`` (any of the three), each factory called at :meth:`init` as
        ``factory(params, frame, box)`` and returning an object with the kind's interface
        (:mod:`wmiltrack.engine.parts`: ``ScaleEstimator``, ``MotionModel``, ``Recovery``), or
        None for no part of that kind. A class whose ``__init__`` takes ``(params, frame,
        box)`` is such a factory.
    **overrides
        Any :class:`~wmiltrack.Params` field, e.g. ``num_selected=30``.

    Notes
    -----
    Threads: a Tracker holds one target's state, so it may be used by one thread at a time;
    ``init``/``update`` called while another thread is inside one of them raise
    ``RuntimeError`` (nothing is changed). Different trackers may run in different threads
    at once (the compiled core releases the GIL and shares no state between them).

    Examples
    --------
    >>> t = Tracker("rcwmil", seed=0)            # doctest: +SKIP
    >>> t.init(frame0, (x, y, w, h))             # doctest: +SKIP
    >>> r = t.update(frame1); r.box, r.score     # doctest: +SKIP
    """

    def __init__(self, variant: str = "rcwmil", *, seed: int = 0, params: Params | None = None,
                 cues: Sequence[Cue] = (), parts: Mapping[str, PartFactory] | None = None,
                 **overrides: Any) -> None:
        if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
            raise ValueError(f"seed must be a non-negative int, got {seed!r}")
        if params is None:
            params = Params.for_variant(variant, **overrides)
        elif overrides:
            params = params.replace(**overrides)
        check_cue_weights(params.colour_weight, params.template_weight, cues)
        self._params = params
        # the search's (radius, step) stages: the coarse grid, then the fine one if any
        self._stages = [(params.coarse_radius, params.coarse_step)]
        if params.fine_radius > 0:
            self._stages.append((params.fine_radius, params.fine_step))
        self._seed = int(seed)
        self._extra_cues = tuple(cues)
        self._part_factories = check_part_factories(parts)
        self._busy = threading.Lock()
        self._initialized = False
        self._frame_wh = (0, 0)
        self._box: IntBox = (0, 0, 0, 0)
        self._score = math.nan
        self._search_log: list[tuple[IntBox, int, int]] = []

    # -- copies: copy.deepcopy(tracker) forks it ------------------------------------------
    def __getstate__(self) -> dict[str, Any]:
        """Everything but the lock that keeps two threads out (a copy gets its own)."""
        state = self.__dict__.copy()
        del state["_busy"]
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._busy = threading.Lock()

    # -- public API ------------------------------------------------------------------------
    @property
    def params(self) -> Params:
        """The parameters in force (frozen)."""
        return self._params

    @property
    def variant(self) -> str:
        """Name of the variant the parameters started from (``"rcwmil"``, ``"ct"``, ...)."""
        return self._params.variant

    @property
    def initialized(self) -> bool:
        """Whether ``init`` has been called, so that ``update`` may be."""
        return self._initialized

    @property
    def parts(self) -> Parts:
        """The parts this tracker is made of (after ``init``)."""
        self._require_init()
        return self._parts

    @property
    def box(self) -> tuple[float, float, float, float]:
        """The current box ``(x, y, w, h)``."""
        self._require_init()
        if self._parts.experts is not None:
            return self._parts.experts.box
        x, y, w, h = self._box
        return float(x), float(y), float(w), float(h)

    @_one_thread_at_a_time
    def init(self, frame: np.ndarray, box: Any) -> None:
        """Start tracking the object in ``box = (x, y, w, h)`` of ``frame``.

        The box is rounded to whole pixels and clipped to the frame; a box wholly outside
        the frame, with non-finite values, non-positive size, or smaller than the variant's
        features need after clipping is a ``ValueError``. Calling ``init`` again restarts
        the tracker (same seed: same result).
        """
        img = as_frame(frame)
        fw, fh = frame_size(img)
        b = clip_box(box, fw, fh)
        parts = compose(self._params, self._seed, img, b, self._extra_cues,
                        self._part_factories)
        model = parts.appearance
        model.start(img, b)
        for part in parts.others():
            part.start(img, b)
        if parts.policy.report is not None:
            _start_report(parts.policy.report, self._params, img, b)
        if parts.experts is not None:
            parts.experts.start(img, (float(b[0]), float(b[1]), float(b[2]), float(b[3])))
        self._parts = parts
        self._frame_wh = (fw, fh)
        self._box = b
        model.compute_integral(img, b, model.first.reach)
        drive(self._learn_steps(model.first))
        self._search_log = []
        self._score = 1.0
        self._ok = self._tracked = True
        self._fused = parts.appearance_only and model.can_fuse
        self._reach = self._params.search_reach + model.reach  # the search's and the bags
        self._initialized = True

    reinit = init

    def search_region(self) -> tuple[int, int, int, int]:
        """The frame region ``(x, y, w, h)`` that the next :meth:`update` reads: its integral
        image covers this rectangle clipped to the frame (what :class:`~wmiltrack.MultiTracker`
        needs to prepare one integral image for several targets)."""
        self._require_init()
        return roi_around(self._origin(), self._margin())

    @property
    def uses_channels(self) -> bool:
        """Whether this tracker's features read other channels than luma (``Params.channels``)."""
        return self._initialized and self._parts.appearance.chan_names is not None

    @_one_thread_at_a_time
    def update(self, frame: np.ndarray, *, integral: _core.IntegralImage | None = None) -> TrackResult:
        """Locate the target in the next frame and learn from it.

        ``integral`` (advanced): a luma integral image of this same frame that covers
        :meth:`search_region` (clipped to the frame), computed once for several trackers; the
        tracker reads it instead of building its own, with the same result. It is ignored when
        it does not cover the region or the tracker uses other channels.

        Returns
        -------
        TrackResult
            ``box`` (x, y, w, h), ``score`` (confidence in [0, 1]: see
            :func:`~wmiltrack.engine.policy.confidence`; rcwmil-plus also counts the box's
            contrast under the first frame's colour and intensity histograms,
            ``Params.score_colour`` / ``score_luma``) and ``ok`` (score >= the variant's
            ``lost_threshold``; False suggests the target is lost or hidden). With
            ``redetect`` (rcwmil-plus), a frame in the lost state has score 0, ``ok``
            False and the last confident box (see
            :class:`~wmiltrack.engine.settings.RecoverySettings`).
        """
        self._require_init()
        img = as_frame(frame)
        result: TrackResult = drive(self._update_steps(img, integral))
        return result

    def track(self, frames: Any, box: Any) -> np.ndarray:
        """Run over an iterable of frames starting with ``box`` on the first; (n, 4) boxes."""
        out = []
        for i, frame in enumerate(frames):
            if i == 0:
                self.init(frame, box)
                out.append(self.box)
            else:
                out.append(self.update(frame).box)
        return np.array(out, dtype=np.float64).reshape(-1, 4)

    def samples(self) -> dict[str, Any]:
        """What the last ``init``/``update`` looked at (read-only copies, for drawing).

        Returns
        -------
        dict
            ``"positive"``, ``"negative"``: top-left corners ``(n, 2)`` of the bags learnt
            from; ``"search"``: one ``(origin_box, radius, step)`` per search stage of the
            last ``update`` (coarse, then fine; empty after ``init``); ``"scales"``: the boxes
            searched at the other scales (empty without scale search); ``"box"``: the box.
        """
        self._require_init()
        pos, neg = self._parts.appearance.corners()
        scale = self._parts.scale
        return {
            "positive": pos.copy(),
            "negative": neg.copy(),
            "search": list(self._search_log),
            "scales": list(scale.tried) if scale is not None else [],
            "box": self._box,
        }

    @property
    def scale(self) -> float:
        """The current box size relative to the first box (1.0 without scale search)."""
        self._require_init()
        return self._parts.scale.scale if self._parts.scale is not None else 1.0

    def __repr__(self) -> str:
        state = f"box={self._box}" if self._initialized else "not initialised"
        return f"Tracker({self._params.variant!r}, seed={self._seed}, {state})"

    # -- one frame -------------------------------------------------------------------------
    def _update_steps(self, img: np.ndarray, integral: _core.IntegralImage | None) -> Steps:
        """:meth:`update` on a checked frame, as a generator of core requests (see
        :data:`~wmiltrack.engine.requests.Steps`): a lost target's frame
        (:meth:`_redetect_steps`) or a tracked one (:meth:`_tracked_steps`), then the one end
        of a frame (:meth:`_report`)."""
        self._check_frame(img)
        previous = self._box
        if self._parts.lost:
            self._score = yield from self._redetect_steps(img, previous)
        else:
            self._score = yield from self._tracked_steps(img, integral, previous)
        result = self._report()
        if self._parts.experts is not None:  # the second expert, and the judge of the two
            return self._parts.experts.step(img, result, self.recentre)
        return result

    def recentre(self, box: Any) -> None:
        """Move the target to the centre of ``box = (x, y, w, h)`` keeping its current size and
        everything learnt (the models, the first-frame memories; a lost state ends): how
        another expert hands the target over (:mod:`wmiltrack.engine.experts`). Unlike
        :meth:`init`, nothing is relearnt."""
        self._require_init()
        x, y, w, h = (float(v) for v in box)
        _, _, bw, bh = self._box
        fw, fh = self._frame_wh
        nx = min(max(int(round(x + w / 2 - bw / 2)), 0), max(fw - bw, 0))
        ny = min(max(int(round(y + h / 2 - bh / 2)), 0), max(fh - bh, 0))
        self._box = (nx, ny, bw, bh)
        if self._parts.recovery is not None and self._parts.recovery.lost:
            self._parts.recovery.lost, self._parts.recovery.frames_lost = False, 0

    def _tracked_steps(self, img: np.ndarray, integral: _core.IntegralImage | None,
                       previous: IntBox) -> Steps:
        """A frame of a tracked target, stage by stage: locate (the motion model's origin, the
        search with the cues merged), scale, judge, learn; returns the frame's score. A paper
        preset (the appearance model alone, which reads luma only and has no other part to
        consult) runs the locate and learn stages as one core call
        (:meth:`~wmiltrack.engine.appearance.HaarAppearance.fused_request`), then the
        verdict. ``integral``: a shared luma table of this frame, borrowed for the frame if it covers
        the search."""
        model = self._parts.appearance
        origin = self._origin(img)
        margin = self._margin()
        own = model.ii
        shared = integral is not None and model.covered_by(integral, roi_around(origin, margin),
                                                           self._frame_wh)
        if shared:
            assert integral is not None
            model.ii = integral
        try:
            search = self._search(img, origin, self._stages, margin, shared=shared)
            if self._fused:  # locate and learn as one core call, then judge
                answer = yield model.fused_request(search, origin)
                raw = self._move(origin, self._stages, model.take_fused(answer))
                score = confidence(raw, model.k, self._params.confidence_offset)
                self._verdict(score, None)
                return score
            raw = self._move(origin, self._stages, (yield search))  # locate
            raw = self._rescale(img, raw)                             # scale
            conf = confidence(raw, model.k, self._params.confidence_offset)
            score = self._parts.policy.score(conf, img, self._box)
            if self._judge(img, conf, score, previous):               # judge
                return 0.0  # (the score of a frame in the lost state)
            yield from self._learn_all(img, score)                    # learn
            if self._parts.motion is not None:
                self._parts.motion.follow(previous, self._box, self._parts.policy.tracked(conf))
            return score
        finally:
            model.ii = own  # a shared table is only borrowed for this frame

    def _rescale(self, img: np.ndarray, raw: float) -> float:
        """The scale stage: the scale estimator tries other sizes around the located box
        (when the search found one); the raw score to report."""
        scale = self._parts.scale
        if scale is not None:
            scale.tried = []
            if math.isfinite(raw):
                self._box, raw = scale.search(self._parts.appearance, img, self._box, raw,
                                              self._contrast())
        return raw

    def _judge(self, img: np.ndarray, conf: float, score: float, previous: IntBox) -> bool:
        """The judge stage: whether the frame counts as tracked (:meth:`_verdict`), and
        whether it starts the lost state, by the recovery part (the box goes back to
        ``previous``) or by the judge of ``ok`` with ``judge_holds`` (the box stays): then
        True, the box is held and nothing learns."""
        parts = self._parts
        if parts.recovery is not None and parts.recovery.judge(conf, img, self._box,
                                                               self._witnesses()):
            self._hold(previous)  # the target is lost from this frame on
            self._verdict(0.0, img)
            return True
        self._verdict(score, img)
        judge = parts.judge
        if (judge is not None and judge.lost and judge.turned and self._params.judge_holds
                and parts.recovery is not None):
            parts.recovery.lost, parts.recovery.frames_lost = True, 1  # look for it again
            self._hold(self._box)
            return True
        return False

    def _verdict(self, score: float, img: np.ndarray | None) -> None:
        """Whether the frame ``img`` of this score counts as tracked: the policy's threshold,
        or the judge's verdict (which keeps its own history). Once per frame, before
        learning."""
        parts = self._parts
        if parts.judge is not None and parts.template is not None and img is not None:
            self._tracked = parts.judge.verdict(score, parts.template.first_peak_on(img))
        else:
            self._tracked = parts.policy.tracked(score)

    def _report(self) -> TrackResult:
        """The end of a frame: its result, the box, the score, and ``ok`` from its verdict and
        the lost state."""
        self._ok = self._tracked and not self._parts.lost
        x, y, w, h = self._box
        return TrackResult((float(x), float(y), float(w), float(h)), self._score, self._ok)

    def _learn_all(self, img: np.ndarray, score: float) -> Steps:
        """Every part learns from the frame at the current box (none while the judge, with
        ``judge_gates``, holds the target for lost)."""
        parts = self._parts
        if parts.judge is not None and parts.judge.lost and self._params.judge_gates:
            parts.appearance.skip_learning()
            return
        yield from self._learn_steps(parts.appearance.track)
        for cue in parts.cues:
            if score >= getattr(cue, "learn_above", 0.0):
                cue.learn(img, self._box)
        if parts.scale is not None and score >= parts.scale.learn_above:
            parts.scale.learn(img, self._box)
        if parts.recovery is not None:
            parts.recovery.learn(img, self._box)

    def _hold(self, box: IntBox) -> None:
        """A lost frame: the box stays at ``box`` (the last confident one) and nothing
        learns."""
        self._box = box
        self._parts.appearance.skip_learning()
        if self._parts.motion is not None:
            self._parts.motion.follow(box, box, False)

    def _redetect_steps(self, img: np.ndarray, previous: IntBox) -> Steps:
        """A frame of the lost state. First the usual search around the last confident box
        (the classifier with every cue): if its confidence is back, tracking resumes there.
        Else the whole frame is searched for the target's template
        (:meth:`~wmiltrack.engine.recovery.Redetector.find`) and, where it matches well
        enough, the fine search places the box. Either way every part then learns from the
        box; if neither finds the target the last confident box is held and nothing learns.
        Returns the frame's score (0 for a held frame)."""
        parts, model, p = self._parts, self._parts.appearance, self._params
        recovery = parts.recovery
        assert recovery is not None
        if parts.scale is not None:
            parts.scale.tried = []
        raw = yield from self._search_from(img, previous, self._stages)
        conf = confidence(raw, model.k, p.confidence_offset)
        if not recovery.back(conf, img, self._box):
            found = recovery.find(img)
            if found is None:
                self._hold(previous)
                self._verdict(0.0, img)
                return 0.0
            stages = [(p.fine_radius, p.fine_step)] if p.fine_radius > 0 else self._stages
            raw = yield from self._search_from(img, found, stages)
            conf = confidence(raw, model.k, p.confidence_offset)
        score = parts.policy.score(conf, img, self._box)
        self._verdict(score, img)
        yield from self._learn_all(img, score)
        if parts.motion is not None:  # a jump back is not a velocity
            parts.motion.follow(self._box, self._box, False)
        return score

    def _witnesses(self) -> list[float]:
        """The cues' own confidences of this frame (those that give one; see
        :class:`~wmiltrack.engine.cues.Cue`)."""
        out = []
        for cue in self._parts.cues:
            value = getattr(cue, "confidence", math.nan)
            if math.isfinite(value):
                out.append(float(value))
        return out

    def _search_from(self, img: np.ndarray, origin: IntBox, stages: list[tuple[int, int]]
                     ) -> Steps:
        """The classifier's search from ``origin`` over ``stages`` with every cue merged (its
        own integral image); moves the box and returns the raw score (see :meth:`_move`)."""
        search = self._search(img, origin, stages, self._margin())
        raw: float = self._move(origin, stages, (yield search))
        return raw

    def _search(self, img: np.ndarray, origin: IntBox, stages: list[tuple[int, int]],
                margin: int, *, shared: bool = False) -> Search:
        """The core's search request from ``origin`` over ``stages`` (the one place a frame's
        search is built): the appearance model makes its integral image ready (``margin``
        pixels around ``origin``; with ``shared``, the borrowed one it holds), then the cues
        give their tables (:meth:`_cue_tables`), which the search merges in."""
        model = self._parts.appearance
        frame, roi = model.prepare(None if shared else img, origin, margin)
        return model.search_request(origin, stages, self._frame_wh, frame, roi,
                                    self._cue_tables(img, origin))

    def _origin(self, frame: np.ndarray | None = None) -> IntBox:
        """Where the search on ``frame`` is centred (without the frame: the motion model's
        guess before seeing it)."""
        motion = self._parts.motion
        return self._box if motion is None else motion.origin(self._box, frame)

    def _margin(self) -> int:
        """The integral image's margin around the search origin."""
        scale = self._parts.scale
        if scale is None:
            return self._reach
        return self._reach + scale.margin(self._box)

    def _cue_tables(self, img: np.ndarray, origin: IntBox) -> tuple[Any, ...] | None:
        """The cues' merged table for the core's search from ``origin``, or None without
        cues."""
        cues = self._parts.cues
        if not cues:
            return None
        x, y, w, h = origin
        m = self._params.search_reach + 1
        region = (x - m, y - m, x + w + m, y + h + m)
        # a map read at the candidates' centres (x + dx + w // 2, ...) need only cover those
        centres = (x + w // 2 - m, y + h // 2 - m, x + w // 2 + m + 1, y + h // 2 + m + 1)
        tables = []
        for c in cues:
            at_centre = getattr(c, "at_centre", False)
            table = c.table(img, centres if at_centre else region)
            tables.append((*table, c.weight, at_centre, at_centre and getattr(c, "pooled", False)))
        rel = self._params.colour_relative
        offset = self._params.confidence_offset if rel is None else -rel
        return tables, offset, rel is not None

    def _contrast(self) -> Callable[[IntBox], float] | None:
        """The colour cue's box contrast on this frame's table, for the scale estimator."""
        for cue in self._parts.cues:
            if isinstance(cue, ColourCue):
                return cue.contrast
        return None

    def _move(self, origin: IntBox, stages: list[tuple[int, int]],
              results: Sequence[tuple[int, int, float, int]]) -> float:
        """Move the box from ``origin`` by a search's per-stage ``(dx, dy, score, n)``; the
        raw score of the last stage that had candidates (-inf if none had)."""
        best = -math.inf
        self._box = origin
        self._search_log = []
        for (radius, step), (dx, dy, score, n) in zip(stages, results):
            self._search_log.append((self._box, radius, step))
            if n == 0:  # no candidate fitted in the frame: stay
                continue
            x, y, w, h = self._box
            self._box = (x + dx, y + dy, w, h)
            best = score
        return best

    def _learn_steps(self, sampler: Any) -> Steps:
        """The appearance model's learning at the current box, with the scale estimator's
        extras (wrong-scale negatives, its own target model)."""
        parts = self._parts
        extra, n_extra, second = (None, 0, None)
        if parts.scale is not None:
            extra, n_extra, second = parts.scale.learning_extras(parts.appearance, self._box)
        learnt = yield from parts.appearance.learn_steps(self._box, self._frame_wh, sampler, extra,
                                                         n_extra, second)
        if parts.scale is not None:
            parts.scale.take_learnt(learnt, len(parts.appearance.corners()[0]))

    def _check_frame(self, img: np.ndarray) -> None:
        wh = frame_size(img)
        if wh != self._frame_wh:
            raise ValueError(
                f"frame size changed from {self._frame_wh[0]}x{self._frame_wh[1]} to {wh[0]}x{wh[1]}; "
                "call init() to restart on frames of the new size"
            )

    def _require_init(self) -> None:
        if not self._initialized:
            raise NotInitializedError("call init(frame, box) before update(frame)")


def update_many(trackers: list[Tracker], frame: np.ndarray, *,
                integral: _core.IntegralImage | None = None,
                threads: int = 1) -> list[TrackResult | Exception]:
    """:meth:`Tracker.update` of several trackers on one frame, their core work in parallel.

    Every tracker runs its own frame step, unchanged (the same boxes as ``update``), but the
    requests they make to the core at the same point of the step (a paper preset's whole step;
    for the others the integral image and search, then the learning step) go to the core
    together and run on up to ``threads`` threads with the GIL released, instead of once per
    tracker and call. ``integral``: as for :meth:`Tracker.update`, a luma table of this frame
    the trackers may borrow. Returns, in order, each tracker's :class:`TrackResult` or the
    ``ValueError``/``TypeError`` its update raised (the others are not affected); a tracker in
    use by another thread gets a ``RuntimeError``.
    """
    img = as_frame(frame)
    out: list[TrackResult | Exception | None] = [None] * len(trackers)
    locked: list[Tracker] = []
    active: dict[int, tuple[Steps, tuple[Any, ...]]] = {}

    def advance(i: int, steps: Steps, value: Any, first: bool = False) -> None:
        try:
            request = next(steps) if first else steps.send(value)
            active[i] = (steps, request)
        except StopIteration as stop:
            out[i] = stop.value
            active.pop(i, None)
        except (ValueError, TypeError) as exc:
            out[i] = exc
            active.pop(i, None)

    try:
        for i, t in enumerate(trackers):
            if not t._busy.acquire(blocking=False):
                out[i] = RuntimeError("this Tracker is in use by another thread")
                continue
            locked.append(t)
            try:
                t._require_init()
            except NotInitializedError as exc:
                out[i] = exc
                continue
            advance(i, t._update_steps(img, integral), None, first=True)
        while active:
            results = run_batches({i: request for i, (_, request) in active.items()}, threads)
            for i in list(active):
                advance(i, active[i][0], results[i])
    finally:
        for t in locked:
            t._busy.release()
    return [r if r is not None else RuntimeError("no result") for r in out]

