"""The tracker: an appearance model composed with optional cues, a scale estimator, a motion
model, the reported score's policy, a recovery part and a judge.

One frame walks one way, through one list of stages (:attr:`Tracker.stages`), each taking the
frame's immutable record (:class:`~wmiltrack.engine.state.FrameState`) and returning the next:
locate (the motion model's origin, the cues' maps, the appearance model's coarse and fine
candidate scoring in C++; then a second expert's own search, its evidence into the record) ->
rescale (the scale estimator) -> score (the confidence, the policy's reported score) ->
recover (a lost target looked for over the whole frame) -> judge (every expert's evidence
weighed: the one verdict, tracked, doubtful, lost or found, the frame's box and what learns)
-> learn (at the frame's box, if the verdict lets it: the appearance model's bags in C++, the
cues, the scale estimator, the recovery part) -> follow (the motion model, a second expert).
A tracked target's frame, a lost target's frame and a paper preset's frame take the same
stages; a preset made of the appearance model alone locates and learns in one core call. A
preset is a composition plus values (:func:`compose`).
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
from .appearance import AppearanceSettings, HaarAppearance
from .colour import ColourModel, ColourSettings
from .cues import ColourCue, Cue, check_cue_weights
from .experts import ExpertSettings, NetworkExpert, network_files
from .frames import IntBox, as_frame, clip_box, frame_size
from .geometry import placed_at, roi_around
from .judge import NO_EVIDENCE, Evidence, FrameJudge, JudgeSettings
from .motion import MotionSettings, VelocityMotion
from .params import Params
from .parts import (
    PART_KINDS,
    PART_SETTINGS,
    Judge,
    MotionModel,
    PartFactory,
    Recovery,
    ScaleEstimator,
    ScorePolicy,
    SecondExpert,
)
from .policy import ContrastScore, ReportedScore, ScoreSettings, confidence
from .recovery import RecoverySettings, Redetector
from .requests import Search, Steps, drive, run_batches
from .result import TrackResult
from .scale import DSSTScale, HaarScale, ScaleSettings
from .settings import own
from .state import FrameState, SearchStage, Verdict, new_frame
from .template import CorrelationTemplate, TemplateSettings

__all__ = ["NotInitializedError", "Parts", "Tracker", "check_part_factories", "compose", "confidence",
           "update_many"]


#: The pixels of a record kept between frames: none (the tracker holds no frame).
_NO_FRAME = np.zeros((0, 0), dtype=np.uint8)
_NO_FRAME.setflags(write=False)
_LOST = Verdict.LOST  # (an enum member read from its class costs ~70 ns, this name ~10 ns)
_TRACKED = Verdict.TRACKED


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
    policy: ScorePolicy
    judge: Judge
    recovery: Recovery | None = None
    template: CorrelationTemplate | None = None  # (its first-frame filter's peak: evidence)
    expert: SecondExpert | None = None  # a second expert beside the tracker (rcwmil-nano)

    @property
    def appearance_only(self) -> bool:
        """Whether nothing but the appearance model (with the paper's score and a judge that
        lets every frame learn) makes up the tracker, so that a frame can run as one core
        call."""
        return (not self.cues and self.scale is None and self.motion is None
                and self.recovery is None and self.policy.plain
                and isinstance(self.judge, FrameJudge) and self.judge.always_learns
                and self.expert is None)

    def others(self) -> list[Any]:
        """The parts besides the appearance model and the policy, each once (a correlation
        template may be both a cue and the motion model), in the order they start."""
        out: list[Any] = []
        for part in (*self.cues, self.motion, self.scale, self.recovery, self.judge, self.expert):
            if part is not None and not any(part is seen for seen in out):
                out.append(part)
        return out


def compose(params: Params, seed: int, frame: np.ndarray, box: IntBox,
            cues: Sequence[Cue] = (), parts: Mapping[str, PartFactory] | None = None) -> Parts:
    """The parts that ``params`` asks for, for a tracker started on ``frame`` at ``box``, with
    ``cues`` added after the preset's own and each kind of part in ``parts`` (a factory, see
    :data:`~wmiltrack.engine.parts.PartFactory`) made by its factory, from its own settings,
    instead of from ``params``. The appearance model is created but not started."""
    parts = parts or {}
    if "appearance" in parts:
        appearance = _made(parts, "appearance", params, frame, box, None, seed=seed)
    else:
        appearance = HaarAppearance(own(AppearanceSettings, params), seed, variant=params.variant)
    all_cues: list[Cue] = []
    colour: ColourCue | None = None
    if ColourCue.wanted(own(ColourSettings, params), frame):
        colour = ColourCue(own(ColourSettings, params), intensity=not ColourModel.usable(frame))
        all_cues.append(colour)
    template = None
    if params.template_weight > 0 or params.template_motion:
        template = CorrelationTemplate(own(TemplateSettings, params))
        if params.template_weight > 0:
            all_cues.append(template)
    all_cues.extend(cues)
    motion: MotionModel | None = None
    if params.template_motion:
        motion = template
    elif params.motion == "velocity":
        motion = VelocityMotion(own(MotionSettings, params))
    report = None
    if (params.score_colour > 0 and colour is not None) or params.score_luma > 0:
        report = ContrastScore(own(ScoreSettings, params), colour=colour is not None)
    recovery: Recovery | None = (Redetector(own(RecoverySettings, params)) if params.redetect
                                 else None)
    return Parts(appearance, all_cues,
                 _made(parts, "scale", params, frame, box, _scale_part(params, frame, box)),
                 _made(parts, "motion", params, frame, box, motion),
                 _made(parts, "policy", params, frame, box,
                       ReportedScore(own(ScoreSettings, params), report)),
                 _made(parts, "judge", params, frame, box, FrameJudge(own(JudgeSettings, params))),
                 _made(parts, "recovery", params, frame, box, recovery), template,
                 _made(parts, "expert", params, frame, box, _network(params, parts)))


def _network(params: Params, parts: Mapping[str, PartFactory]) -> SecondExpert | None:
    """The second expert ``params`` asks for (a network; None without one, or when ``parts``
    supplies the expert)."""
    if not params.network or "expert" in parts:
        return None
    return NetworkExpert(own(ExpertSettings, params))


def _scale_part(params: Params, frame: np.ndarray, box: IntBox) -> ScaleEstimator | None:
    """The scale estimator ``params`` asks for (None without scale search)."""
    if params.scale_steps <= 0:
        return None
    kind = DSSTScale if params.scale_model == "dsst" else HaarScale
    return kind(own(ScaleSettings, params), (box[2], box[3]), frame_size(frame))


def _made(parts: Mapping[str, PartFactory], kind: str, params: Params, frame: np.ndarray,
          box: IntBox, default: Any, **more: Any) -> Any:
    """The part of ``kind`` made by the user's factory in ``parts`` from the kind's own
    settings (checked against the kind's interface), else ``default``, the one ``params``
    asks for."""
    if kind not in parts:
        return default
    part = parts[kind](own(PART_SETTINGS[kind], params), frame, box, **more)
    if part is None and kind in _REQUIRED:
        raise TypeError(f"the {kind} part's factory returned None: a tracker needs one")
    if part is not None and not isinstance(part, PART_KINDS[kind]):
        missing = [m for m in _members(PART_KINDS[kind]) if not hasattr(part, m)]
        raise TypeError(f"the {kind} part {part!r} lacks {', '.join(missing) or 'the class'} "
                        f"(see wmiltrack.engine.parts.PART_KINDS[{kind!r}])")
    return part


#: The kinds of part every tracker has (a factory may not leave them out).
_REQUIRED = ("appearance", "policy", "judge")


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
        Parts of your own instead of the preset's, by kind: ``"appearance"``, ``"policy"``,
        ``"judge"``, ``"scale"``, ``"motion"``, ``"recovery"``, ``"expert"``; each a factory called at
        :meth:`init` as ``factory(settings, frame, box)`` with the kind's own settings
        (:data:`~wmiltrack.engine.parts.PART_SETTINGS`; an appearance model's factory also
        gets ``seed=``), returning an object with the kind's interface
        (:data:`~wmiltrack.engine.parts.PART_KINDS`), or None for no scale estimator, motion
        model, re-detection or second expert. A class whose ``__init__`` takes ``(settings, frame, box)`` is
        such a factory.
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
        if params.network:  # its model files are checked now, not at the first frame
            network_files(own(ExpertSettings, params))
        self._params = params
        # the search's (radius, step) grids: the coarse one, then the fine one if any
        self._grids = [(params.coarse_radius, params.coarse_step)]
        if params.fine_radius > 0:
            self._grids.append((params.fine_radius, params.fine_step))
        self._seed = int(seed)
        self._extra_cues = tuple(cues)
        self._part_factories = check_part_factories(parts)
        self._busy = threading.Lock()
        self._initialized = False
        self._frame_wh = (0, 0)
        # (stages, the stages a frame walks) for those stages: _stages_walked
        self._walk: tuple[tuple[Any, ...], tuple[Any, ...]] | None = None

    # -- copies: copy.deepcopy(tracker) forks it ------------------------------------------
    def __getstate__(self) -> dict[str, Any]:
        """Everything but the lock that keeps two threads out (a copy gets its own) and the last
        frame's pixels."""
        state = self.__dict__.copy()
        del state["_busy"]
        state.pop("_walk", None)  # worked out again (it may hold a subclass's stages)
        if "_last" in state:  # the last frame's pixels are not part of the tracker's state
            state["_last"] = state["_last"].evolve(frame=_NO_FRAME, integral=None)
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._busy = threading.Lock()
        self._walk = None

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
        return _result(self._last).box

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
        parts.policy.start(img, b)
        self._parts = parts
        self._frame_wh = (fw, fh)
        model.compute_integral(img, b, model.first_sampler.reach)
        drive(self._learn_steps(model.first_sampler, b))
        # the first frame's record: the given box, tracked with score 1
        self._last = FrameState(_NO_FRAME, b, False, None, b, b, score=1.0,
                                verdict=Verdict.TRACKED, ok=True, learns=True)
        self._fused = parts.appearance_only and model.can_fuse
        self._rest_every = self._params.tracker_every if parts.expert is not None else 1
        self._walk = None  # parts of another kind may lack other stages
        self._reach = self._params.search_reach + model.reach  # the search's and the bags
        self._initialized = True

    reinit = init

    def search_region(self) -> tuple[int, int, int, int]:
        """The frame region ``(x, y, w, h)`` that the next :meth:`update` reads: its integral
        image covers this rectangle clipped to the frame (what :class:`~wmiltrack.MultiTracker`
        needs to prepare one integral image for several targets)."""
        self._require_init()
        box = self._last.box
        return roi_around(self._origin(None, box), self._margin(box))

    @property
    def lost(self) -> bool:
        """Whether the target is held for lost after the last frame (the next :meth:`update`
        looks for it again): the frame's verdict."""
        self._require_init()
        return self._last.verdict is Verdict.LOST

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
            :class:`~wmiltrack.engine.recovery.RecoverySettings`).
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
            searched at the other scales (empty without scale search); ``"box"``: the frame's
            box, as :meth:`update` reported it (the judge's from a second expert's, where it took it).
        """
        self._require_init()
        pos, neg = self._parts.appearance.corners()
        last = self._last
        return {
            "positive": pos.copy(),
            "negative": neg.copy(),
            "search": list(last.searched),
            "scales": list(last.tried),
            "box": _result(last).box,
        }

    @property
    def scale(self) -> float:
        """The current box size relative to the first box (1.0 without scale search)."""
        self._require_init()
        return self._parts.scale.scale if self._parts.scale is not None else 1.0

    def __repr__(self) -> str:
        state = f"box={_result(self._last).box}" if self._initialized else "not initialised"
        return f"Tracker({self._params.variant!r}, seed={self._seed}, {state})"

    # -- one frame -------------------------------------------------------------------------
    def _update_steps(self, img: np.ndarray, integral: _core.IntegralImage | None) -> Steps:
        """:meth:`update` on a checked frame, as a generator of core requests (see
        :data:`~wmiltrack.engine.requests.Steps`): the frame's record
        (:class:`~wmiltrack.engine.state.FrameState`) walks through :attr:`stages` in order,
        each stage returning the next record (or a generator of core requests that returns
        it); the last record is kept as the tracker's state and read out as the result. A
        tracked target's frame, a lost target's and a paper preset's one-call frame take the
        same stages; each stage reads from the record which of them it is on."""
        self._check_frame(img)
        last = self._last
        state = new_frame(img, last, integral)
        if self._rests(last):
            state = state.evolve(rested=last.rested + 1, raw=last.raw, conf=last.conf,
                                 score=last.score)
        model = self._parts.appearance
        own_table = model.ii
        try:
            for stage in self._stages_walked():
                out = stage(self, state)
                state = out if isinstance(out, FrameState) else (yield from out)
        finally:
            model.ii = own_table  # a shared integral image is only borrowed for the frame
        self._last = state  # (copies and pickles leave its pixels out: __getstate__)
        return _result(state)

    def _rests(self, last: FrameState) -> bool:
        """Whether the tracker rests on the frame after ``last`` (a second expert's
        ``tracker_every``): the judge found the experts vouching for ``last`` (tracked), the
        tracker's own confidence there was at least ``lost_threshold`` (``steady``), and it
        has not yet rested ``tracker_every - 1`` frames in a row."""
        return (self._rest_every > 1 and last.vouched and last.steady
                and last.verdict is _TRACKED and last.rested + 1 < self._rest_every)

    def _stages_walked(self) -> tuple[Callable[[Tracker, FrameState], FrameState | Steps], ...]:
        """:attr:`stages` less those of the parts this tracker lacks (rescale without a scale
        estimator, recover without re-detection, follow without a motion model or a second
        expert, a second expert's locate without one: each would hand the record back
        unchanged: a call a frame saved), worked out again when ``stages`` changes."""
        stages, walk = self.stages, self._walk
        if walk is None or walk[0] is not stages:
            parts = self._parts
            needs: dict[Any, Any] = {Tracker._rescale: parts.scale, Tracker._recover: parts.recovery,
                                     Tracker._follow: parts.motion or parts.expert,
                                     Tracker._locate_expert: parts.expert}
            walk = self._walk = (stages, tuple(s for s in stages if needs.get(s, s) is not None))
        return walk[1]

    def recentre(self, box: Any) -> None:
        """Move the target to the centre of ``box = (x, y, w, h)`` keeping its current size and
        everything learnt (the models, the first-frame memories; a lost state ends), as the
        judge does when another expert hands the target over. Unlike :meth:`init`, nothing is
        relearnt."""
        self._require_init()
        state = self._last
        if state.verdict is Verdict.LOST:
            state = state.evolve(verdict=Verdict.TRACKED, lost_for=0)
        self._last = state.evolve(box=placed_at(state.box, box, *self._frame_wh), exact=None)

    def _locate(self, state: FrameState) -> Steps:
        """Locate: the search with the cues merged, from the motion model's origin (a lost
        target's frame: from the last confident box). A paper preset (the appearance model
        alone, reading luma only, with no other part to consult) locates and learns in one
        core call (:meth:`~wmiltrack.engine.appearance.HaarAppearance.fused_request`). The
        frame's shared luma table (``integral``) is borrowed if it covers the search."""
        if state.lost:
            return (yield from self._search_at(state, state.previous, self._grids))
        if state.rested:  # (the tracker rests: its box stays where the last frame put it)
            return state
        img, model = state.frame, self._parts.appearance
        origin = self._origin(img, state.previous)
        margin = self._margin(state.previous)
        shared = state.integral is not None and model.covered_by(
            state.integral, roi_around(origin, margin), self._frame_wh)
        if shared:
            model.ii = state.integral  # (given back by _update_steps)
        search = self._search(img, origin, self._grids, margin, shared=shared)
        if self._fused:
            results = model.take_fused((yield model.fused_request(search, origin)))
        else:
            results = yield search
        box, raw, searched = _moved(origin, self._grids, results)
        return state.located(origin, box, raw, searched, self._fused)

    def _locate_expert(self, state: FrameState) -> FrameState:
        """Locate (the second expert): its own search on the frame, beside the tracker's; its
        evidence (box, likeness) goes into the record for the judge."""
        expert = self._parts.expert
        if expert is None:
            return state
        return state.evolve(expert=expert.locate(state))

    def _rescale(self, state: FrameState) -> FrameState:
        """Rescale: the scale estimator tries other sizes around the located box (on a tracked
        target's frame whose search found a candidate)."""
        scale = self._parts.scale
        if scale is None or state.lost or state.rested or not math.isfinite(state.raw):
            return state
        box, raw = scale.search(self._parts.appearance, state.frame, state.box, state.raw,
                                self._contrast())
        return state.evolve(box=box, raw=raw, tried=tuple(scale.tried))

    def _score(self, state: FrameState) -> FrameState:
        """Score: the classifier's confidence at the box and the score to report (the
        policy's)."""
        if state.rested:  # (the last frame's score stands)
            return state
        parts = self._parts
        conf = confidence(state.raw, parts.appearance.k, self._params.confidence_offset)
        return state.scored(conf, parts.policy.score(conf, state.frame, state.box))

    def _recover(self, state: FrameState) -> FrameState | Steps:
        """Recover: on a lost target's frame where the judge does not see the target back at
        the located box, the recovery part looks for it over the whole frame; where it
        matches well enough the fine search places the box (``rescued``)."""
        recovery = self._parts.recovery
        if (not state.lost or recovery is None
                or self._parts.judge.back(state, self._evidence(state))):
            return state
        found = recovery.find(state.frame, state.lost_for)
        if found is None:
            return state
        return self._found_steps(state, found)

    def _found_steps(self, state: FrameState, found: IntBox) -> Steps:
        """The recover stage's search from the box the recovery part ``found``, then the
        frame's score there."""
        p = self._params
        grids = [(p.fine_radius, p.fine_step)] if p.fine_radius > 0 else self._grids
        state = yield from self._search_at(state, found, grids)
        return self._score(state).evolve(rescued=True)

    def _judge(self, state: FrameState) -> FrameState:
        """Judge: the judge's verdict on the frame (:class:`~wmiltrack.engine.parts.Judge`),
        from the record and the other parts' evidence; the count of frames lost."""
        evidence = NO_EVIDENCE if state.rested else self._evidence(state)
        state = self._parts.judge.verdict(state, evidence)
        if state.verdict is _LOST:
            return state.evolve(lost_for=state.lost_for + 1)
        return state.evolve(lost_for=0) if state.lost_for else state

    def _evidence(self, state: FrameState) -> Evidence:
        """What the judge weighs besides the record: the cues' own confidences, the
        recovery's likeness of the box to the target, the first-frame filter's peak."""
        parts = self._parts
        if not parts.cues and parts.recovery is None and parts.template is None:
            return NO_EVIDENCE
        recovery, template = parts.recovery, parts.template
        return Evidence(
            self._witnesses(),
            None if recovery is None else functools.partial(recovery.likeness, state.frame,
                                                            state.box),
            math.nan if template is None else template.first_peak_on(state.frame))

    def _learn(self, state: FrameState) -> FrameState | Steps:
        """Learn: every part learns from the frame at its box, if the judge lets it (the
        appearance model of a one-call frame has learnt already)."""
        if state.learnt:
            return state
        if not state.learns or state.rested:
            self._parts.appearance.skip_learning()
            return state
        return self._learn_all(state)

    def _learn_all(self, state: FrameState) -> Steps:
        """The learn stage's work: the appearance model (one core request), the cues and the
        scale estimator (from frames of a high enough score) and the recovery part."""
        parts, img, box = self._parts, state.frame, state.box
        if state.exact is not None:  # (the judge may have moved the box: a second expert's frame)
            self._cover(state, box)
        yield from self._learn_steps(parts.appearance.sampler, box)
        for cue in parts.cues:
            if state.score >= getattr(cue, "learn_above", 0.0):
                cue.learn(img, box)
        parts.policy.learn(img, box)
        if parts.scale is not None and state.score >= parts.scale.learn_above:
            parts.scale.learn(img, box)
        if parts.recovery is not None:
            parts.recovery.learn(img, box)
        return state.evolve(learnt=True)

    def _cover(self, state: FrameState, box: IntBox) -> None:
        """The appearance model's integral image made to cover learning at ``box`` (where the
        judge moved the box away from the search; a borrowed table is left as it was)."""
        model = self._parts.appearance
        margin = self._margin(box)
        if model.holds(roi_around(box, margin), self._frame_wh):
            return
        if state.integral is not None and model.ii is state.integral:
            model.ii = _core.IntegralImage()
        model.compute_integral(state.frame, box, margin)

    def _follow(self, state: FrameState) -> FrameState:
        """Follow: the motion model sees the frame's move (a lost, found or held frame is no
        move: the target stands at its box, not steady); a second expert sees the verdict."""
        motion, expert = self._parts.motion, self._parts.expert
        if motion is not None:
            if state.lost or state.verdict is _LOST:
                motion.follow(state.box, state.box, False)
            else:
                motion.follow(state.previous, state.box, state.steady)
        if expert is not None:
            expert.follow(state)
        return state

    #: The stages every frame walks through, in order: each takes the tracker and the frame's
    #: record and returns the next record, or a generator of core requests that returns it
    #: (:meth:`_update_steps`). A stage of one's own goes into an instance's or a subclass's
    #: copy of this tuple.
    stages: tuple[Callable[[Tracker, FrameState], FrameState | Steps], ...] = (
        _locate, _locate_expert, _rescale, _score, _recover, _judge, _learn, _follow)

    def _witnesses(self) -> tuple[float, ...]:
        """The cues' own confidences of this frame (those that give one; see
        :class:`~wmiltrack.engine.cues.Cue`)."""
        out = []
        for cue in self._parts.cues:
            value = getattr(cue, "confidence", math.nan)
            if math.isfinite(value):
                out.append(float(value))
        return tuple(out)

    def _search_at(self, state: FrameState, origin: IntBox, grids: list[tuple[int, int]]
                   ) -> Steps:
        """The classifier's search from ``origin`` over ``grids`` with every cue merged (its
        own integral image): the record with the box moved (see :func:`_moved`)."""
        search = self._search(state.frame, origin, grids, self._margin(state.box))
        box, raw, searched = _moved(origin, grids, (yield search))
        return state.located(origin, box, raw, searched, state.learnt)

    def _search(self, img: np.ndarray, origin: IntBox, grids: list[tuple[int, int]],
                margin: int, *, shared: bool = False) -> Search:
        """The core's search request from ``origin`` over ``grids`` (the one place a frame's
        search is built): the appearance model makes its integral image ready (``margin``
        pixels around ``origin``; with ``shared``, the borrowed one it holds), then the cues
        give their tables (:meth:`_cue_tables`), which the search merges in."""
        model = self._parts.appearance
        frame, roi = model.prepare(None if shared else img, origin, margin)
        return model.search_request(origin, grids, self._frame_wh, frame, roi,
                                    self._cue_tables(img, origin))

    def _origin(self, frame: np.ndarray | None, box: IntBox) -> IntBox:
        """Where the search on ``frame`` is centred for a target last at ``box`` (without the
        frame: the motion model's guess before seeing it)."""
        motion = self._parts.motion
        return box if motion is None else motion.origin(box, frame)

    def _margin(self, box: IntBox) -> int:
        """The integral image's margin around a search from ``box``."""
        scale = self._parts.scale
        if scale is None:
            return self._reach
        return self._reach + scale.margin(box)

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

    def _learn_steps(self, sampler: Any, box: IntBox) -> Steps:
        """The appearance model's learning at ``box``, with the scale estimator's extras
        (wrong-scale negatives, its own target model)."""
        parts = self._parts
        extra, n_extra, second = (None, 0, None)
        if parts.scale is not None:
            extra, n_extra, second = parts.scale.learning_extras(parts.appearance, box)
        learnt = yield from parts.appearance.learn_steps(box, self._frame_wh, sampler, extra,
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


def _result(state: FrameState) -> TrackResult:
    """A frame's result, from its record: its box (``exact``, fractional, where the judge took
    it from a second expert, else the tracker's ``box``), score and ``ok``."""
    x, y, w, h = state.box if state.exact is None else state.exact
    return TrackResult((float(x), float(y), float(w), float(h)), state.score, state.ok)


def _moved(origin: IntBox, grids: list[tuple[int, int]],
           results: Sequence[tuple[int, int, float, int]]
           ) -> tuple[IntBox, float, tuple[SearchStage, ...]]:
    """The box moved from ``origin`` by a search's per-grid ``(dx, dy, score, n)``, the raw
    score of the last grid that had candidates (-inf if none had), and each grid's start."""
    best = -math.inf
    box = origin
    searched = []
    for (radius, step), (dx, dy, score, n) in zip(grids, results):
        searched.append((box, radius, step))
        if n == 0:  # no candidate fitted in the frame: stay
            continue
        x, y, w, h = box
        box = (x + dx, y + dy, w, h)
        best = score
    return box, best, tuple(searched)


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

