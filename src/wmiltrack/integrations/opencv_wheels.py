"""OpenCV's trackers and the wheels that have them: their names, their factories in ``cv2``, which
wheel the installed ``cv2`` is, and what to do when a tracker is missing from it.

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
"""

from __future__ import annotations

from importlib import import_module
from importlib.metadata import PackageNotFoundError, version
from typing import Any

__all__ = [
    "OPENCV_TRACKERS",
    "TrackerUnavailable",
    "available_opencv_trackers",
    "installed_opencv",
    "opencv_factory",
    "opencv_params_class",
    "parse_opencv_name",
    "swap_hint",
]

#: Names of the OpenCV trackers that :class:`~wmiltrack.integrations.opencv_peers.OpenCVTracker` wraps.
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

_PREFIX = "opencv:"


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
    has_contrib = opencv_factory("KCF") is not None
    for dist in (*contrib, *plain) if has_contrib else (*plain, *contrib):
        try:
            return dist, version(dist)
        except PackageNotFoundError:
            continue
    return "opencv-python-headless", str(getattr(_cv2(), "__version__", "<version>"))


def swap_hint(name: str) -> str:
    """What to do about tracker ``name`` missing from the installed ``cv2``: the commands that
    swap the plain wheel for the contrib one (and back)."""
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


def opencv_factory(name: str) -> Any:
    """The factory of tracker ``name`` in the installed ``cv2``, or None where it has none."""
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
    return [n for n in OPENCV_TRACKERS if opencv_factory(n) is not None]


def opencv_params_class(name: str) -> Any:
    """The ``cv2.Tracker*_Params`` class of tracker ``name`` (one of :data:`OPENCV_TRACKERS`),
    or None where it takes no parameters."""
    params_name = _FACTORIES[name][1]
    return None if params_name is None else getattr(_cv2(), params_name, None)
