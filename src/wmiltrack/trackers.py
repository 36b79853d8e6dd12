"""The tracker specs, shared by the command line, the evaluation and the benchmarks.

A spec names a tracker and may set its parameters: ``"rcwmil"``, ``"rcwmil-plus:scale_steps=2"``
(one of wmiltrack's presets, see :func:`wmiltrack.variants`), ``"opencv:KCF"`` (one of OpenCV's
trackers, :mod:`wmiltrack.integrations.opencv_peers`) or ``"nanotrack:v3"`` (NanoTrack alone,
:mod:`wmiltrack.integrations.nanotrack_peer`). :func:`make_tracker` turns a spec into an object
with the two methods ``init(frame, box)`` and ``update(frame) -> TrackResult``, so the code that
runs trackers never needs to know which library one comes from; :func:`parse_spec` and
:func:`split_specs` read specs from the command line. It lives outside ``eval/`` so that
tracking a video does not depend on the evaluation package.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from .engine.result import TrackerLike
from .integrations.opencv_wheels import OPENCV_TRACKERS

__all__ = [
    "NANOTRACK_PREFIX",
    "OPENCV_PREFIX",
    "is_opencv_spec",
    "make_tracker",
    "network_runtime",
    "parse_spec",
    "split_specs",
    "tracker_labels",
]

OPENCV_PREFIX = "opencv:"
"""``opencv:NAME``: one of OpenCV's trackers
(:data:`~wmiltrack.integrations.opencv_wheels.OPENCV_TRACKERS`)."""

#: ``nanotrack:v2`` / ``nanotrack:v3``: NanoTrack alone by its published tracking step
#: (:class:`~wmiltrack.integrations.nanotrack_peer.NanoTracker`; keyword overrides ``backbone``,
#: ``head``, ``runtime``, ``threads``); deterministic, so ``seed`` is not used.
NANOTRACK_PREFIX = "nanotrack:"


def is_opencv_spec(spec: str) -> bool:
    """Whether a tracker spec names one of OpenCV's trackers (``"opencv:..."``)."""
    return spec.strip().lower().startswith(OPENCV_PREFIX)


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
        :class:`~wmiltrack.integrations.opencv_peers.OpenCVTracker`; ``"nanotrack:VERSION"``
        for a :class:`~wmiltrack.integrations.nanotrack_peer.NanoTracker`; anything else is one
        of wmiltrack's presets (a key of :func:`wmiltrack.variants`, the preset registry) given
        to ``wmiltrack.Tracker``;
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
    wmiltrack.integrations.opencv_wheels.TrackerUnavailable
        The OpenCV tracker is not in the installed ``cv2``.
    """
    s, overrides = parse_spec(spec)
    kw = {**overrides, **params}
    if s.lower().startswith(OPENCV_PREFIX):
        from .integrations.opencv_peers import OpenCVTracker

        return OpenCVTracker(s[len(OPENCV_PREFIX) :], seed=seed, **kw)
    if s.lower().startswith(NANOTRACK_PREFIX):
        from .integrations.nanotrack_peer import NanoTracker

        return NanoTracker(s[len(NANOTRACK_PREFIX):].lower() or "v3", **kw)
    from .engine.params import variants

    presets = list(variants())
    if s.lower() not in presets:
        import difflib

        from .networks.files import nanotrack_versions

        nano = [f"{NANOTRACK_PREFIX}{v}" for v in nanotrack_versions()]
        close = difflib.get_close_matches(
            s.lower(), presets + nano + [f"opencv:{n}" for n in OPENCV_TRACKERS], n=2)
        hint = f"did you mean {' or '.join(close)}? " if close else ""
        raise ValueError(f"unknown tracker {s!r}; {hint}choose one of {', '.join(presets)}, "
                         f"{' or '.join(nano)} (NanoTrack alone), or opencv:NAME with NAME one "
                         f"of {', '.join(OPENCV_TRACKERS)}")
    from .engine.tracker import Tracker  # the compiled core is loaded only now

    tracker: TrackerLike = Tracker(s, seed=seed, **kw)
    return tracker


def network_runtime(tracker: Any) -> str | None:
    """The runtime that runs ``tracker``'s network (one :func:`make_tracker` made):
    ``"onnxruntime"`` or ``"opencv"`` (OpenCV's dnn), or None for a tracker without a network.
    The boxes of a network tracker are the same for the same runtime and version only."""
    from .networks.backends import choose_runtime

    runtime = getattr(tracker, "runtime", None)  # NanoTrack alone
    if isinstance(runtime, str):
        return runtime
    if getattr(tracker, "kind", None) in ("Nano", "Vit"):  # OpenCV's network trackers
        return "opencv"
    params: Any = getattr(tracker, "params", None)
    if params is not None and params.network:
        return choose_runtime(params.network_runtime, params.network_threads)
    return None
