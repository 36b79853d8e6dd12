"""A second expert beside the tracker: a Siamese network (rcwmil-nano's NanoTrack).

The tracker (rcwmil-cf: the classifier, colour and correlation filters) and NanoTrack's
network fail on different frames: the network finds targets that move fast, deform or are
small, and the tracker holds on where the network jumps to a look-alike. Neither one's own
score says when it is wrong (the network's best score is close to 1 on almost every frame).
:class:`NetworkExpert` is a part (kind ``"expert"``, :class:`~wmiltrack.engine.parts.SecondExpert`):
each frame it locates the target beside the tracker and reports its evidence into the frame's
record (:class:`~wmiltrack.engine.state.ExpertReport`: its box, and the *likeness* of that box
to a memory of the target that no search changes, the network's first-frame template). The
judge (:class:`~wmiltrack.engine.judge.FrameJudge`) weighs it with the tracker's own evidence
and gives the frame's one verdict and box; the tracker learns there, and the network follows.

One frame::

    tracked:  the network's own search (narrow after a frame the judge vouched for, with
              ``narrow_search``); its likeness measured when the judge asks
    lost:     the network's own search, and the tracker's box and (after ``redetect_after``
              lost frames) ``redetect_windows`` windows a frame of a whole-frame sweep, each
              with its likeness; the judge picks the place, the network moves there
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..networks.backends import RUNTIMES
from ..networks.families import check_siamese, load_siamese, siamese_networks
from ..networks.files import find_files
from ..networks.nanotrack import check_narrow
from ..networks.siamese import SiameseStep, as_bgr
from .frames import IntBox
from .geometry import centre, within
from .settings import check_choices, check_ints, need
from .state import ExpertReport, FloatBox, FrameState, Verdict

__all__ = ["NETWORKS", "ExpertSettings", "NetworkExpert", "network_files"]


NETWORKS: tuple[str, ...] = ("", *siamese_networks())
"""The Siamese networks :class:`ExpertSettings` can add ("" for none): the model sets of
:func:`wmiltrack.networks.families.siamese_networks`."""


@dataclass(frozen=True)
class ExpertSettings:
    """A Siamese network as a second expert beside the tracker (:class:`NetworkExpert`;
    rcwmil-nano). How its evidence is weighed (agreement, likeness, hysteresis) is the judge's
    (:class:`~wmiltrack.engine.judge.JudgeSettings`).

    The network (NanoTrack, :mod:`wmiltrack.networks.nanotrack`) is the more accurate locator
    on the development set, and its first-frame template is a memory of the target that never
    learns. While the target is lost the network searches, besides its own window, the
    tracker's box and, after ``redetect_after`` lost frames, ``redetect_windows`` more windows
    a frame over the whole frame (nearest first, then sweeping).

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
    redetect_windows : int
        Whole-frame search windows a lost frame tries besides the network's own (0: none).
    redetect_after : int
        Lost frames before the whole-frame windows start: a short spell (a turn, a brief
        occlusion) is better left to the network's own search than risked on a far place that
        looks like the target's surroundings.
    tracker_every : int
        While the experts vouch for the target and the tracker's own confidence is at least
        ``lost_threshold``, the tracker locates and learns only on every ``tracker_every``-th
        frame; on the frames between it rests: the network's search alone
        gives the frame's box, the judge weighs it against the tracker's box of the frame
        before, and the tracker is moved there without learning (the record's ``rested``).
        A frame after one that was doubtful, lost or not vouched for always runs the tracker.
        1: the tracker runs on every frame.
    narrow_search : int
        The side, in network pixels, of the search crop on a frame after one the judge vouched
        for (the experts agreed, the tracker said ``ok``, nothing counted against the target):
        the published crop's scale over a smaller window (:mod:`wmiltrack.networks.nanotrack`),
        a network pass at about two thirds of the published one's cost at 223 px; 0: the
        published crop (255 px) on every frame. ``16 k - 1`` px, 143 to 239; needs the
        ``onnx`` package (without it the published crop is used, said once). No preset sets
        it: on the development set, 223 px makes rcwmil-nano about 1.1 times as fast and
        costs 0.01 on one half, losing one sequence (docs/performance.md).
    """

    network: str = ""
    backbone: str = ""
    head: str = ""
    network_runtime: str = "auto"
    network_threads: int = 1
    redetect_windows: int = 4
    redetect_after: int = 10
    tracker_every: int = 1
    narrow_search: int = 0

    def __post_init__(self) -> None:
        ExpertSettings.check(self)

    def check(self) -> None:
        """``ValueError`` naming the first setting out of range."""
        check_choices(self, {"network": NETWORKS,
                              "network_runtime": RUNTIMES})
        need(isinstance(self.backbone, str) and isinstance(self.head, str),
             "backbone and head must be paths as strings ('' to find them)")
        check_ints(self, "network_threads", "redetect_windows", "redetect_after", "tracker_every",
                   "narrow_search")
        check_narrow(self.narrow_search)
        need(self.tracker_every >= 1, f"tracker_every must be >= 1, got {self.tracker_every}")
        need(self.redetect_after >= 0, f"redetect_after must be >= 0, got {self.redetect_after}")
        need(self.network_threads >= 1, f"network_threads must be >= 1, got {self.network_threads}")
        need(self.redetect_windows >= 0,
             f"redetect_windows must be >= 0, got {self.redetect_windows}")


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
                  runtime=settings.network_runtime, threads=settings.network_threads,
                  narrow=settings.narrow_search)
    return found[0], found[1]


class NetworkExpert:
    """A Siamese network as a second expert (see the module's docstring): a part of kind
    ``"expert"`` (:class:`~wmiltrack.engine.parts.SecondExpert`), made from its own settings
    (``frame`` and ``box``, the factory's other arguments, are not needed before
    :meth:`start`)."""

    def __init__(self, settings: ExpertSettings, frame: np.ndarray | None = None,
                 box: IntBox | None = None) -> None:
        backbone, head = network_files(settings)
        self.settings = settings
        self.locator: SiameseStep = load_siamese(
            settings.network, backbone=backbone, head=head,
            runtime=settings.network_runtime, threads=settings.network_threads,
            narrow=settings.narrow_search)
        self._restart((0.0, 0.0, 0.0, 0.0))

    def start(self, frame: np.ndarray, box: IntBox | FloatBox) -> None:
        """Take the network's template at ``box`` of the first frame."""
        b = (float(box[0]), float(box[1]), float(box[2]), float(box[3]))
        self.locator.start(as_bgr(frame), b)
        self._restart(b)

    def _restart(self, box: FloatBox) -> None:
        """The per-run state as on a first frame at ``box``."""
        self._held: FloatBox = box  # the last tracked box: where the sweep starts
        self._sweep: list[tuple[float, float]] = []  # the sweep's centres still to search
        self._own: FloatBox = box  # the network's own choice on the last frame
        self._narrow = False  # whether the next frame searches the narrow window

    def locate(self, state: FrameState) -> ExpertReport:
        """The network's search on the record's frame and its evidence: its box and that box's
        likeness to the first frame's target (measured when the judge asks); on a frame that
        started with the target lost (``state.lost``), also the other places searched (the
        tracker's box ``state.box``, then the sweep's share) with their likeness."""
        img = as_bgr(state.frame)
        found = self.locator.locate(img, narrow=self._narrow and not state.lost)
        self._own = found.box
        if not state.lost:
            return ExpertReport(found.box, functools.partial(self.locator.likeness, img, found.box))
        likeness = self.locator.likeness(img, found.box)
        places = []
        size = self.locator.size
        for place in self._places(img, state.box, state.lost_for):
            cand = self.locator.search_at(img, place, size, window=False)
            places.append((cand.box, self.locator.likeness(img, cand.box)))
        return ExpertReport(found.box, functools.partial(float, likeness), tuple(places))

    def follow(self, state: FrameState) -> None:
        """The network follows the frame's verdict: on a lost target's frame where the judge
        took another place than the network's own, the network moves there; a tracked frame's
        box is where a later sweep starts, and a found target's ends the sweep. The next frame
        searches the narrow window where the judge vouched for this one."""
        self._narrow = (self.settings.narrow_search > 0 and state.vouched
                        and state.verdict is Verdict.TRACKED)
        box = state.exact
        if box is None:
            return
        fh, fw = state.frame.shape[:2]
        if state.lost and box != within(self._own, fw, fh):
            self.locator.recentre(box)
        if state.verdict is Verdict.TRACKED or state.verdict is Verdict.FOUND:
            self._held = box
        if state.verdict is Verdict.FOUND:
            self._sweep = []

    def _places(self, img: np.ndarray, tracker_box: IntBox, lost_for: int
                ) -> list[tuple[float, float]]:
        """The centres this lost frame searches besides the network's own: the tracker's box,
        then, after ``redetect_after`` lost frames, the next ``redetect_windows`` of the
        whole-frame sweep."""
        places = [centre(tracker_box)]
        n = self.settings.redetect_windows
        if n <= 0 or lost_for < self.settings.redetect_after:
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
