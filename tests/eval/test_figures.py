"""Figures people read: the accuracy-speed plot's labels never overlap one another, never cover
a point and never leave the axes, even for 13 trackers whose points collide; every plot is
written at 150 dpi or more."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("matplotlib")

from wmiltrack.eval.plots import (  # noqa: E402
    DPI,
    accuracy_speed_figure,
    place_labels,
    plot_accuracy_speed,
    plot_fscore_bars,
    plot_precision_recall,
)

NAMES = ["rcwmil", "rcwmil-cf", "rcwmil-plus", "rcwmil-nano", "fct", "ct", "mil", "wmil", "osil",
         "opencv:MIL", "opencv:MOSSE", "opencv:CSRT", "opencv:Nano"]


def colliding_points() -> tuple[dict[str, float], dict[str, float]]:
    """13 trackers: five on one point, four more within a hair of each other, the rest near the
    edges (fastest, slowest, best, worst)."""
    aucs, fps = {}, {}
    for i, name in enumerate(NAMES):
        if i < 5:
            aucs[name], fps[name] = 0.55, 700.0
        elif i < 9:
            aucs[name], fps[name] = 0.551 + 0.001 * i, 705.0 + i
        else:
            aucs[name] = [0.30, 0.62, 0.45, 0.60][i - 9]
            fps[name] = [20.0, 9000.0, 60.0, 150.0][i - 9]
    return aucs, fps


def assert_apart_and_inside(fig: object, ax: object, texts: list[object], xs: list[float],
                            ys: list[float]) -> None:
    renderer = fig.canvas.get_renderer()  # type: ignore[attr-defined]
    area = ax.get_window_extent(renderer)  # type: ignore[attr-defined]
    figure_box = fig.bbox  # type: ignore[attr-defined]
    boxes = [t.get_window_extent(renderer) for t in texts]  # type: ignore[attr-defined]
    for i, b in enumerate(boxes):
        assert b.width > 0 and b.height > 0
        assert area.x0 <= b.x0 and b.x1 <= area.x1 and area.y0 <= b.y0 and b.y1 <= area.y1, \
            f"label {texts[i].get_text()!r} leaves the axes"  # type: ignore[attr-defined]
        assert figure_box.x0 <= b.x0 and b.x1 <= figure_box.x1
        for j in range(i):
            assert not b.overlaps(boxes[j]), (texts[i].get_text(), texts[j].get_text())  # type: ignore[attr-defined]
    points = ax.transData.transform(np.column_stack([xs, ys]))  # type: ignore[attr-defined]
    for b, t in zip(boxes, texts):
        for px, py in points:
            assert not (b.x0 < px < b.x1 and b.y0 < py < b.y1), f"{t.get_text()!r} covers a point"  # type: ignore[attr-defined]


def test_thirteen_colliding_trackers_get_labels_that_do_not_overlap() -> None:
    import matplotlib.pyplot as plt

    aucs, fps = colliding_points()
    fig, ax, shown, texts = accuracy_speed_figure(aucs, fps)
    try:
        assert len(shown) == len(texts) == 13
        assert sorted(t.get_text() for t in texts) == sorted(NAMES)
        assert_apart_and_inside(fig, ax, texts, [fps[n] for n in shown], [aucs[n] for n in shown])
    finally:
        plt.close(fig)


def test_place_labels_on_one_point_thirteen_times() -> None:
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 4.4), dpi=DPI)
    try:
        ax.scatter([0.5] * 13, [0.5] * 13)
        ax.set_xlim(0, 1)
        ax.set_ylim(0, 1)
        texts = place_labels(ax, [0.5] * 13, [0.5] * 13, NAMES)
        assert_apart_and_inside(fig, ax, texts, [0.5] * 13, [0.5] * 13)
    finally:
        plt.close(fig)


def test_place_labels_says_when_there_is_no_room() -> None:
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(1.0, 0.8), dpi=60)
    try:
        ax.set_xlim(0, 1)
        ax.set_ylim(0, 1)
        with pytest.raises(RuntimeError, match="no room"):
            place_labels(ax, [0.5] * 40, [0.5] * 40, [f"a long tracker name {i}" for i in range(40)])
    finally:
        plt.close(fig)


def test_plots_are_written_at_150_dpi(tmp_path: Path) -> None:
    import cv2

    aucs, fps = colliding_points()
    plot_accuracy_speed(aucs, fps, tmp_path / "a.png")
    assert cv2.imread(str(tmp_path / "a.png")).shape[:2] == (round(4.4 * DPI), round(6.4 * DPI))
    assert DPI >= 150
    curve = (np.linspace(1, 0.3, 10), np.linspace(0, 0.8, 10))
    plot_precision_recall({n: curve for n in NAMES[:3]}, {n: 0.5 for n in NAMES[:3]},
                          tmp_path / "pr.png")
    plot_fscore_bars({n: 0.5 for n in NAMES}, {n: 0.4 for n in NAMES}, tmp_path / "f.png")
    for name in ("pr.png", "f.png"):
        assert cv2.imread(str(tmp_path / name)).shape[1] >= 5 * 150


def test_home_figures_come_from_one_run_on_every_root(tmp_path: Path) -> None:
    """benchmarks/home_figures.py links the sequences of several roots into one dataset and
    runs eval once: the accuracy-speed, success and precision plots of that one run."""
    import json
    import subprocess
    import sys

    from conftest import REPO_ROOT, write_generated_otb

    write_generated_otb(tmp_path / "shared", "A", seed=1, n=8)
    write_generated_otb(tmp_path / "pool", "B", seed=2, n=8)
    out = tmp_path / "home"
    cmd = [sys.executable, str(REPO_ROOT / "benchmarks" / "home_figures.py"), "--roots",
           f"{tmp_path / 'shared'},{tmp_path / 'pool'}", "--out", str(out), "--trackers",
           "rcwmil,ct", "--repeats", "1", "-j", "1"]
    done = subprocess.run(cmd, capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    doc = json.loads((out / "eval" / "eval_ope.json").read_text())
    assert sorted(doc["sequences"]) == ["A", "B"] and doc["trackers"] == ["rcwmil", "ct"]
    for name in ("accuracy_speed.png", "success_ope.png", "precision_ope.png"):
        assert (out / "eval" / name).is_file()
    assert (out / "dataset" / "A").is_symlink()
    # a second run reuses its own links; an entry of the user's there is never replaced
    (out / "dataset" / "C").mkdir()
    write_generated_otb(tmp_path / "pool", "C", seed=3, n=8)
    again = subprocess.run(cmd, capture_output=True, text=True, check=False)
    assert again.returncode != 0 and "is not a link" in again.stderr
