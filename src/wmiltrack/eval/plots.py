"""Success and precision plots in the style of the OTB toolkit (matplotlib, Agg backend), and
an accuracy-speed plot.

Each tracker is one curve; the legend reads ``name [score]`` and is sorted by that score,
best first, as OTB's ``perfPlot.m`` does, but a tracker's colour, line style and marker are
fixed by the order the trackers were given (:func:`tracker_styles`), so that it looks the same
in every plot of a run whatever each plot's ranking: the success plot is ranked by AUC (the mean of the
21 success-curve points), the precision plot by the precision at 20 px. The accuracy-speed
plot puts each tracker at its mean AUC against its update frames per second, both from the same
run, so that the trade-off between trackers is read at a glance; its labels are placed so that
none overlaps another or leaves the axes (:func:`place_labels`). The long-term protocol's plots
are the tracking precision-recall curve and the F-score bars. Every plot is written at
:data:`DPI` (150) dots per inch.

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
    "DPI",
    "INSTALL_HINT",
    "accuracy_speed_figure",
    "place_labels",
    "plot_accuracy_speed",
    "plot_fscore_bars",
    "plot_precision_recall",
    "plot_precision",
    "plot_success",
    "ranked",
    "require_matplotlib",
    "speed_text",
    "tracker_styles",
]

INSTALL_HINT = 'plots need matplotlib: pip install "wmiltrack[eval]"'
"""Message of the error raised when matplotlib is missing."""

FloatArray = npt.NDArray[np.float64]

#: Resolution of every plot: a 5 x 3.9 inch figure is 750 x 585 pixels, readable on a page.
DPI = 150

#: Distances (pixels) from its point at which a label is tried, nearest first.
_LABEL_RADII = (5, 9, 14, 20, 28, 38, 50, 65, 82, 100, 125, 150, 180, 215, 255, 300)
#: Directions (degrees) tried at each distance: right first, then up and down, left last.
_LABEL_ANGLES = (0, 30, -30, 60, -60, 90, -90, 120, -120, 150, -150, 180)
#: Gap (pixels) kept around every label and marker.
_LABEL_PAD = 1.5

#: Colours of the trackers in the order given (matplotlib's ``tab10``); past ten they come round
#: again with the next line style (:data:`_LINE_STYLES`).
_COLOURS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2",
            "#7f7f7f", "#bcbd22", "#17becf")
_LINE_STYLES = ("-", "--", "-.", ":")
#: Markers of the accuracy-speed points, in the order given.
_MARKERS = ("o", "s", "^", "D", "v", "P", "X", "*")

#: Tick sets tried on the speed axis, densest first: the mantissas labelled in a decade, and
#: every how many decades; the first whose labels stand apart is kept (:func:`_speed_ticks`).
_SPEED_TICKS: tuple[tuple[tuple[float, ...], int], ...] = (
    ((1.0, 2.0, 5.0), 1), ((1.0, 3.0), 1), ((1.0,), 1), ((1.0,), 2), ((1.0,), 3))
#: Least gap (pixels) between two tick labels of the speed axis.
_TICK_GAP = 4.0

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


def tracker_styles(names: Sequence[str]) -> dict[str, dict[str, str]]:
    """Each tracker's ``color``, ``linestyle`` and ``marker``, fixed by its place in ``names``
    (the order the trackers were given on the command line), so that a tracker has one look in
    every plot of a run: the plots rank their legends by their own scores, which differ.

    Parameters
    ----------
    names:
        The trackers, in the order given (a name given twice keeps its first place).

    Returns
    -------
    dict
        ``{tracker: {"color": ..., "linestyle": ..., "marker": ...}}``.
    """
    unique = list(dict.fromkeys(names))
    return {
        name: {
            "color": _COLOURS[i % len(_COLOURS)],
            "linestyle": _LINE_STYLES[(i // len(_COLOURS)) % len(_LINE_STYLES)],
            "marker": _MARKERS[i % len(_MARKERS)],
        }
        for i, name in enumerate(unique)
    }


def _styles_for(names: Sequence[str], order: Sequence[str] | None) -> dict[str, dict[str, str]]:
    """:func:`tracker_styles` of ``order`` (default: ``names`` as given), with any of ``names``
    that ``order`` leaves out after it."""
    return tracker_styles([*(order if order is not None else ()), *names])


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
    order: Sequence[str] | None,
) -> None:
    plt = require_matplotlib()
    outside = len(scores) > _LEGEND_INSIDE_MAX  # beside the axes, not over the curves
    fig, ax = plt.subplots(figsize=(7.4 if outside else 5.0, 3.9))
    styles = _styles_for(list(scores), order)
    try:
        for i, name in enumerate(ranked(scores)):
            y = np.asarray(curves[name], dtype=np.float64)
            ax.plot(
                thresholds,
                y,
                color=styles[name]["color"],
                linestyle=styles[name]["linestyle"],
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
    dpi: int = DPI,
    order: Sequence[str] | None = None,
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
        Resolution (:data:`DPI`).
    order:
        The trackers in the order given, which fixes their colours (:func:`tracker_styles`);
        default: the order of ``aucs``.

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
        order=order,
    )


def plot_precision(
    curves: Mapping[str, Sequence[float] | FloatArray],
    precisions: Mapping[str, float],
    path: str | os.PathLike[str],
    *,
    title: str = "Precision plots of OPE",
    dpi: int = DPI,
    order: Sequence[str] | None = None,
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
    order:
        The trackers in the order given, which fixes their colours (:func:`tracker_styles`);
        default: the order of ``precisions``.

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
        order=order,
    )


def _free(box: Any, area: Any, taken: Sequence[Any]) -> bool:
    """Whether the text box ``box`` lies inside ``area`` and overlaps nothing in ``taken``."""
    inside = (box.x0 >= area.x0 and box.y0 >= area.y0 and box.x1 <= area.x1
              and box.y1 <= area.y1)
    return inside and not any(box.overlaps(t) for t in taken)


def _alignment(angle: float) -> tuple[str, str]:
    """Text alignment that puts a label on the side of its point that ``angle`` points to."""
    c, s = np.cos(np.radians(angle)), np.sin(np.radians(angle))
    ha = "left" if c > 0.3 else "right" if c < -0.3 else "center"
    va = "bottom" if s > 0.3 else "top" if s < -0.3 else "center"
    return ha, va


def place_labels(ax: Any, xs: Sequence[float], ys: Sequence[float], labels: Sequence[str],
                 *, fontsize: float = 8.0) -> list[Any]:
    """Write one label beside each point so that no two labels overlap, no label covers a
    point's marker, and every label lies inside the axes.

    Each label in turn is tried at growing distances from its point (:data:`_LABEL_RADII`) in
    several directions (:data:`_LABEL_ANGLES`), and takes the first place where its drawn text
    box, as the figure's renderer measures it, is free; a label put more than 20 pixels away
    gets a thin line to its point. A label that finds no place at its size is tried one point
    smaller (down to 5 pt). Call it after the axes' limits and the figure's layout are final:
    the places are in pixels.

    Parameters
    ----------
    ax:
        The matplotlib axes, points already drawn.
    xs, ys:
        The points, in data coordinates.
    labels:
        One label per point.
    fontsize:
        Points.

    Returns
    -------
    list of matplotlib.text.Annotation
        The labels, in the order given.

    Raises
    ------
    ValueError
        Lengths that differ.
    RuntimeError
        A label that fits nowhere even at 5 pt (more labels than the axes can hold).
    """
    if not len(xs) == len(ys) == len(labels):
        raise ValueError(f"{len(xs)} x, {len(ys)} y and {len(labels)} labels: give one of each "
                         "per point")
    fig = ax.figure
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    area = ax.get_window_extent(renderer)
    from matplotlib.transforms import Bbox

    points = ax.transData.transform(np.column_stack([xs, ys]).astype(np.float64))

    half = 4.0 + _LABEL_PAD  # a marker's half size in pixels, with the gap
    taken: list[Any] = [Bbox.from_extents(px - half, py - half, px + half, py + half)
                        for px, py in points]
    per_pixel = 72.0 / fig.dpi  # offset points per pixel
    texts = []
    for x, y, label in zip(xs, ys, labels):
        placed = None
        size = fontsize
        while placed is None and size >= 5.0:
            text = ax.annotate(label, (x, y), xytext=(0.0, 0.0), textcoords="offset points",
                               fontsize=size)
            placed = _first_free(text, renderer, area, taken, per_pixel)
            if placed is None:
                text.remove()
                size -= 1.0
        if placed is None:
            raise RuntimeError(f"no room for the label {label!r}: the plot holds too many points "
                               "close together")
        text, box, (dx, dy) = placed
        taken.append(box.padded(_LABEL_PAD))
        if np.hypot(dx, dy) > 20.0:
            ax.annotate("", (x, y), xytext=(dx * per_pixel, dy * per_pixel),
                        textcoords="offset points",
                        arrowprops={"arrowstyle": "-", "linewidth": 0.5, "color": "0.45",
                                    "shrinkA": 0.0, "shrinkB": 3.0})
        texts.append(text)
    return texts


def _first_free(text: Any, renderer: Any, area: Any, taken: Sequence[Any], per_pixel: float
                ) -> tuple[Any, Any, tuple[float, float]] | None:
    """Move ``text`` to the first free place around its point: ``(text, box, offset)``."""
    for r in _LABEL_RADII:
        for angle in _LABEL_ANGLES:
            dx, dy = r * np.cos(np.radians(angle)), r * np.sin(np.radians(angle))
            ha, va = _alignment(angle)
            text.set_horizontalalignment(ha)
            text.set_verticalalignment(va)
            text.set_position((dx * per_pixel, dy * per_pixel))
            box = text.get_window_extent(renderer)
            if _free(box.padded(_LABEL_PAD), area, taken):
                return text, box, (dx, dy)
    return None


def speed_text(v: float) -> str:
    """A speed-axis tick label: a plain number (``0.5``, ``20``, ``1000``), read at a glance
    where ``2×10¹`` is not."""
    return f"{v:.0f}" if v >= 1.0 else f"{v:g}"


def _tick_labels_apart(fig: Any, ax: Any) -> bool:
    """Whether the x axis's drawn tick labels inside its limits stand :data:`_TICK_GAP`
    pixels apart."""
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    lo, hi = sorted(ax.get_xlim())
    boxes = sorted((t.get_window_extent(renderer) for t in ax.get_xticklabels(which="both")
                    if t.get_visible() and t.get_text() and lo <= t.get_position()[0] <= hi),
                   key=lambda b: b.x0)
    return all(b.x0 - a.x1 >= _TICK_GAP for a, b in zip(boxes, boxes[1:]))


def _speed_ticks(fig: Any, ax: Any) -> None:
    """Label the logarithmic speed axis with plain numbers, as densely as their labels stand
    apart (:data:`_SPEED_TICKS`): matplotlib's own log labels (``3×10¹4×10¹``) run into each
    other when the axis spans about one decade. Lays the figure out (``tight_layout``)."""
    from matplotlib.ticker import FixedLocator, FuncFormatter, LogLocator, NullFormatter

    lo, hi = sorted(float(v) for v in ax.get_xlim())
    ax.xaxis.set_minor_locator(LogLocator(subs=tuple(float(m) for m in range(2, 10))))
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: speed_text(float(v))))
    decades = range(int(np.floor(np.log10(lo))), int(np.ceil(np.log10(hi))) + 1)
    for mantissas, every in _SPEED_TICKS:
        ticks = [m * 10.0**e for e in decades if e % every == 0 for m in mantissas]
        ax.xaxis.set_major_locator(FixedLocator([t for t in ticks if lo <= t <= hi]))
        fig.tight_layout()
        if _tick_labels_apart(fig, ax):
            return


def accuracy_speed_figure(
    aucs: Mapping[str, float],
    fps: Mapping[str, float],
    *,
    title: str = "Accuracy and speed",
    dpi: int = DPI,
    order: Sequence[str] | None = None,
) -> tuple[Any, Any, list[str], list[Any]]:
    """The accuracy-speed figure (see :func:`plot_accuracy_speed`), not yet saved or closed:
    ``(figure, axes, trackers shown, their labels)``; the caller closes the figure."""
    shown = [t for t in ranked(aucs)
             if t in fps and np.isfinite(float(aucs[t])) and np.isfinite(float(fps[t]))
             and float(fps[t]) > 0]
    if not shown:
        raise ValueError("no tracker has both an AUC and a speed to plot")
    styles = _styles_for(list(aucs), order)
    plt = require_matplotlib()
    fig, ax = plt.subplots(figsize=(6.4, 4.4), dpi=dpi)
    try:
        xs = np.array([float(fps[t]) for t in shown])
        ys = np.array([float(aucs[t]) for t in shown])
        for name, x, y in zip(shown, xs, ys):
            ax.scatter([x], [y], marker=styles[name]["marker"], color=styles[name]["color"],
                       s=30, zorder=3, label=name)
        ax.set_xscale("log")
        lo, hi = float(xs.min()), float(xs.max())
        ax.set_xlim(lo / 2.5, hi * 4.0)  # room for labels on either side of the extreme points
        span = max(float(ys.max() - ys.min()), 0.05)
        ax.set_ylim(max(0.0, float(ys.min()) - 0.35 * span), min(1.0, float(ys.max()) + 0.35 * span))
        ax.set_xlabel("Update frames per second (log scale, same run)")
        ax.set_ylabel("Mean success AUC")
        ax.set_title(title, fontsize=10)
        ax.grid(True, which="both", linewidth=0.4, alpha=0.6)
        _speed_ticks(fig, ax)
        texts = place_labels(ax, list(xs), list(ys), shown, fontsize=8.0)
    except BaseException:
        plt.close(fig)
        raise
    return fig, ax, shown, texts


def plot_accuracy_speed(
    aucs: Mapping[str, float],
    fps: Mapping[str, float],
    path: str | os.PathLike[str],
    *,
    title: str = "Accuracy and speed",
    dpi: int = DPI,
    order: Sequence[str] | None = None,
) -> list[str]:
    """Write the accuracy-speed plot: one labelled point per tracker at (update frames per
    second, mean AUC), the speed axis logarithmic (trackers differ by orders of magnitude).
    Labels never overlap each other or leave the axes (:func:`place_labels`).

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
    order:
        The trackers in the order given, which fixes their colours and markers
        (:func:`tracker_styles`); default: the order of ``aucs``.

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
    plt = require_matplotlib()
    fig, _, shown, _ = accuracy_speed_figure(aucs, fps, title=title, dpi=dpi, order=order)
    try:
        fig.savefig(os.fspath(path), dpi=dpi)
    finally:
        plt.close(fig)
    return shown


def plot_precision_recall(
    curves: Mapping[str, tuple[Sequence[float], Sequence[float]]],
    fscores: Mapping[str, float],
    path: str | os.PathLike[str],
    *,
    title: str = "Tracking precision-recall",
    dpi: int = DPI,
    order: Sequence[str] | None = None,
) -> None:
    """Write the long-term precision-recall plot: each tracker's tracking recall (x) and
    precision (y) over its confidence thresholds, its best F-score marked by a dot, the legend
    ranked by that F-score and ending with the dot's entry.

    Parameters
    ----------
    curves:
        ``{tracker: (precision, recall)}``, one value per threshold
        (:mod:`wmiltrack.eval.longterm`).
    fscores:
        ``{tracker: F-score}``: legend values and order (best first).
    path:
        Output file (``.png``).
    order:
        The trackers in the order given, which fixes their colours (:func:`tracker_styles`);
        default: the order of ``fscores``.
    """
    plt = require_matplotlib()
    from matplotlib.lines import Line2D

    outside = len(fscores) > _LEGEND_INSIDE_MAX
    fig, ax = plt.subplots(figsize=(7.4 if outside else 5.0, 4.2))
    styles = _styles_for(list(fscores), order)
    try:
        handles = []
        for i, name in enumerate(ranked(fscores)):
            pr = np.asarray(curves[name][0], dtype=np.float64)
            re = np.asarray(curves[name][1], dtype=np.float64)
            handles += ax.plot(re, pr, color=styles[name]["color"],
                               linestyle=styles[name]["linestyle"],
                               linewidth=2.0 if i == 0 else 1.5,
                               label=f"{name} [{float(fscores[name]):.3f}]")
            f = np.where(pr + re > 0, 2 * pr * re / np.where(pr + re > 0, pr + re, 1.0), 0.0)
            best = int(np.argmax(f))
            ax.plot([re[best]], [pr[best]], marker="o", color=styles[name]["color"],
                    markersize=5, linestyle="none")
        handles.append(Line2D([], [], marker="o", color="0.35", markersize=5, linestyle="none",
                              label="best F-score"))
        ax.set_xlim(0.0, 1.0)
        ax.set_ylim(0.0, 1.0)
        ax.set_xlabel("Tracking recall")
        ax.set_ylabel("Tracking precision")
        ax.set_title(title, fontsize=10)
        ax.grid(True, linewidth=0.4, alpha=0.6)
        if outside:
            ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.02, 1.0),
                      borderaxespad=0.0, fontsize=8, frameon=False)
        else:
            ax.legend(handles=handles, loc="lower left", fontsize=8, framealpha=0.85)
        fig.tight_layout()
        fig.savefig(os.fspath(path), dpi=dpi)
    finally:
        plt.close(fig)


def plot_fscore_bars(
    fscores: Mapping[str, float],
    ok_fscores: Mapping[str, float],
    path: str | os.PathLike[str],
    *,
    title: str = "Tracking F-score",
    dpi: int = DPI,
    order: Sequence[str] | None = None,
) -> None:
    """Write the F-score bars: per tracker, ranked, in its own colour, its F-score at the best
    confidence threshold (solid) and at its own lost flag (hatched), side by side, each bar
    with its value.

    Parameters
    ----------
    fscores:
        ``{tracker: maximum F-score over thresholds}``.
    ok_fscores:
        ``{tracker: F-score at its lost flag}``.
    path:
        Output file (``.png``).
    order:
        The trackers in the order given, which fixes their colours (:func:`tracker_styles`);
        default: the order of ``fscores``.
    """
    plt = require_matplotlib()
    from matplotlib.patches import Patch

    names = ranked(fscores)
    styles = _styles_for(list(fscores), order)
    colours = [styles[n]["color"] for n in names]
    fig, ax = plt.subplots(figsize=(max(5.0, 1.0 + 0.55 * len(names)), 4.2))
    try:
        x = np.arange(len(names), dtype=np.float64)
        best = [float(fscores[n]) for n in names]
        at_ok = [float(ok_fscores.get(n, float("nan"))) for n in names]
        for offset, values, hatch in ((-0.2, best, ""), (0.2, at_ok, "///")):
            bars = ax.bar(x + offset, np.nan_to_num(values), width=0.38, color=colours,
                          edgecolor="white" if hatch else colours, hatch=hatch,
                          alpha=0.55 if hatch else 1.0)
            ax.bar_label(bars, labels=[f"{v:.2f}" if np.isfinite(v) else "n/a" for v in values],
                         fontsize=7, padding=1)
        ax.set_xticks(x)
        ax.set_xticklabels(names, rotation=30, ha="right", fontsize=8)
        ax.set_ylim(0.0, 1.08)
        ax.set_ylabel("Tracking F-score")
        ax.set_title(title, fontsize=10)
        ax.legend(handles=[Patch(facecolor="0.45", label="best threshold"),
                           Patch(facecolor="0.45", alpha=0.55, edgecolor="white", hatch="///",
                                 label="own lost flag")],
                  loc="upper right", fontsize=8, framealpha=0.85)
        ax.grid(True, axis="y", linewidth=0.4, alpha=0.6)
        fig.tight_layout()
        fig.savefig(os.fspath(path), dpi=dpi)
    finally:
        plt.close(fig)
