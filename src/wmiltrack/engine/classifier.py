"""Gaussian naive-Bayes weak classifiers, one per feature and class, updated online."""

from __future__ import annotations

import numpy as np

from .settings import AppearanceSettings


class GaussianPool:
    """Class-conditional Gaussians N(mu1, sigma1) (target) and N(mu0, sigma0) (background).

    The core's learning step updates them (``_core.learn``: spec section 1.1 for
    ``classifier="gaussian"``, CT, FCT, WMIL, rcwmil; section 1.2 for ``classifier="mil"``,
    MILTrack; lambda = ``learning_rate`` weighting the old model) and hands the result to
    :meth:`assign`.
    """

    def __init__(self, params: AppearanceSettings | int) -> None:
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
