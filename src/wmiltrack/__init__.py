"""wmiltrack: fast single-object visual tracking by online weighted multiple-instance learning.

The public names are loaded on first use, so that ``import wmiltrack.eval.metrics`` and the
command line start quickly and work even before the compiled core is needed.
"""

from __future__ import annotations

from importlib import import_module
from importlib.metadata import PackageNotFoundError, version
from typing import TYPE_CHECKING, Any

try:
    __version__ = version("wmiltrack")
except PackageNotFoundError:  # running from a source tree that was never installed
    __version__ = "0+unknown"

from .engine.result import TrackResult
from .opencv_check import warn_at_import

warn_at_import()  # two OpenCV wheels share one cv2: say how to fix it, in one line

if TYPE_CHECKING:
    from .engine.cues import Cue
    from .engine.multi import MultiTracker
    from .engine.params import Params, variants
    from .engine.tracker import Tracker

_LAZY = {
    "Cue": "engine.cues",
    "MultiTracker": "engine.multi",
    "Tracker": "engine.tracker",
    "Params": "engine.params",
    "variants": "engine.params",
}

__all__ = ["Cue", "MultiTracker", "Params", "TrackResult", "Tracker", "__version__", "variants"]


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'wmiltrack' has no attribute {name!r}")
    value = getattr(import_module(f".{module}", __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(__all__)
