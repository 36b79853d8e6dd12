"""Two experts under one judge: the engine's tracker and a Siamese network (rcwmil-nano).

The tracker (rcwmil-cf: the classifier, colour and correlation filters) and NanoTrack's
network fail on different frames: the network finds targets that move fast, deform or are
small, and the tracker holds on where the network jumps to a look-alike. Neither one's own
score says when it is wrong (the network's best score is close to 1 on almost every frame).
:class:`TwoExperts` runs both each frame and :class:`ExpertJudge` decides, from a memory of the
target that neither expert's search changes (the network's first-frame template, compared with
the network's choice: the *likeness*), whether the target is tracked, doubtful, lost or found
again; see :class:`ExpertSettings` for the rules and their values.

One frame::

    network locates -> judge's verdict from the likeness ->
      tracked or doubtful: the box (the mix where the experts agree, else the network's; the
                           tracker moved to it, keeping what it learnt, when they disagree)
      lost:                the network also searches whole-frame windows and the tracker's box;
                           the likeliest is the best guess, and the verdict turns to found
                           after enough frames alike the target; then both experts move there.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..networks.backends import RUNTIMES
from ..networks.families import check_siamese, load_siamese, siamese_networks
from ..networks.files import find_files
from ..networks.siamese import SiameseStep, as_bgr
from .geometry import centre, overlap, within
from .result import TrackResult
from .settings import check_choices, check_ints, check_numbers, need
from .state import Verdict

__all__ = ["NETWORKS", "ExpertJudge", "ExpertSettings", "TwoExperts", "Verdict", "network_files"]


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
        check_choices(self, {"network": NETWORKS,
                              "network_runtime": RUNTIMES})
        need(isinstance(self.backbone, str) and isinstance(self.head, str),
             "backbone and head must be paths as strings ('' to find them)")
        check_ints(self, "network_threads", "lost_frames", "found_frames", "redetect_windows",
                   "redetect_after", "likeness_every")
        need(self.redetect_after >= 0, f"redetect_after must be >= 0, got {self.redetect_after}")
        need(self.likeness_every >= 1, f"likeness_every must be >= 1, got {self.likeness_every}")
        check_numbers(self, "expert_agree", "expert_blend", "like_low", "like_high", "like_drop",
                      "like_found", "like_rate")
        need(0.0 <= self.like_drop <= self.like_found <= 1.0,
             f"like_drop and like_found must satisfy 0 <= like_drop <= like_found <= 1, got "
             f"{self.like_drop} and {self.like_found}")
        need(0.0 < self.like_rate <= 1.0, f"like_rate must be in (0, 1], got {self.like_rate}")
        need(self.network_threads >= 1, f"network_threads must be >= 1, got {self.network_threads}")
        need(0.0 <= self.expert_agree <= 1.0, f"expert_agree must be in [0, 1], got {self.expert_agree}")
        need(0.0 <= self.expert_blend <= 1.0, f"expert_blend must be in [0, 1], got {self.expert_blend}")
        need(-1.0 <= self.like_low <= self.like_high <= 1.0,
             f"like_low and like_high must satisfy -1 <= like_low <= like_high <= 1, got "
             f"{self.like_low} and {self.like_high}")
        need(self.lost_frames >= 1, f"lost_frames must be >= 1, got {self.lost_frames}")
        need(self.found_frames >= 1, f"found_frames must be >= 1, got {self.found_frames}")
        need(self.redetect_windows >= 0,
             f"redetect_windows must be >= 0, got {self.redetect_windows}")


FloatBox = tuple[float, float, float, float]


class ExpertJudge:
    """The verdict of each frame from its likeness and the experts' agreement, with
    hysteresis, and the reported confidence.

    A frame counts against the target when its likeness is below ``like_low``, or below
    ``like_drop`` times the running mean of the tracked frames' likeness (``like_rate`` per
    frame: a target whose look drifts slowly keeps its own level), unless the experts agree on
    the box and the tracker says ``ok`` (two experts that agree are rarely both wrong, even
    where the target no longer looks like the first frame's). ``lost_frames`` such frames in a
    row start the lost state; ``found_frames`` in a row above both ``like_high`` and
    ``like_found`` times the mean end it (a gap between the two levels, so that a place that
    looks like the target's surroundings, as an occluder in front of it does, does not end it).
    """

    def __init__(self, settings: ExpertSettings) -> None:
        self.settings = settings
        self.lost = False
        self.typical = math.nan  # the running mean of the tracked frames' likeness
        self._run = 0

    def verdict(self, likeness: float, agree: bool) -> Verdict:
        """The verdict of a frame whose best place has ``likeness``, the experts agreeing on
        it (and the tracker saying ``ok``) or not (``agree``)."""
        s = self.settings
        if math.isnan(likeness):  # not measured: a frame the experts vouch for
            self._run = 0 if not self.lost else self._run
            return Verdict.LOST if self.lost else Verdict.TRACKED
        if math.isnan(self.typical):
            self.typical = likeness
        floor = s.like_drop * self.typical
        if not self.lost:
            against = (likeness < s.like_low or likeness < floor) and not agree
            self._run = self._run + 1 if against else 0
            if self._run == 0:
                self.typical += s.like_rate * (likeness - self.typical)
                return Verdict.TRACKED
            if self._run < s.lost_frames:
                return Verdict.DOUBTFUL
            self.lost, self._run = True, 0
            return Verdict.LOST
        self._run = self._run + 1 if likeness > self.found_level() else 0
        if self._run < s.found_frames:
            return Verdict.LOST
        self.lost, self._run = False, 0
        return Verdict.FOUND

    def found_level(self) -> float:
        """The likeness above which a lost frame counts for the target."""
        s = self.settings
        typical = self.typical if math.isfinite(self.typical) else 0.0
        return max(s.like_high, s.like_found * typical)

    def confidence(self, likeness: float) -> float:
        """The likeness mapped to [0, 1]: 0.5 at the lower of ``like_low`` and the dropped
        running mean, rising with the likeness (a logistic of slope 20)."""
        s = self.settings
        typical = self.typical if math.isfinite(self.typical) else 1.0
        z = 20.0 * (likeness - max(s.like_low, s.like_drop * typical))
        return 1.0 / (1.0 + math.exp(-z)) if math.isfinite(z) else 0.0


def network_files(settings: ExpertSettings) -> tuple[Path, Path]:
    """The backbone and head of ``settings.network``: the paths in ``settings`` if given, else
    found as :func:`wmiltrack.networks.files.find_files` finds them, and loaded once by the
    runtime (:func:`wmiltrack.networks.families.check_siamese`). The one check of a network's
    files, made when a tracker is built (so that a missing or unreadable file is said at once,
    not at its first frame) and again when its network is loaded.

    Raises
    ------
    ModelFilesMissing
        A file is missing or is another set's or role's; the message says how to give them.
        :class:`~wmiltrack.networks.files.ModelFileUnreadable` (a ModelFilesMissing): a file
        the runtime cannot run (empty, corrupt, truncated, another role's); one line.
    """
    found = find_files(settings.network, {"backbone": settings.backbone or None,
                                          "head": settings.head or None})
    check_siamese(settings.network, backbone=found[0], head=found[1],
                  runtime=settings.network_runtime, threads=settings.network_threads)
    return found[0], found[1]


class TwoExperts:
    """The network expert and the judge beside a tracker (see the module's docstring).

    ``settings``: its own; the tracker is reached only through the frame's result and the
    ``recentre`` callback that each :meth:`step` receives.
    """

    def __init__(self, settings: ExpertSettings) -> None:
        backbone, head = network_files(settings)
        self.settings = settings
        self.locator: SiameseStep = load_siamese(
            settings.network, backbone=backbone, head=head,
            runtime=settings.network_runtime, threads=settings.network_threads)
        self._restart((0.0, 0.0, 0.0, 0.0))

    def start(self, frame: np.ndarray, box: FloatBox) -> None:
        """Take the network's template at ``box`` of the first frame."""
        self.locator.start(as_bgr(frame), box)
        self._restart(box)

    def _restart(self, box: FloatBox) -> None:
        """The judge and the per-run state as on a first frame at ``box``."""
        self.judge = ExpertJudge(self.settings)
        self.box: FloatBox = (float(box[0]), float(box[1]), float(box[2]), float(box[3]))
        self._held: FloatBox = self.box  # the last tracked box: where the sweep starts
        self._sweep: list[tuple[float, float]] = []  # the sweep's centres still to search
        self._since = 0  # vouched frames since the likeness was last measured
        self._score = 1.0  # the last measured confidence
        self._lost_for = 0  # frames in the lost state

    def step(self, frame: np.ndarray, tracker: TrackResult,
             recentre: Callable[[FloatBox], None]) -> TrackResult:
        """The frame's result from the tracker's (``tracker``) and the network's; ``recentre``
        moves the tracker to a box without forgetting what it learnt."""
        img = as_bgr(frame)
        if self.judge.lost:
            return self._lost_step(img, tracker, recentre)
        found = self.locator.locate(img)
        agree = overlap(found.box, tracker.box) >= self.settings.expert_agree
        vouched = agree and tracker.ok
        self._since += 1
        if not vouched or self._since >= self.settings.likeness_every:
            self._since = 0
            likeness = self.locator.likeness(img, found.box)
            verdict = self.judge.verdict(likeness, vouched)
            self._score = self.judge.confidence(likeness)
        else:  # the experts vouch for the box: no need to ask the memory this frame
            verdict = self.judge.verdict(math.nan, vouched)
        box = within(self._merge(found.box, tracker.box, agree, recentre, verdict),
                     img.shape[1], img.shape[0])
        if verdict is Verdict.TRACKED:
            self._held = box
        self.box = box
        return TrackResult(box, self._score, verdict is not Verdict.LOST)

    def _merge(self, network: FloatBox, tracker: FloatBox, agree: bool,
               recentre: Callable[[FloatBox], None], verdict: Verdict) -> FloatBox:
        """The network's box, mixed with the tracker's where they agree; the tracker is moved
        to the network's box where they do not (only on a tracked frame)."""
        if agree:
            b = self.settings.expert_blend
            return tuple((1 - b) * n + b * t for n, t in zip(network, tracker))  # type: ignore[return-value]
        if verdict is Verdict.TRACKED:
            recentre(network)
        return network

    def _lost_step(self, img: np.ndarray, tracker: TrackResult,
                   recentre: Callable[[FloatBox], None]) -> TrackResult:
        """A frame of the lost state: the network's own search, unless the tracker's box or
        this frame's share of whole-frame windows holds a place alike the target (above the
        judge's level for found, :meth:`ExpertJudge.found_level`) and more alike than the
        network's: then the network moves there. A place merely less unlike the target than
        the network's own never takes the box (a target that changed its look is still best
        followed by the network)."""
        self._lost_for += 1
        best = self.locator.locate(img)
        likeness = self.locator.likeness(img, best.box)
        level = self.judge.found_level()
        for place in self._places(img, tracker.box):
            cand = self.locator.search_at(img, place, self.locator.size, window=False)
            like = self.locator.likeness(img, cand.box)
            if like > max(likeness, level):
                best, likeness = cand, like
                self.locator.recentre(best.box)
        verdict = self.judge.verdict(likeness, False)
        if verdict is Verdict.FOUND:
            recentre(best.box)
            self._held = best.box
            self._sweep, self._lost_for = [], 0
        self.box = within(best.box, img.shape[1], img.shape[0])
        return TrackResult(self.box, self.judge.confidence(likeness), verdict is Verdict.FOUND)

    def _places(self, img: np.ndarray, tracker: FloatBox) -> list[tuple[float, float]]:
        """The centres this lost frame searches besides the network's own: the tracker's box,
        then the next ``redetect_windows`` of the whole-frame sweep."""
        places = [centre(tracker)]
        n = self.settings.redetect_windows
        if n <= 0 or self._lost_for < self.settings.redetect_after:
            return places
        if not self._sweep:
            reach = self.locator.search_side(self.locator.size) * 0.44  # half the answer grid's span
            self._sweep = _sweep(img.shape[1], img.shape[0], reach, centre(self._held))
        places += self._sweep[:n]
        self._sweep = self._sweep[n:]
        return places


def _sweep(fw: int, fh: int, reach: float, near: tuple[float, float]) -> list[tuple[float, float]]:
    """Search-window centres covering a ``fw x fh`` frame for a network that reaches ``reach``
    frame pixels from a window's centre (windows 0.8 of that reach apart), nearest to ``near``
    first."""
    step = max(0.8 * 2 * reach, 8.0)
    xs = np.arange(step / 2, fw + step / 2, step).clip(0, fw)
    ys = np.arange(step / 2, fh + step / 2, step).clip(0, fh)
    centres = [(float(x), float(y)) for y in ys for x in xs]
    centres.sort(key=lambda c: (c[0] - near[0]) ** 2 + (c[1] - near[1]) ** 2)
    return centres
