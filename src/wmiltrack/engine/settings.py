"""What every part's settings share: :func:`own`, the checks their ``check`` methods are made
of, and the limit two parts' settings share.

Each part of a tracker has one small frozen dataclass of settings, in the part's own module,
that documents and checks its fields: :class:`~wmiltrack.engine.features.FeatureSettings`,
:class:`~wmiltrack.engine.sampling.BagSettings`,
:class:`~wmiltrack.engine.classifier.ClassifierSettings`,
:class:`~wmiltrack.engine.appearance.SearchSettings` and
:class:`~wmiltrack.engine.appearance.AppearanceSettings` (the four at once),
:class:`~wmiltrack.engine.scale.ScaleSettings`, :class:`~wmiltrack.engine.motion.MotionSettings`,
:class:`~wmiltrack.engine.colour.ColourSettings`, :class:`~wmiltrack.engine.policy.ScoreSettings`,
:class:`~wmiltrack.engine.template.TemplateSettings`,
:class:`~wmiltrack.engine.recovery.RecoverySettings`, :class:`~wmiltrack.engine.judge.JudgeSettings`
and :class:`~wmiltrack.engine.experts.ExpertSettings` (all of them importable from
:mod:`wmiltrack.engine`). :class:`~wmiltrack.Params` (:mod:`wmiltrack.engine.params`), the public
face, is all of them at once (it inherits every class), so ``Tracker("fct", num_features=200)``
and ``--set key=value`` keep one flat namespace while every setting is documented and checked
in exactly one place: the class that owns it.

Every default is rcwmil's (the paper's tracker); a part whose defaults leave it off (scale,
motion, colour, the reported score's contrasts) is not built at all, so the paper presets run
the paper's code path.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any, TypeVar

__all__ = ["MAX_SEARCH_RADIUS", "check_choices", "check_ints", "check_numbers", "is_int", "is_number",
           "need", "own"]

MAX_SEARCH_RADIUS = 1000
"""Largest search radius (``coarse_radius``, ``fine_radius``; the motion model's ``motion_max``)."""


_S = TypeVar("_S")


def own(cls: type[_S], params: Any) -> _S:
    """The settings of one part: a ``cls`` (a part's settings class) holding ``params``'s values
    of ``cls``'s fields and nothing else. :func:`~wmiltrack.engine.tracker.compose` builds each
    part with its own, so a part cannot read another part's settings."""
    return cls(**{f.name: getattr(params, f.name) for f in dataclasses.fields(cls)})  # type: ignore[arg-type]


def need(ok: bool, message: str) -> None:
    """``ValueError(message)`` unless ``ok``."""
    if not ok:
        raise ValueError(message)


def is_int(v: Any) -> bool:
    """An int, not a bool."""
    return isinstance(v, int) and not isinstance(v, bool)


def is_number(v: Any) -> bool:
    """A finite int or float, not a bool."""
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def check_choices(obj: Any, choices: dict[str, tuple[str, ...]]) -> None:
    """Each named field of ``obj`` is one of its allowed values."""
    for name, allowed in choices.items():
        value = getattr(obj, name)
        need(value in allowed, f"{name} must be one of {', '.join(map(repr, allowed))}; got {value!r}")


def check_ints(obj: Any, *names: str) -> None:
    """Each named field of ``obj`` is an int (not a bool)."""
    for name in names:
        need(is_int(getattr(obj, name)), f"{name} must be an int, got {getattr(obj, name)!r}")


def check_numbers(obj: Any, *names: str) -> None:
    """Each named field of ``obj`` is a finite number (not a bool)."""
    for name in names:
        v = getattr(obj, name)
        need(is_number(v), f"{name} must be a finite number, got {v!r}")
