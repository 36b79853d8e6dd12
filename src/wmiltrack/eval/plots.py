"""Success and precision plots in the style of the OTB toolkit (matplotlib, Agg backend), and
an accuracy-speed plot.

Each tracker is one curve; the legend reads ``name [score]`` and is sorted by that score,
best first, as OTB's ``perfPlot.m`` does: the success plot is ranked by AUC (the mean of the
21 success-curve points), the precision plot by the precision at 20 px. The accuracy-speed
plot puts each tracker at its mean AUC against its update frames per second, both from the same
run, so that the trade-off between trackers is read at a glance.

matplotlib is an optional dependency (the ``eval`` extra).  :func:`require_matplotlib`
raises a :class:`RuntimeError` that tells the user to ``pip install "wmiltrack[eval]"``.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import numpy.typing as npt

from .metrics import PRECISION_THRESHOLDS, SUCCESS_THRESHOLDS

__all__ = [
    "INSTALL_HINT",
    "plot_accuracy_speed",
    "plot_precision",
    "plot_success",
    "ranked",
    "require_matplotlib",
]

INSTALL_HINT = 'plots need matplotlib: pip install "wmiltrack[eval]"'
"""Message of the error raised when matplotlib is missing."""

FloatArray = npt.NDArray[np.float64]

#: Up to this many curves the legend sits inside the axes (OTB's style); with more it would
#: cover the curves, so it goes beside them.
_LEGEND_INSIDE_MAX = 6


def require_matplotlib() -> Any:
    """Import matplotlib's pyplot with the non-interactive Agg backend.

    Returns
    -------
    module
        ``matplotlib.pyplot``.

    Raises
    ------
    RuntimeError
        If matplotlib is not installed; the message says how to install it.
    """
    try:
        import matplotlib
    except ImportError:
        raise RuntimeError(INSTALL_HINT) from None
    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    return plt


def ranked(scores: Mapping[str, float]) -> list[str]:
    """Tracker names ordered by score, best first (NaN scores last, ties by name).

    Parameters
    ----------
    scores:
        ``{tracker: score}``.

    Returns
    -------
    list of str
    """

    def key(name: str) -> tuple[bool, float, str]:
        s = float(scores[name])
        return (bool(np.isnan(s)), -s if not np.isnan(s) else 0.0, name)

    return sorted(scores, key=key)


def _plot(
    curves: Mapping[str, Sequence[float] | FloatArray],
    scores: Mapping[str, float],
    thresholds: FloatArray,
    path: str | os.PathLike[str],
    *,
    title: str,
    xlabel: str,
    ylabel: str,
    score_fmt: str,
    legend_loc: str,
    dpi: int,
) -> None:
    plt = require_matplotlib()
    outside = len(scores) > _LEGEND_INSIDE_MAX  # beside the axes, not over the curves
    fig, ax = plt.subplots(figsize=(7.4 if outside else 5.0, 3.9))
    styles = ["-", "--", "-.", ":"]
    try:
        for i, name in enumerate(ranked(scores)):
            y = np.asarray(curves[name], dtype=np.float64)
            ax.plot(
                thresholds,
                y,
                linestyle=styles[(i // 10) % len(styles)],
                linewidth=2.0 if i == 0 else 1.5,
                label=f"{name} [{format(float(scores[name]), score_fmt)}]",
            )
        ax.set_xlim(float(thresholds[0]), float(thresholds[-1]))
        ax.set_ylim(0.0, 1.0)
        ax.set_xlabel(xlabel)
        ax.set_ylabel(ylabel)
        ax.set_title(title, fontsize=10)
        ax.grid(True, linewidth=0.4, alpha=0.6)
        if outside:
            ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0,
                      fontsize=8, frameon=False)
        else:
            ax.legend(loc=legend_loc, fontsize=8, framealpha=0.85)
        fig.tight_layout()
        fig.savefig(os.fspath(path), dpi=dpi)
    finally:
        plt.close(fig)


def plot_success(
    curves: Mapping[str, Sequence[float] | FloatArray],
    aucs: Mapping[str, float],
    path: str | os.PathLike[str],
    *,
    title: str = "Success plots of OPE",
    dpi: int = 80,
) -> None:
    """Write the success plot (fraction of frames with IoU > t against t) as a PNG.

    Parameters
    ----------
    curves:
        ``{tracker: 21 success rates}`` at :data:`wmiltrack.eval.metrics.SUCCESS_THRESHOLDS`.
    aucs:
        ``{tracker: AUC}``: legend values and order (best first).
    path:
        Output file (``.png``).
    title:
        Plot title.
    dpi:
        Resolution (80 keeps the file around 30-40 KB).

    Raises
    ------
    RuntimeError
        If matplotlib is missing.
    """
    _plot(
        curves,
        aucs,
        SUCCESS_THRESHOLDS,
        path,
        title=title,
        xlabel="Overlap threshold",
        ylabel="Success rate",
        score_fmt=".3f",
        legend_loc="lower left",
        dpi=dpi,
    )


def plot_precision(
    curves: Mapping[str, Sequence[float] | FloatArray],
    precisions: Mapping[str, float],
    path: str | os.PathLike[str],
    *,
    title: str = "Precision plots of OPE",
    dpi: int = 80,
) -> None:
    """Write the precision plot (fraction of frames with centre error <= t px) as a PNG.

    Parameters
    ----------
    curves:
        ``{tracker: 51 precisions}`` at :data:`wmiltrack.eval.metrics.PRECISION_THRESHOLDS`.
    precisions:
        ``{tracker: precision at 20 px}``: legend values and order (best first).
    path:
        Output file (``.png``).
    title:
        Plot title.
    dpi:
        Resolution.

    Raises
    ------
    RuntimeError
        If matplotlib is missing.
    """
    _plot(
        curves,
        precisions,
        PRECISION_THRESHOLDS,
        path,
        title=title,
        xlabel="Location error threshold (px)",
        ylabel="Precision",
        score_fmt=".3f",
        legend_loc="lower right",
        dpi=dpi,
    )


def plot_accuracy_speed(
    aucs: Mapping[str, float],
    fps: Mapping[str, float],
    path: str | os.PathLike[str],
    *,
    title: str = "Accuracy and speed",
    dpi: int = 80,
) -> list[str]:
    """Write the accuracy-speed plot: one labelled point per tracker at (update frames per
    second, mean AUC), the speed axis logarithmic (trackers differ by orders of magnitude).

    Parameters
    ----------
    aucs:
        ``{tracker: mean success AUC}``.
    fps:
        ``{tracker: update frames per second}`` of the same run as ``aucs``.
    path:
        Output file (``.png``).
    title:
        Plot title.
    dpi:
        Resolution.

    Returns
    -------
    list of str
        The trackers plotted: those with a finite AUC and a positive, finite speed (a run
        scored from box files, ``--results``, has no speed).

    Raises
    ------
    RuntimeError
        If matplotlib is missing.
    ValueError
        If no tracker has both figures.
    """
    shown = [t for t in ranked(aucs)
             if t in fps and np.isfinite(float(aucs[t])) and np.isfinite(float(fps[t]))
             and float(fps[t]) > 0]
    if not shown:
        raise ValueError("no tracker has both an AUC and a speed to plot")
    plt = require_matplotlib()
    fig, ax = plt.subplots(figsize=(5.6, 3.9))
    try:
        xs = np.array([float(fps[t]) for t in shown])
        ys = np.array([float(aucs[t]) for t in shown])
        markers = ["o", "s", "^", "D", "v", "P", "X", "*"]
        for i, (name, x, y) in enumerate(zip(shown, xs, ys)):
            ax.scatter([x], [y], marker=markers[i % len(markers)], s=36, zorder=3)
            ax.annotate(name, (x, y), xytext=(4, 3), textcoords="offset points", fontsize=7)
        ax.set_xscale("log")
        lo, hi = float(xs.min()), float(xs.max())
        ax.set_xlim(lo / 2.0, hi * 3.0)  # room for the labels right of the fastest point
        ax.set_ylim(max(0.0, float(ys.min()) - 0.05), min(1.0, float(ys.max()) + 0.05))
        ax.set_xlabel("Update frames per second (log scale, same run)")
        ax.set_ylabel("Mean success AUC")
        ax.set_title(title, fontsize=10)
        ax.grid(True, which="both", linewidth=0.4, alpha=0.6)
        fig.tight_layout()
        fig.savefig(os.fspath(path), dpi=dpi)
    finally:
        plt.close(fig)
    return shown
