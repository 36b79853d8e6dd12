"""Gaussian naive-Bayes weak classifiers, one per feature and class, updated online."""

from __future__ import annotations

import numpy as np

from .. import _learn
from .params import Params


class GaussianPool:
    """Class-conditional Gaussians N(mu1, sigma1) (target) and N(mu0, sigma0) (background).

    ``update`` follows spec section 1.1 (``classifier="gaussian"``: CT, FCT, WMIL, rcwmil)
    or section 1.2 (``classifier="mil"``: MILTrack), with lambda = ``learning_rate``
    weighting the old model.
    """

    def __init__(self, params: Params) -> None:
        m = params.num_features
        self.params = params
        self.mu1 = np.zeros(m)
        self.sigma1 = np.ones(m)
        self.mu0 = np.zeros(m)
        self.sigma0 = np.ones(m)
        self._seen = [False, False]  # has class 0 / 1 been updated yet

    def update(self, positives: np.ndarray, negatives: np.ndarray,
               learning_rate: float | None = None) -> None:
        """Fold in the feature values (M x n) of one frame's positive and negative samples.

        ``learning_rate`` (lambda, the old model's weight) defaults to the parameters'.
        """
        lam = self.params.learning_rate if learning_rate is None else learning_rate
        self.mu1, self.sigma1 = self._update_class(1, self.mu1, self.sigma1, positives, lam)
        self.mu0, self.sigma0 = self._update_class(0, self.mu0, self.sigma0, negatives, lam)

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

    def _update_class(self, cls: int, mu: np.ndarray, sigma: np.ndarray,
                      values: np.ndarray, lam: float) -> tuple[np.ndarray, np.ndarray]:
        if values.shape[1] == 0:  # no sample of this class in this frame: keep the model
            return mu, sigma
        p = self.params
        first = not self._seen[cls]
        self._seen[cls] = True
        new_mu, new_sigma = _learn.gaussian_update(
            np.asarray(values, dtype=np.float64), mu, sigma, lam, first,
            p.first_update == "direct", p.classifier == "mil", p.sigma_floor)
        return new_mu, new_sigma
