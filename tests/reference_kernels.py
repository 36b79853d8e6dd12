"""Plain numpy versions of the compiled learning kernels (Gaussian update, WMIL and MILBoost
selection), written from the spec for the tests to compare the compiled ones against."""

from __future__ import annotations

from typing import Any

import numpy as np


def _sigmoid(z: np.ndarray) -> np.ndarray:
    return 0.5 * (1.0 + np.tanh(0.5 * z))


def wmil_log_likelihood(H_pos: np.ndarray, H_neg: np.ndarray, w_pos: np.ndarray) -> float:
    """L = ln sum_j w_j sigma(H+_j) + ln sum_j (1 - sigma(H-_j)) (the weighted bag model)."""
    total = 0.0
    if H_pos.size:
        total += float(np.log(np.sum(w_pos * _sigmoid(H_pos))))
    if H_neg.size:
        total += float(np.log(np.sum(1.0 - _sigmoid(H_neg))))
    return total


def wmil_select_reference(h_pos: np.ndarray, h_neg: np.ndarray, w_pos: np.ndarray, k: int,
                          *, code_gradient: bool = False) -> np.ndarray:
    """Plain numpy version of ``engine.selection.wmil_select`` (for tests; not numerically hardened)."""
    m = h_pos.shape[0]
    H_pos = np.zeros(h_pos.shape[1])
    H_neg = np.zeros(h_neg.shape[1])
    chosen: list[int] = []
    for _ in range(k):
        sp = _sigmoid(H_pos)
        ws = w_pos * sp
        g_pos = ws * (1.0 - (ws if code_gradient else sp)) / ws.sum() if H_pos.size else H_pos
        sn = _sigmoid(H_neg)
        g_neg = -sn * (1.0 - sn) / (1.0 - sn).sum() if H_neg.size else H_neg
        score = h_pos @ g_pos + h_neg @ g_neg
        score[chosen] = -np.inf
        best = int(np.argmax(score))
        chosen.append(best)
        H_pos = H_pos + h_pos[best]
        H_neg = H_neg + h_neg[best]
    assert len(set(chosen)) == len(chosen) <= m
    return np.array(chosen, dtype=np.int32)


def milboost_nll(H_pos: np.ndarray, H_neg: np.ndarray, guard: float = 1e-5) -> float:
    """MILTrack's bag negative log-likelihood for strong-classifier outputs H."""
    pos = -np.log(1.0 - np.prod(1.0 - _sigmoid(H_pos)) + guard) / max(H_pos.size, 1)
    neg = -np.sum(np.log(guard + 1.0 - _sigmoid(H_neg))) / max(H_neg.size, 1)
    return float(pos + neg)


def milboost_select_reference(h_pos: np.ndarray, h_neg: np.ndarray, k: int, *,
                              guard: float = 1e-5) -> np.ndarray:
    """Plain numpy version of ``engine.selection.milboost_select``: evaluates the NLL for every candidate."""
    H_pos = np.zeros(h_pos.shape[1])
    H_neg = np.zeros(h_neg.shape[1])
    chosen: list[int] = []
    for _ in range(k):
        nll = np.array([
            np.inf if m in chosen else milboost_nll(H_pos + h_pos[m], H_neg + h_neg[m], guard)
            for m in range(h_pos.shape[0])
        ])
        best = int(np.argmin(nll))
        chosen.append(best)
        H_pos = H_pos + h_pos[best]
        H_neg = H_neg + h_neg[best]
    return np.array(chosen, dtype=np.int32)


def reference_update(mu: np.ndarray, sigma: np.ndarray, values: np.ndarray, lam: float,
                     first: bool, params: Any) -> tuple[np.ndarray, np.ndarray]:
    """Plain numpy version of one class's update (what the compiled kernel computes, bit
    for bit; for the tests)."""
    p = params
    mean = values.mean(axis=1)
    if p.classifier == "mil":
        # MILTrack: stores the variance; the first update is direct; later ones blend the
        # variance around the *updated* mean.
        if first:
            var = values.var(axis=1) + 1e-9
            new_mu = mean
        else:
            new_mu = lam * mu + (1.0 - lam) * mean
            var = lam * sigma**2 + (1.0 - lam) * ((values - new_mu[:, None]) ** 2).mean(axis=1)
        return new_mu, np.maximum(np.sqrt(var), p.sigma_floor)
    std = values.std(axis=1)
    if first and p.first_update == "direct":
        return mean, np.maximum(std, p.sigma_floor)
    new_sigma = np.sqrt(lam * sigma**2 + (1.0 - lam) * std**2 + lam * (1.0 - lam) * (mu - mean) ** 2)
    new_mu = lam * mu + (1.0 - lam) * mean
    return new_mu, np.maximum(new_sigma, p.sigma_floor)


# ---------------------------------------------------------------------- colour contrast
def box_means(table: np.ndarray, x0: int, y0: int, xs: np.ndarray, ys: np.ndarray, w: int, h: int) -> np.ndarray:
    """Mean over the ``w x h`` boxes with top-left corners ``(xs, ys)`` (frame coordinates, inside
    the region) of an integral table whose region starts at ``(x0, y0)``."""
    cx = np.asarray(xs, dtype=np.intp) - x0
    cy = np.asarray(ys, dtype=np.intp) - y0
    s = table[cy + h, cx + w] - table[cy, cx + w] - table[cy + h, cx] + table[cy, cx]
    return s / float(w * h)


def box_sums_clipped(table: np.ndarray, x0: int, y0: int, boxes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Sums and areas of boxes ``(n, 4)`` (x, y, w, h in frame coordinates) clipped to the
    table's region."""
    th, tw = table.shape[0] - 1, table.shape[1] - 1
    b = np.asarray(boxes, dtype=np.intp)
    xa = np.clip(b[:, 0] - x0, 0, tw)
    ya = np.clip(b[:, 1] - y0, 0, th)
    xb = np.clip(b[:, 0] + b[:, 2] - x0, 0, tw)
    yb = np.clip(b[:, 1] + b[:, 3] - y0, 0, th)
    s = table[yb, xb] - table[ya, xb] - table[yb, xa] + table[ya, xa]
    return s, ((xb - xa) * (yb - ya)).astype(np.float64)


def colour_contrast(table: np.ndarray, x0: int, y0: int, boxes: np.ndarray, ring: float = 0.25) -> np.ndarray:
    """Vectorised ``engine.colour.box_contrast`` of every box: mean ``P(target | colour)`` inside
    minus its mean over a ring ``ring * (w + h) / 2`` wide, both clipped to the table's region."""
    b = np.asarray(boxes, dtype=np.intp)
    pad = np.maximum(1, np.rint(ring * (b[:, 2] + b[:, 3]) / 2.0)).astype(np.intp)
    outer = np.stack([b[:, 0] - pad, b[:, 1] - pad, b[:, 2] + 2 * pad, b[:, 3] + 2 * pad], axis=1)
    s_in, a_in = box_sums_clipped(table, x0, y0, b)
    s_out, a_out = box_sums_clipped(table, x0, y0, outer)
    return s_in / np.maximum(a_in, 1.0) - (s_out - s_in) / np.maximum(a_out - a_in, 1.0)
