"""Warn when two OpenCV wheels are installed side by side.

wmiltrack depends on ``opencv-python-headless``.  Installing it where ``opencv-python`` or
``opencv-contrib-python`` (or their headless twins) is already installed puts a second copy of
the ``cv2`` package over the first: the four wheels write the same ``cv2/`` folder, so the one
installed last wins file by file (``cv2.imshow`` may vanish, contrib modules may go missing), and
uninstalling either later leaves a broken ``cv2``.  pip does not stop this.

:func:`warn_if_opencv_conflict` runs once when ``wmiltrack`` is imported, so both library users
(whose own ``cv2`` calls are the ones that break) and the command line (which imports the
package) see it; it costs under a millisecond (four :mod:`importlib.metadata` look-ups after the
one ``wmiltrack.__version__`` already made).  It emits :class:`OpenCVConflictWarning`, a
:class:`UserWarning`, as one line (at import it names ``wmiltrack`` as its source, not a line
of wmiltrack's code, which would be printed after it) with a one-line fix that installs the
matching version; silence it with
``warnings.filterwarnings("ignore", category=OpenCVConflictWarning)`` or
``python -W "ignore::UserWarning"``.  With only one OpenCV wheel installed nothing is emitted.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from importlib import metadata

__all__ = [
    "OPENCV_DISTRIBUTIONS",
    "OpenCVConflictWarning",
    "installed_opencv_distributions",
    "opencv_conflict_message",
    "warn_at_import",
    "warn_if_opencv_conflict",
]

OPENCV_DISTRIBUTIONS = (
    "opencv-python",
    "opencv-python-headless",
    "opencv-contrib-python",
    "opencv-contrib-python-headless",
)
"""The PyPI wheels that each install the top-level ``cv2`` package."""


class OpenCVConflictWarning(UserWarning):
    """More than one of :data:`OPENCV_DISTRIBUTIONS` is installed: they share one ``cv2``."""


def installed_opencv_distributions() -> list[str]:
    """Which of :data:`OPENCV_DISTRIBUTIONS` are installed, in that order (metadata only: ``cv2``
    is not imported)."""
    found = []
    for name in OPENCV_DISTRIBUTIONS:
        try:
            metadata.version(name)
        except metadata.PackageNotFoundError:
            continue
        found.append(name)
    return found


def opencv_conflict_message(installed: Sequence[str],
                            versions: Mapping[str, str] | None = None) -> str | None:
    """One line saying how to fix several OpenCV wheels installed together, or ``None`` for one.

    The fix removes every one of them (a lone uninstall would delete files the other needs) and
    installs the single wheel that covers what the installed ones offered: contrib modules if a
    contrib wheel was there, GUI functions if a non-headless one was, at the version installed
    (``versions``: each wheel's; the kept wheel's own, else that of an installed wheel of its
    kind, contrib or not), so that the fix does not also upgrade OpenCV.  wmiltrack runs with
    any of the four.
    """
    names = list(dict.fromkeys(installed))
    if len(names) < 2:
        return None
    contrib = any("contrib" in n for n in names)
    gui = any(not n.endswith("-headless") for n in names)
    keep = "opencv" + ("-contrib" if contrib else "") + "-python" + ("" if gui else "-headless")
    known = dict(versions or {})
    same_kind = [n for n in names if ("contrib" in n) == contrib and n in known]
    version = known.get(keep) or (known[same_kind[0]] if same_kind else None)
    pin = f"=={version}" if version else ""
    return (
        f"{' and '.join(names)} are installed together and overwrite each other's cv2; "
        f"fix: pip uninstall -y {' '.join(names)} && pip install {keep}{pin}"
    )


def _versions(names: Sequence[str]) -> dict[str, str]:
    """The installed version of each of ``names`` (metadata only)."""
    out = {}
    for name in names:
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            continue
    return out


def warn_if_opencv_conflict(stacklevel: int = 1) -> str | None:
    """Emit :class:`OpenCVConflictWarning` when several OpenCV wheels are installed.

    Parameters
    ----------
    stacklevel:
        Which frame the warning names: 1 the line calling this function, 2 its caller, ...

    Returns
    -------
    str or None
        The warning's message, or ``None`` when at most one OpenCV wheel is installed.
    """
    installed = installed_opencv_distributions()
    message = opencv_conflict_message(installed, _versions(installed))
    if message is not None:
        warnings.warn(message, OpenCVConflictWarning, stacklevel=stacklevel + 1)
    return message


def warn_at_import() -> str | None:
    """:func:`warn_if_opencv_conflict` as ``import wmiltrack`` runs it: the warning names
    ``wmiltrack`` as its source, so that it prints as one line (``wmiltrack:0:
    OpenCVConflictWarning: ...``) instead of being followed by a line of wmiltrack's own code,
    in every command of the command line as in a user's program; filters by category and
    module (``-W ignore::UserWarning``) work as before."""
    installed = installed_opencv_distributions()
    message = opencv_conflict_message(installed, _versions(installed))
    if message is not None:
        warnings.warn_explicit(message, OpenCVConflictWarning, "wmiltrack", 0, module="wmiltrack")
    return message
