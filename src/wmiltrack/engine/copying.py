"""``copy.deepcopy`` of the compiled core's objects, so that a started tracker can be forked.

A user who wants to try two hypotheses from the same state copies the tracker
(``copy.deepcopy(tracker)``); the copy must go on exactly as the original would, and
independently of it. The core's classes have no copy protocol of their own, so it is given here:

* the models that learn from frame to frame (colour histograms, correlation and scale filters)
  are copied with their own ``copy()``;
* a feature bank, a sample's spectrum and a filter's response never change once made: the copy
  shares them;
* an integral image is scratch space, rebuilt from the frame before every read: the copy gets
  an empty one (pickling gives an empty one too).

Pickling (to another process or to disk) works for the trackers made of the appearance model
alone (the paper presets); the learning models above have no serialised form in the core, so
pickling a started tracker that holds one raises a ``TypeError`` that says so.

Importing this module installs the hooks (:mod:`wmiltrack.engine.tracker` does).
"""

from __future__ import annotations

import copyreg
from typing import Any

from .. import _core

__all__: list[str] = []


def _own_copy(self: Any, memo: dict[int, Any]) -> Any:
    """A model that learns: an independent copy of it as it is now."""
    return self.copy()


def _shared(self: Any, memo: dict[int, Any]) -> Any:
    """An object that never changes once made: the copy shares it."""
    return self


def _empty_integral(self: Any, memo: dict[int, Any]) -> Any:
    """An integral image: scratch, recomputed before every read."""
    return _core.IntegralImage()


def _reduce_integral(ii: Any) -> tuple[Any, tuple[()]]:
    return _core.IntegralImage, ()


def _no_pickle(obj: Any) -> Any:
    """Pickling one of the core's learning models: a ``TypeError`` that says why and what to
    do instead."""
    raise TypeError(
        f"a started tracker that holds {type(obj).__name__} (colour histograms or correlation "
        "filters: rcwmil-plus, rcwmil-cf) cannot be pickled, as the compiled core has no "
        "serialised form of them; copy.deepcopy(tracker) forks it within this process, and "
        "a tracker pickled before init() can be started anywhere")


def _install() -> None:
    for name in ("ColourHistograms", "TranslationFilter", "ScaleFilter"):
        getattr(_core, name).__deepcopy__ = _own_copy
        copyreg.pickle(getattr(_core, name), _no_pickle)
    for name in ("FeatureBank", "Spectrum", "TranslationResponse", "ScaleResponse"):
        getattr(_core, name).__deepcopy__ = _shared
    _core.IntegralImage.__deepcopy__ = _empty_integral  # type: ignore[attr-defined]
    copyreg.pickle(_core.IntegralImage, _reduce_integral)


_install()
