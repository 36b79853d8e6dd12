"""The registry of tracker specs, shared by the command line, the evaluation and the benchmarks.

A spec names a tracker and may set its parameters: ``"rcwmil"``, ``"rcwmil-plus:scale_steps=2"``
(one of wmiltrack's presets, see :func:`wmiltrack.variants`) or ``"opencv:KCF"`` (one of OpenCV's
trackers). :func:`make_tracker` turns a spec into an object with the two methods
``init(frame, box)`` and ``update(frame) -> TrackResult``, so the code that runs trackers never
needs to know which library one comes from; :func:`parse_spec` and :func:`split_specs` read
specs from the command line. It lives outside ``eval/`` so that tracking a video does not
depend on the evaluation package.

Which wheel has which tracker (checked with OpenCV 5.0.0.93):

============  =========================================  ===================================
tracker       ``opencv-python-headless``                 ``opencv-contrib-python-headless``
============  =========================================  ===================================
MIL           ``cv2.TrackerMIL_create``                  same
KCF           --                                         ``cv2.TrackerKCF_create``
CSRT          --                                         ``cv2.TrackerCSRT_create``
MOSSE         --                                         ``cv2.legacy.TrackerMOSSE_create``
MedianFlow    --                                         ``cv2.legacy.TrackerMedianFlow_create``
TLD           --                                         ``cv2.legacy.TrackerTLD_create``
Boosting      --                                         ``cv2.legacy.TrackerBoosting_create``
Nano          ``cv2.TrackerNano_create``                 same
Vit           ``cv2.TrackerVit_create``                  same
============  =========================================  ===================================

Both wheels install the same ``cv2`` package, so only one can be installed at a time; a
tracker missing from the installed one raises :class:`TrackerUnavailable` whose message
gives the commands to swap wheels.

Nano (NanoTrack v2) and Vit are neural-network trackers: they need model files, which are
not part of any wheel. Give their paths as parameters (``opencv:Nano:backbone=FILE:neckhead=FILE``,
``opencv:Vit:net=FILE``) or in the environment variables of :data:`MODEL_ENV`
(``WMILTRACK_NANO_BACKBONE``, ``WMILTRACK_NANO_HEAD``, ``WMILTRACK_VIT_MODEL``); without them
the tracker raises :class:`TrackerUnavailable` saying which file is missing.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from importlib import import_module
from importlib.metadata import PackageNotFoundError, version
from typing import Any, Literal

import numpy as np
import numpy.typing as npt

from .engine.frames import clip_box
from .engine.result import Box, Frame, TrackerLike, TrackResult

__all__ = [
    "MODEL_ENV",
    "MODEL_FILES",
    "OPENCV_TRACKERS",
    "OpenCVTracker",
    "installed_opencv",
    "TrackerUnavailable",
    "available_opencv_trackers",
    "is_opencv_spec",
    "make_tracker",
    "parse_opencv_name",
    "parse_spec",
    "split_specs",
    "tracker_labels",
]

#: Names of the OpenCV trackers that :class:`OpenCVTracker` wraps.
OPENCV_TRACKERS: tuple[str, ...] = ("MIL", "KCF", "CSRT", "MOSSE", "MedianFlow", "TLD", "Boosting",
                                     "Nano", "Vit")

# name -> (factories tried in order as dotted paths under cv2, Params class or None)
_FACTORIES: dict[str, tuple[tuple[str, ...], str | None]] = {
    "MIL": (("TrackerMIL_create", "legacy.TrackerMIL_create"), "TrackerMIL_Params"),
    "KCF": (("TrackerKCF_create", "legacy.TrackerKCF_create"), "TrackerKCF_Params"),
    "CSRT": (("TrackerCSRT_create", "legacy.TrackerCSRT_create"), "TrackerCSRT_Params"),
    "MOSSE": (("legacy.TrackerMOSSE_create", "TrackerMOSSE_create"), None),
    "MedianFlow": (("legacy.TrackerMedianFlow_create", "TrackerMedianFlow_create"), None),
    "TLD": (("legacy.TrackerTLD_create", "TrackerTLD_create"), None),
    "Boosting": (("legacy.TrackerBoosting_create", "TrackerBoosting_create"), None),
    "Nano": (("TrackerNano_create",), "TrackerNano_Params"),
    "Vit": (("TrackerVit_create",), "TrackerVit_Params"),
}

_CONTRIB_ONLY = frozenset(OPENCV_TRACKERS) - {"MIL", "Nano", "Vit"}

MODEL_ENV: dict[str, dict[str, str]] = {
    "Nano": {"backbone": "WMILTRACK_NANO_BACKBONE", "neckhead": "WMILTRACK_NANO_HEAD"},
    "Vit": {"net": "WMILTRACK_VIT_MODEL"},
}
"""The model files of OpenCV's neural-network trackers: for each tracker, its ``Params``
attribute and the environment variable read when the parameter is not given."""

MODEL_FILES: dict[tuple[str, str], str] = {
    ("Nano", "backbone"): "NanoTrack's backbone (nanotrack_backbone_sim.onnx)",
    ("Nano", "neckhead"): "NanoTrack's neck and head (nanotrack_head_sim.onnx)",
    ("Vit", "net"): "the Vit tracker's model (object_tracking_vittrack_2023sep.onnx)",
}
"""What each model file of :data:`MODEL_ENV` is, by (tracker, parameter), for messages and
help."""

_PREFIX = "opencv:"
#: ``nanotrack:v2`` / ``nanotrack:v3``: NanoTrack alone by its published tracking step
#: (:class:`~wmiltrack.engine.siamese.NanoTracker`; keyword overrides ``backbone``, ``head``,
#: ``runtime``, ``threads``); deterministic, so ``seed`` is not used.
NANOTRACK_PREFIX = "nanotrack:"

BoxLike = Sequence[float] | npt.NDArray[Any]


class TrackerUnavailable(RuntimeError):
    """An OpenCV tracker is not part of the installed ``cv2`` build."""


def _cv2() -> Any:
    return import_module("cv2")


def _lookup(cv2: Any, dotted: str) -> Any:
    obj: Any = cv2
    for part in dotted.split("."):
        obj = getattr(obj, part, None)
        if obj is None:
            return None
    return obj


def installed_opencv() -> tuple[str, str]:
    """Return the distribution that provides ``cv2`` and its version.

    When a contrib and a plain wheel are both recorded as installed (they share the ``cv2``
    folder, so the last one installed is the one imported), the loaded ``cv2`` decides: one
    with a contrib-only tracker is reported as the contrib wheel.
    """
    plain = ("opencv-python-headless", "opencv-python")
    contrib = ("opencv-contrib-python-headless", "opencv-contrib-python")
    has_contrib = _factory("KCF") is not None
    for dist in (*contrib, *plain) if has_contrib else (*plain, *contrib):
        try:
            return dist, version(dist)
        except PackageNotFoundError:
            continue
    return "opencv-python-headless", str(getattr(_cv2(), "__version__", "<version>"))


def _swap_hint(name: str) -> str:
    dist, ver = installed_opencv()
    if "contrib" in dist:
        return (
            f"OpenCV tracker {name!r} is not in the installed cv2 ({dist} {ver}), although "
            "that is a contrib build; this OpenCV version may have dropped it."
        )
    contrib = dist.replace("opencv-", "opencv-contrib-", 1)
    where = " or ".join(f"cv2.{p}" for p in _FACTORIES[name][0])
    return (
        f"OpenCV tracker {name!r} is not in the installed cv2 ({dist} {ver}): it comes with "
        f"the contrib wheel {contrib} (as {where}). Both wheels install the same 'cv2' "
        "package and overwrite each other, so swap one for the other (the dry run first, so "
        "that a failed install cannot leave you without cv2):\n"
        f"    pip install --dry-run {contrib}=={ver} && pip uninstall -y {dist} && "
        f"pip install {contrib}=={ver}\n"
        f"and to go back:\n"
        f"    pip uninstall -y {contrib} && pip install {dist}=={ver}"
    )


def parse_opencv_name(name: str) -> str:
    """Canonical spelling of an OpenCV tracker name.

    Parameters
    ----------
    name:
        ``"kcf"``, ``"KCF"``, ``"opencv:medianflow"``... (case-insensitive, prefix optional).

    Returns
    -------
    str
        The entry of :data:`OPENCV_TRACKERS`, e.g. ``"MedianFlow"``.

    Raises
    ------
    ValueError
        If the name is not one of :data:`OPENCV_TRACKERS`; the message lists them.
    """
    key = name.strip()
    if key.lower().startswith(_PREFIX):
        key = key[len(_PREFIX) :]
    for known in OPENCV_TRACKERS:
        if known.lower() == key.lower():
            return known
    raise ValueError(
        f"unknown OpenCV tracker {name!r}; valid names: "
        + ", ".join(f"opencv:{n}" for n in OPENCV_TRACKERS)
    )


def is_opencv_spec(spec: str) -> bool:
    """Whether a tracker spec names one of OpenCV's trackers (``"opencv:..."``)."""
    return spec.strip().lower().startswith(_PREFIX)


def model_option(kind: str, attr: str) -> str:
    """The command line's option for a model file: ``--nano-backbone``, ``--nano-head``,
    ``--vit-model``."""
    short = {"neckhead": "head", "net": "model"}.get(attr, attr)
    return f"--{kind.lower()}-{short}"


def model_paths(kind: str, params: dict[str, Any]) -> dict[str, str]:
    """The model files of OpenCV tracker ``kind`` (none for the trackers that need none):
    each from ``params`` or else from its environment variable (:data:`MODEL_ENV`).

    Raises
    ------
    TrackerUnavailable
        A model file is not given or does not exist; the message names every such file, with
        the command-line option, the tracker parameter and the environment variable that
        give it.
    """
    import os

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
    if problems:
        raise TrackerUnavailable(
            f"opencv:{kind} needs {len(problems)} model file(s) it does not have: "
            + "; ".join(problems) + ". The model files are not part of OpenCV's wheels")
    return out


def _factory(name: str) -> Any:
    cv2 = _cv2()
    for path in _FACTORIES[name][0]:
        fn = _lookup(cv2, path)
        if fn is not None:
            return fn
    return None


def available_opencv_trackers() -> list[str]:
    """Names from :data:`OPENCV_TRACKERS` that the installed ``cv2`` provides.

    Returns
    -------
    list of str
        E.g. ``["MIL"]`` with ``opencv-python-headless``, all seven with the contrib wheel.
    """
    return [n for n in OPENCV_TRACKERS if _factory(n) is not None]


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
        self._create = _factory(self.kind)
        if self._create is None:
            raise TrackerUnavailable(_swap_hint(self.kind))
        params = {**params, **model_paths(self.kind, params)}
        self._params = self._make_params(params)
        self._tracker: Any = None
        self._last: Box = (math.nan,) * 4

    def _make_params(self, params: dict[str, Any]) -> Any:
        if not params:
            return None
        params_name = _FACTORIES[self.kind][1]
        cls = None if params_name is None else getattr(_cv2(), params_name, None)
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
        if self.kind in MODEL_ENV and (img.ndim == 2 or img.shape[2] == 1):
            return np.ascontiguousarray(np.repeat(img.reshape(img.shape[0], img.shape[1], 1), 3,
                                                  axis=2))
        return img

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
        img = self._colour(_frame(frame))
        ibox = _int_box(box, img.shape)
        _cv2().setRNGSeed(self.seed)
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


def split_specs(text: str | None) -> list[str]:
    """Split a comma-separated list of tracker specs, keeping commas inside brackets and quotes
    (``"rcwmil,rcwmil-plus:channels=('luma','grad')"`` is two specs), so that a
    tuple-valued override can be given on the command line. Empty items are dropped."""
    out: list[str] = []
    part: list[str] = []
    depth, quote = 0, ""
    for ch in text or "":
        if quote:
            quote = "" if ch == quote else quote
        elif ch in "'\"":
            quote = ch
        elif ch in "([{":
            depth += 1
        elif ch in ")]}":
            depth = max(depth - 1, 0)
        elif ch == "," and depth == 0:
            out.append("".join(part))
            part = []
            continue
        part.append(ch)
    out.append("".join(part))
    return [p.strip() for p in out if p.strip()]


#: The parameters that give a tracker a model file: left out of its label (:func:`tracker_labels`).
MODEL_KEYWORDS = frozenset({"backbone", "head", "neckhead", "net"})


def tracker_labels(specs: Sequence[str]) -> dict[str, str]:
    """Each spec's name in tables, plots and box folders: the spec without its model files
    (``opencv:Nano:backbone=/a/b.onnx:neckhead=/a/c.onnx`` is ``opencv:Nano``). Specs that
    differ only in their files keep the files' names (``:backbone=b.onnx``), and if that is
    not enough, their whole spec."""
    from collections import Counter
    from pathlib import PurePath

    def label(spec: str, with_files: bool) -> str:
        name, overrides = parse_spec(spec)
        parts = [name] + [f"{k}={_spec_text(spec, k)}" for k in overrides if k not in MODEL_KEYWORDS]
        if with_files:
            parts += [f"{k}={PurePath(str(v)).name}" for k, v in overrides.items()
                      if k in MODEL_KEYWORDS]
        return ":".join(parts)

    def clashing() -> list[str]:
        counts = Counter(out.values())
        return [s for s in out if counts[out[s]] > 1]

    out = {s: label(s, False) for s in specs}
    for s in clashing():
        out[s] = label(s, True)
    for s in clashing():
        out[s] = s.strip()
    return out


def _spec_text(spec: str, key: str) -> str:
    """The text of parameter ``key`` as written in ``spec`` (``"rcwmil:lr=0.85"``, ``"lr"``:
    ``"0.85"``)."""
    for part in spec.strip().split(":"):
        k, sep, text = part.partition("=")
        if sep and k.strip() == key:
            return text.strip()
    return ""


def parse_spec(spec: str) -> tuple[str, dict[str, Any]]:
    """Split a tracker spec into its name and its parameter overrides.

    ``"rcwmil:num_selected=30:learning_rate=0.85"`` gives ``("rcwmil", {"num_selected": 30,
    "learning_rate": 0.85})``; ``"opencv:MIL"`` stays ``("opencv:MIL", {})`` (a part without
    ``=`` belongs to the name).  Values are read with :func:`ast.literal_eval` (numbers,
    ``True``, tuples...) and kept as strings when that fails.

    Parameters
    ----------
    spec:
        The spec.

    Returns
    -------
    tuple
        ``(name, overrides)``.

    Raises
    ------
    ValueError
        An override with an empty key, or a key given twice.
    """
    import ast

    name_parts: list[str] = []
    overrides: dict[str, Any] = {}
    for part in spec.strip().split(":"):
        if "=" not in part:
            name_parts.append(part.strip())
            continue
        key, _, text = part.partition("=")
        key = key.strip()
        if not key.isidentifier():
            raise ValueError(f"bad override {part!r} in tracker spec {spec!r}: want name=value")
        if key in overrides:
            raise ValueError(f"{key!r} given twice in tracker spec {spec!r}")
        text = text.strip()
        try:
            overrides[key] = ast.literal_eval(text)
        except (ValueError, SyntaxError):
            overrides[key] = text
    return ":".join(name_parts), overrides


def make_tracker(spec: str, seed: int = 0, **params: Any) -> TrackerLike:
    """Create a tracker from a name.

    Parameters
    ----------
    spec:
        ``"opencv:NAME"`` (NAME case-insensitive, one of :data:`OPENCV_TRACKERS`) for an
        :class:`OpenCVTracker`; anything else is one of wmiltrack's presets (a key of
        :func:`wmiltrack.variants`, the preset registry) given to ``wmiltrack.Tracker``;
        either may end in ``:name=value`` overrides (``"rcwmil:num_selected=30"``, see
        :func:`parse_spec`), so a parameter sweep is a list of specs.
    seed:
        Random seed of the tracker.
    **params:
        Parameters of the tracker (OpenCV Params attributes, or ``wmiltrack.Tracker``'s);
        they take precedence over the spec's overrides.

    Returns
    -------
    TrackerLike
        An object with ``init(frame, box)`` and ``update(frame) -> TrackResult``.

    Raises
    ------
    ValueError
        Unknown OpenCV name (the message lists the valid ones), or a bad variant.
    TrackerUnavailable
        The OpenCV tracker is not in the installed ``cv2``.
    """
    s, overrides = parse_spec(spec)
    kw = {**overrides, **params}
    if s.lower().startswith(_PREFIX):
        return OpenCVTracker(s[len(_PREFIX) :], seed=seed, **kw)
    if s.lower().startswith(NANOTRACK_PREFIX):
        from .engine.siamese import NanoTracker

        return NanoTracker(s[len(NANOTRACK_PREFIX):].lower() or "v3", **kw)
    from .engine.params import variants

    presets = list(variants())
    if s.lower() not in presets:
        import difflib

        from .engine.siamese import NANO_VERSIONS

        nano = [f"{NANOTRACK_PREFIX}{v}" for v in NANO_VERSIONS]
        close = difflib.get_close_matches(
            s.lower(), presets + nano + [f"opencv:{n}" for n in OPENCV_TRACKERS], n=2)
        hint = f"did you mean {' or '.join(close)}? " if close else ""
        raise ValueError(f"unknown tracker {s!r}; {hint}choose one of {', '.join(presets)}, "
                         f"{' or '.join(nano)} (NanoTrack alone), or opencv:NAME with NAME one "
                         f"of {', '.join(OPENCV_TRACKERS)}")
    from .engine.tracker import Tracker  # the compiled core is loaded only now

    tracker: TrackerLike = Tracker(s, seed=seed, **kw)
    return tracker
