"""Gaussian naive-Bayes weak classifiers, one per feature and class, updated online."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, Protocol

import numpy as np

from .settings import check_choices, check_numbers, need

__all__ = ["CONFIDENCE_OFFSET", "ClassifierSettings", "GaussianPool"]

#: Default of ``confidence_offset``: the mean weak-classifier log ratio at which a frame is as
#: likely tracked (IoU > 0) as lost. A class-balanced logistic fit of "IoU > 0" on the mean log
#: ratio over 17 OTB sequences and 6 generated full-occlusion/vanishing sequences gave offsets
#: 1.25-1.63 and gains 0.8-1.1 for five variants (``scripts/score_study.py``).
CONFIDENCE_OFFSET = 1.4


@dataclass(frozen=True)
class ClassifierSettings:
    """The online Gaussian weak classifiers and how the strong classifier's features are chosen.

    Attributes
    ----------
    learning_rate : float
        lambda in [0, 1): weight of the old model in the Gaussian update.
    classifier : {"gaussian", "mil"}
        ``gaussian``: std-based update of CT/FCT/WMIL (spec 1.1); ``mil``: MILTrack's
        variance-based update (spec 1.2).
    first_update : {"direct", "blend"}
        ``direct``: the first frame sets mu and sigma from the samples; ``blend``: the
        references' quirk of blending them into (0, 1).
    sigma_floor : float
        Lower bound of every sigma.
    guard : float
        The epsilon added to each likelihood before the log (1e-30 CT family, 1e-5 MIL).
    selection : {"wmil", "milboost", "none"}
        Weighted-MIL gradient selection, MILBoost's Noisy-OR likelihood selection, or all
        features (CT, FCT; then ``num_selected`` must equal ``num_features``).
    instance_weights : {"exp", "exp_sq", "uniform"}
        Positive-bag weights: exp(-d) normalised (paper), exp(-d^2) unnormalised (WMIL
        reference code), or equal weights (OSIL).
    gradient : {"paper", "code"}
        WMIL selection gradient w s (1 - s) / sum(w s) (paper) or the reference code's
        w s (1 - w s) / sum(w s).
    confidence_offset : float
        Offset of the confidence ``logistic(raw / K - offset)`` (see
        :func:`wmiltrack.engine.policy.confidence`).
    """

    learning_rate: float = 0.9
    classifier: Literal["gaussian", "mil"] = "gaussian"
    first_update: Literal["direct", "blend"] = "direct"
    sigma_floor: float = 1e-6
    guard: float = 1e-30
    selection: Literal["wmil", "milboost", "none"] = "wmil"
    instance_weights: Literal["exp", "exp_sq", "uniform"] = "exp"
    gradient: Literal["paper", "code"] = "paper"
    confidence_offset: float = CONFIDENCE_OFFSET

    def __post_init__(self) -> None:
        ClassifierSettings.check(self)

    def check(self) -> None:
        """``ValueError`` naming the first setting out of range."""
        check_choices(self, {"classifier": ("gaussian", "mil"), "first_update": ("direct", "blend"),
                              "selection": ("wmil", "milboost", "none"),
                              "instance_weights": ("exp", "exp_sq", "uniform"),
                              "gradient": ("paper", "code")})
        check_numbers(self, "learning_rate", "sigma_floor", "guard", "confidence_offset")
        need(0.0 <= self.learning_rate < 1.0,
             f"learning_rate (lambda) must be in [0, 1), got {self.learning_rate}")
        need(self.sigma_floor > 0, f"sigma_floor must be > 0, got {self.sigma_floor}")
        need(self.guard > 0, f"guard must be > 0, got {self.guard}")


class _PoolSettings(Protocol):
    """What a pool reads of the appearance model's settings
    (:class:`~wmiltrack.engine.appearance.AppearanceSettings`, which holds these): the number
    of features."""

    @property
    def num_features(self) -> int: ...


class GaussianPool:
    """Class-conditional Gaussians N(mu1, sigma1) (target) and N(mu0, sigma0) (background).

    The core's learning step updates them (``_core.learn``: spec section 1.1 for
    ``classifier="gaussian"``, CT, FCT, WMIL, rcwmil; section 1.2 for ``classifier="mil"``,
    MILTrack; lambda = ``learning_rate`` weighting the old model) and hands the result to
    :meth:`assign`.
    """

    def __init__(self, params: _PoolSettings | int) -> None:
        """``params``: the appearance model's parameters (kept as :attr:`params`), or just a
        number of features (a model outside the appearance model's learning rules)."""
        m = params if isinstance(params, int) else params.num_features
        self.params = None if isinstance(params, int) else params
        self.mu1 = np.zeros(m)
        self.sigma1 = np.ones(m)
        self.mu0 = np.zeros(m)
        self.sigma0 = np.ones(m)
        self._seen = [False, False]  # has class 0 / 1 been updated yet

    def first(self, cls: int) -> bool:
        """Whether class ``cls`` (1 target, 0 background) has not been updated yet."""
        return not self._seen[cls]

    def assign(self, mu1: np.ndarray, sigma1: np.ndarray, mu0: np.ndarray, sigma0: np.ndarray,
               updated_pos: bool, updated_neg: bool) -> None:
        """Take the model that a frame's update computed elsewhere (the core's one-call
        learning step, ``_core.learn``), with which classes it updated."""
        self.mu1, self.sigma1, self.mu0, self.sigma0 = mu1, sigma1, mu0, sigma0
        self._seen[1] = self._seen[1] or updated_pos
        self._seen[0] = self._seen[0] or updated_neg
