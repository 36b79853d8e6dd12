"""wmiltrack's trackers in OpenCV's shape: drop-in replacements for OpenCV's tracker classes
(the other way round from :class:`wmiltrack.trackers.OpenCVTracker`, which puts OpenCV's
trackers behind wmiltrack's interface).

Code written for ``cv2.TrackerMIL`` runs unchanged with one of these::

    from wmiltrack.compat import TrackerRCWMIL

    tracker = TrackerRCWMIL.create()              # like cv2.TrackerMIL.create()
    tracker.init(frame, (x, y, w, h))             # BGR or gray frame from cv2.VideoCapture
    ok, rect = tracker.update(frame)              # rect: (x, y, w, h) ints, as OpenCV gives
    tracker.getTrackingScore()                    # confidence of the last update in [0, 1]

The richer :class:`wmiltrack.TrackResult` of the last update is :attr:`TrackerCompat.last_result`,
and :attr:`TrackerCompat.tracker` is the underlying :class:`wmiltrack.Tracker`.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, ClassVar

import numpy as np

from ..engine.params import Params
from ..engine.result import TrackResult
from ..engine.tracker import NotInitializedError, Tracker

__all__ = [
    "COMPAT_CLASSES",
    "TrackerCT",
    "TrackerCompat",
    "TrackerFCT",
    "TrackerMILBoost",
    "TrackerOSIL",
    "TrackerRCWMIL",
    "TrackerRCWMILCF",
    "TrackerRCWMILNano",
    "TrackerRCWMILPlus",
    "TrackerWMIL",
]

Rect = tuple[int, int, int, int]


class TrackerCompat:
    """A :class:`wmiltrack.Tracker` behind OpenCV's ``cv2.Tracker`` interface.

    Parameters
    ----------
    variant : str
        A preset: a key of :func:`wmiltrack.variants`, the preset registry (each preset also
        has its own subclass, listed in :data:`COMPAT_CLASSES`).
    params : Params or mapping, optional
        Full parameters, or a mapping of overrides of the variant's defaults.
    seed : int
        Random seed (same seed and frames: same boxes).

    Attributes
    ----------
    last_result : TrackResult or None
        The full result of the last :meth:`update` (``None`` before the first one).
    """

    #: Variant that :meth:`create` builds; subclasses set it.
    VARIANT: ClassVar[str] = "rcwmil"

    def __init__(self, variant: str | None = None, params: Params | Mapping[str, Any] | None = None,
                 seed: int = 0) -> None:
        name = self.VARIANT if variant is None else variant
        if params is None:
            self._tracker = Tracker(name, seed=seed)
        elif isinstance(params, Params):
            self._tracker = Tracker(name, seed=seed, params=params)
        elif isinstance(params, Mapping):
            self._tracker = Tracker(name, seed=seed, **dict(params))
        else:
            raise TypeError("params must be a wmiltrack.Params, a mapping or None, "
                            f"got {type(params).__name__}")
        self.last_result: TrackResult | None = None
        self._started = False

    @classmethod
    def create(cls, params: Params | Mapping[str, Any] | None = None, seed: int = 0) -> TrackerCompat:
        """Make a tracker of this class's variant, as ``cv2.TrackerMIL.create(params)`` does.

        Parameters
        ----------
        params : Params or mapping, optional
            Parameters, or overrides of the variant's defaults.
        seed : int
            Random seed.

        Returns
        -------
        TrackerCompat
            A new, uninitialised tracker.
        """
        return cls(None, params, seed)

    @property
    def tracker(self) -> Tracker:
        """The underlying :class:`wmiltrack.Tracker`."""
        return self._tracker

    def init(self, image: np.ndarray, boundingBox: Any) -> None:  # noqa: N803 (OpenCV's name)
        """Start (or restart) tracking ``boundingBox = (x, y, w, h)`` in ``image``.

        Parameters
        ----------
        image : numpy.ndarray
            ``H x W`` gray or ``H x W x 3`` BGR frame (``uint8``, or 0..255 ints/floats).
        boundingBox : sequence of 4 numbers
            ``(x, y, w, h)``; ints or floats, rounded to whole pixels and clipped to the frame.
        """
        self._tracker.init(image, boundingBox)
        self.last_result = None
        self._started = True

    def update(self, image: np.ndarray) -> tuple[bool, Rect]:
        """Locate the target in the next frame.

        Parameters
        ----------
        image : numpy.ndarray
            The next frame, same size as the one given to :meth:`init`.

        Returns
        -------
        tuple of (bool, tuple of 4 int)
            ``(ok, (x, y, w, h))`` as OpenCV returns them; ``ok`` is the tracker's lost flag
            (:attr:`wmiltrack.TrackResult.ok`; False: the target is judged lost or hidden, the
            box is still the best guess). For the paper presets it is the score against the
            variant's ``lost_threshold``; presets with a lost judge (``rcwmil-cf``) decide from
            more than this frame's score, so ``ok`` and ``score >= lost_threshold`` can differ.
        """
        r = self._tracker.update(image)
        self.last_result = r
        x, y, w, h = (int(round(v)) for v in r.box)
        return bool(r.ok), (x, y, w, h)

    def getTrackingScore(self) -> float:  # noqa: N802 (OpenCV's name)
        """Confidence in [0, 1] of the last update (1.0 right after :meth:`init`: the box was
        given).

        Returns
        -------
        float
            The ``score`` of :attr:`last_result`, as ``cv2.TrackerNano.getTrackingScore``.

        Raises
        ------
        NotInitializedError
            Before :meth:`init`: there is no target yet, so no confidence to give.
        """
        if not self._started:
            raise NotInitializedError("call init(image, boundingBox) before getTrackingScore()")
        return 1.0 if self.last_result is None else float(self.last_result.score)

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self._tracker!r})"


class TrackerRCWMIL(TrackerCompat):
    """OpenCV-shaped RCWMIL tracker (the paper's): ``TrackerRCWMIL.create()``."""

    VARIANT = "rcwmil"


class TrackerCT(TrackerCompat):
    """OpenCV-shaped compressive tracker (CT): ``TrackerCT.create()``."""

    VARIANT = "ct"


class TrackerFCT(TrackerCompat):
    """OpenCV-shaped fast compressive tracker (FCT): ``TrackerFCT.create()``."""

    VARIANT = "fct"


class TrackerMILBoost(TrackerCompat):
    """OpenCV-shaped MILTrack (wmiltrack's ``mil`` variant): ``TrackerMILBoost.create()``."""

    VARIANT = "mil"


class TrackerWMIL(TrackerCompat):
    """OpenCV-shaped weighted-MIL tracker: ``TrackerWMIL.create()``."""

    VARIANT = "wmil"


class TrackerOSIL(TrackerCompat):
    """OpenCV-shaped online sparse instance learning tracker: ``TrackerOSIL.create()``."""

    VARIANT = "osil"


class TrackerRCWMILPlus(TrackerCompat):
    """OpenCV-shaped ``rcwmil-plus`` (the paper's tracker plus scale, channels, motion and
    occlusion-aware update): ``TrackerRCWMILPlus.create()``."""

    VARIANT = "rcwmil-plus"


class TrackerRCWMILCF(TrackerCompat):
    """OpenCV-shaped ``rcwmil-cf`` (rcwmil-plus with correlation filters on fHOG features for
    the target's position and size): ``TrackerRCWMILCF.create()``."""

    VARIANT = "rcwmil-cf"


class TrackerRCWMILNano(TrackerCompat):
    """OpenCV-shaped ``rcwmil-nano`` (rcwmil-cf and NanoTrack v3's network as two experts under
    one judge; the model files by path or from the models folder):
    ``TrackerRCWMILNano.create()``, or ``.create({"backbone": ..., "head": ...})``."""

    VARIANT = "rcwmil-nano"


COMPAT_CLASSES: dict[str, type[TrackerCompat]] = {
    cls.VARIANT: cls for cls in TrackerCompat.__subclasses__()
}
"""The OpenCV-shaped class of each preset, by preset name (one per key of
:func:`wmiltrack.variants`; a test checks that none is missing)."""
