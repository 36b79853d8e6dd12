"""The tracking engine: parameters, feature banks, bag sampling, weak classifiers, feature
selection and the :class:`~wmiltrack.engine.tracker.Tracker` that walks one frame through them.

The pixel and feature work runs in the compiled core (:mod:`wmiltrack._core`); the modules here
orchestrate it. Each part's settings class lives in its part's module and is exported here
(``from wmiltrack.engine import ScaleSettings``), loaded on first use like the top level's
names, so that importing one engine module does not import them all.
"""

from __future__ import annotations

from importlib import import_module
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from .appearance import AppearanceSettings, SearchSettings
    from .classifier import ClassifierSettings
    from .colour import ColourSettings
    from .experts import ExpertSettings
    from .features import FeatureSettings
    from .judge import JudgeSettings
    from .motion import MotionSettings
    from .params import Params
    from .policy import ScoreSettings
    from .recovery import RecoverySettings
    from .sampling import BagSettings
    from .scale import ScaleSettings
    from .template import TemplateSettings

#: Each exported name -> the engine module that defines it.
_LAZY = {
    "AppearanceSettings": "appearance",
    "BagSettings": "sampling",
    "ClassifierSettings": "classifier",
    "ColourSettings": "colour",
    "ExpertSettings": "experts",
    "FeatureSettings": "features",
    "JudgeSettings": "judge",
    "MotionSettings": "motion",
    "Params": "params",
    "RecoverySettings": "recovery",
    "ScaleSettings": "scale",
    "ScoreSettings": "policy",
    "SearchSettings": "appearance",
    "TemplateSettings": "template",
}

__all__ = ["AppearanceSettings", "BagSettings", "ClassifierSettings", "ColourSettings", "ExpertSettings",
           "FeatureSettings", "JudgeSettings", "MotionSettings", "Params", "RecoverySettings",
           "ScaleSettings", "ScoreSettings", "SearchSettings", "TemplateSettings"]


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'wmiltrack.engine' has no attribute {name!r}")
    value = getattr(import_module(f".{module}", __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
