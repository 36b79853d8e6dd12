"""OpenCV's trackers with wmiltrack's ``init``/``update`` interface (:class:`OpenCVTracker`,
``opencv:NAME`` of the command line and the evaluation), and their model files.

Nano (NanoTrack v2) and Vit are neural-network trackers: they need model files, which are
not part of any wheel. Nano's are NanoTrack v2's model set, found as every network's files are
(:func:`wmiltrack.networks.files.locate`: the parameters ``opencv:Nano:backbone=FILE:neckhead=FILE``,
then ``WMILTRACK_NANO_BACKBONE`` and ``WMILTRACK_NANO_HEAD``, then the models folder, where
``wmiltrack models fetch nanotrack-v2`` puts them; each checked against its pinned SHA-1). Vit's
is given by ``opencv:Vit:net=FILE`` or ``WMILTRACK_VIT_MODEL``. Without them the tracker raises
:class:`~wmiltrack.integrations.opencv_wheels.TrackerUnavailable` saying which file is missing.
Which wheel has which tracker: :mod:`wmiltrack.integrations.opencv_wheels`.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from typing import Any, Literal

import numpy as np
import numpy.typing as npt

from ..engine.frames import clip_box
from ..engine.result import Box, Frame, TrackResult
from ..networks.files import MODEL_ENV, locate
from ..networks.siamese import as_bgr
from .opencv_wheels import (
    TrackerUnavailable,
    opencv_factory,
    opencv_params_class,
    parse_opencv_name,
    swap_hint,
)

__all__ = ["MODEL_FILES", "NANO_MODELS", "OpenCVTracker", "model_option", "model_paths"]

MODEL_FILES: dict[tuple[str, str], str] = {
    ("Nano", "backbone"): "NanoTrack's backbone (nanotrack_backbone_sim.onnx)",
    ("Nano", "neckhead"): "NanoTrack's neck and head (nanotrack_head_sim.onnx)",
    ("Vit", "net"): "the Vit tracker's model (object_tracking_vittrack_2023sep.onnx)",
}
"""What each model file of :data:`MODEL_ENV` is, by (tracker, parameter), for messages and
help."""

NANO_MODELS = "nanotrack-v2"
"""The model set ``opencv:Nano`` runs (:data:`wmiltrack.networks.files.MODELS`); its
``backbone`` and ``head`` are TrackerNano's ``backbone`` and ``neckhead``."""

BoxLike = Sequence[float] | npt.NDArray[Any]


def model_option(kind: str, attr: str) -> str:
    """The command line's option for a model file: ``--nano-backbone``, ``--nano-head``,
    ``--vit-model``."""
    short = {"neckhead": "head", "net": "model"}.get(attr, attr)
    return f"--{kind.lower()}-{short}"


def model_paths(kind: str, params: dict[str, Any]) -> dict[str, str]:
    """The model files of OpenCV tracker ``kind`` (none for the trackers that need none):
    Nano's found as NanoTrack v2's set (:data:`NANO_MODELS`; the parameters, the environment,
    the models folder), Vit's from ``params`` or else from its environment variable
    (:data:`~wmiltrack.networks.files.MODEL_ENV`).

    Raises
    ------
    TrackerUnavailable
        A model file is not given or does not exist; the message names every such file, with
        the command-line option, the tracker parameter and the environment variable that
        give it.
    """
    if kind == "Nano":
        return _nano_paths(params)
    out: dict[str, str] = {}
    problems: list[str] = []
    for attr, env in MODEL_ENV.get(kind, {}).items():
        value = params.get(attr) or os.environ.get(env, "")
        what = MODEL_FILES[(kind, attr)]
        if not value:
            problems.append(f"{what}: give its path with {model_option(kind, attr)} FILE (or "
                            f"opencv:{kind}:{attr}=FILE, or the environment variable {env})")
        elif not os.path.isfile(str(value)):
            source = f"{attr}=" if params.get(attr) else f"{env}="
            problems.append(f"{what}: {source}{value} is not a file; check the path")
        else:
            out[attr] = str(value)
    _raise_missing(kind, problems)
    return out


def _raise_missing(kind: str, problems: list[str]) -> None:
    """A :class:`TrackerUnavailable` naming each of ``problems``, if there are any."""
    if problems:
        raise TrackerUnavailable(
            f"opencv:{kind} needs {len(problems)} model file(s) it does not have: "
            + "; ".join(problems) + ". The model files are not part of OpenCV's wheels")


def _nano_paths(params: dict[str, Any]) -> dict[str, str]:
    """``opencv:Nano``'s ``backbone`` and ``neckhead``: NanoTrack v2's files, found as
    :func:`wmiltrack.networks.files.locate` finds every network's (given, else in the
    environment, else in the models folder)."""
    attrs = {"backbone": "backbone", "head": "neckhead"}  # the set's role -> TrackerNano's
    found = locate(NANO_MODELS, {role: params.get(attr) or None for role, attr in attrs.items()})
    problems = []
    for p in found:
        attr, env = attrs[p.role], MODEL_ENV["Nano"][attrs[p.role]]
        if p.problem is None:
            continue
        what = MODEL_FILES[("Nano", attr)]
        if p.origin == "models folder":
            problems.append(f"{what}: give its path with {model_option('Nano', attr)} FILE (or "
                            f"opencv:Nano:{attr}=FILE, or the environment variable {env}), or fetch "
                            f"it into the models folder: `wmiltrack models fetch {NANO_MODELS}` "
                            f"({p.problem})")
        else:  # a path given (named by TrackerNano's parameter) or in the environment
            problem = attr + p.problem.removeprefix(p.role) if p.origin == f"{p.role}=" else p.problem
            problems.append(f"{what}: {problem}; check the path")
    _raise_missing("Nano", problems)
    return {attrs[p.role]: str(p.path) for p in found}


def _frame(frame: npt.ArrayLike) -> Frame:
    if not isinstance(frame, np.ndarray):
        raise TypeError(f"frame must be a numpy array, not {type(frame).__name__}")
    if frame.dtype != np.uint8:
        raise ValueError(f"frame must be uint8 (as cv2.imread gives), not {frame.dtype}")
    if not (frame.ndim == 2 or (frame.ndim == 3 and frame.shape[2] in (1, 3))):
        raise ValueError(f"frame must be (h, w) gray or (h, w, 3) BGR; got shape {frame.shape}")
    if frame.shape[0] < 1 or frame.shape[1] < 1:
        raise ValueError(f"empty frame of shape {frame.shape}")
    return frame


def _int_box(box: BoxLike, shape: tuple[int, ...]) -> tuple[int, int, int, int]:
    """Round and clip a box as :class:`wmiltrack.Tracker` does; OpenCV needs >= 2x2 pixels."""
    x, y, w, h = clip_box(box, int(shape[1]), int(shape[0]))
    if w < 2 or h < 2:
        raise ValueError(f"box {box!r} leaves less than 2x2 pixels inside the {shape[1]}x{shape[0]} frame")
    return x, y, w, h


class OpenCVTracker:
    """One of OpenCV's trackers with wmiltrack's ``init``/``update`` interface.

    Parameters
    ----------
    name:
        One of :data:`OPENCV_TRACKERS`, case-insensitive, with or without ``"opencv:"``.
    seed:
        Passed to ``cv2.setRNGSeed`` before each ``init`` (MIL and Boosting draw samples).
    lost_box:
        What ``update`` reports as the box when OpenCV says the target was not found:
        ``"nan"`` (default: no box, scored as a miss) or ``"hold"`` (the last box found).
    **params:
        Attributes of the tracker's ``cv2.Tracker*_Params`` (MIL, KCF and CSRT only), e.g.
        ``detect_thresh=0.3`` for KCF.

    Raises
    ------
    ValueError
        Unknown name, or params the tracker does not have.
    TrackerUnavailable
        The installed ``cv2`` does not provide this tracker; the message says how to get it.

    Attributes
    ----------
    name:
        ``"opencv:<NAME>"``, e.g. ``"opencv:KCF"``.
    kind:
        The OpenCV name, e.g. ``"KCF"``.
    """

    def __init__(
        self,
        name: str,
        seed: int = 0,
        *,
        lost_box: Literal["nan", "hold"] = "nan",
        **params: Any,
    ) -> None:
        self.kind: str = parse_opencv_name(name)
        self.name: str = f"opencv:{self.kind}"
        self.seed = int(seed)
        if lost_box not in ("nan", "hold"):
            raise ValueError(f"lost_box must be 'nan' or 'hold', not {lost_box!r}")
        self.lost_box = lost_box
        self._create = opencv_factory(self.kind)
        if self._create is None:
            raise TrackerUnavailable(swap_hint(self.kind))
        params = {**params, **model_paths(self.kind, params)}
        self._params = self._make_params(params)
        self._tracker: Any = None
        self._last: Box = (math.nan,) * 4

    def _make_params(self, params: dict[str, Any]) -> Any:
        if not params:
            return None
        cls = opencv_params_class(self.kind)
        if cls is None:
            raise ValueError(f"{self.name} takes no parameters; got {sorted(params)}")
        p = cls()
        known = sorted(a for a in dir(p) if not a.startswith("_"))
        for key, value in params.items():
            if key not in known:
                raise ValueError(
                    f"{self.name} has no parameter {key!r}; it has: {', '.join(known)}"
                )
            setattr(p, key, value)
        return p

    def __repr__(self) -> str:
        return f"OpenCVTracker({self.kind!r}, seed={self.seed})"

    def _colour(self, img: Frame) -> Frame:
        """The frame as the tracker reads it: the neural-network trackers take 3-channel
        images only, so a gray frame is repeated into three channels for them."""
        return as_bgr(img) if self.kind in MODEL_ENV else img

    def init(self, frame: Frame, box: BoxLike) -> None:
        """Start tracking ``box`` in ``frame`` with a fresh OpenCV tracker.

        Parameters
        ----------
        frame:
            ``(h, w, 3)`` BGR or ``(h, w)`` gray uint8 image.
        box:
            ``(x, y, w, h)``; floats are rounded to whole pixels (corners rounded, so the box
            covers the pixels nearest to the float one) and clipped to the frame.

        Raises
        ------
        ValueError
            NaN/infinite values, non-positive size, or less than 2x2 pixels inside the frame.
        RuntimeError
            OpenCV refused to initialise.
        """
        import cv2

        img = self._colour(_frame(frame))
        ibox = _int_box(box, img.shape)
        cv2.setRNGSeed(self.seed)
        tracker = self._create() if self._params is None else self._create(self._params)
        ok = tracker.init(img, ibox)
        if ok is False:  # legacy trackers return a bool, the others None
            raise RuntimeError(f"{self.name} failed to initialise on box {ibox}")
        self._tracker = tracker
        self._last = tuple(float(v) for v in ibox)  # type: ignore[assignment]

    def update(self, frame: Frame) -> TrackResult:
        """Track into the next frame.

        Parameters
        ----------
        frame:
            The next image, same kind as the one given to :meth:`init`.

        Returns
        -------
        TrackResult
            ``score`` is the tracker's ``getTrackingScore()`` where it has one (Nano, Vit),
            else NaN (the others give none); ``ok`` is OpenCV's "found" flag;
            ``box`` is NaN (or the last box, with ``lost_box="hold"``) when not found.

        Raises
        ------
        RuntimeError
            If :meth:`init` was not called.
        """
        if self._tracker is None:
            raise RuntimeError(f"{self.name}: call init() before update()")
        found, rect = self._tracker.update(self._colour(_frame(frame)))
        found = bool(found)
        score = self._score()
        if found:
            self._last = (float(rect[0]), float(rect[1]), float(rect[2]), float(rect[3]))
            return TrackResult(self._last, score, True)
        box: Box = self._last if self.lost_box == "hold" else (math.nan,) * 4
        return TrackResult(box, score, False)

    def _score(self) -> float:
        """The tracker's confidence of its last update where OpenCV gives one (Nano and Vit:
        ``getTrackingScore()``), else NaN."""
        get = getattr(self._tracker, "getTrackingScore", None)
        if get is None or self.kind not in MODEL_ENV:  # only the networks' confidence is reported
            return math.nan
        value = float(get())
        return value if math.isfinite(value) else math.nan
