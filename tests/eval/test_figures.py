"""Figures people read: the accuracy-speed plot's labels never overlap one another, never cover
a point and never leave the axes, even for 13 trackers whose points collide, nor do its speed
axis's numbers; a tracker has one colour in every plot of a run; every mark has a legend entry;
every plot is written at 150 dpi or more; counts agree with their nouns."""

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
    # the plots' colours follow the summary's order: the order given, as in any eval run
    assert list(doc["summary"]) == ["rcwmil", "ct"]
    for name in ("accuracy_speed.png", "success_ope.png", "precision_ope.png"):
        assert (out / "eval" / name).is_file()
    assert (out / "dataset" / "A").is_symlink()
    # a second run reuses its own links; an entry of the user's there is never replaced
    (out / "dataset" / "C").mkdir()
    write_generated_otb(tmp_path / "pool", "C", seed=3, n=8)
    again = subprocess.run(cmd, capture_output=True, text=True, check=False)
    assert again.returncode != 0 and "is not a link" in again.stderr


def speeds(n: int, layout: str) -> dict[str, float]:
    """``n`` speeds: ``close`` within a factor of 3 (the axis spans about a decade, where
    matplotlib labels its minor ticks ``3×10¹``, ``4×10¹``...), ``spread`` over four decades."""
    hi = 3.0 if layout == "close" else 4000.0
    return {f"tracker {i}": 30.0 * hi ** (i / max(n - 1, 1)) for i in range(n)}


@pytest.mark.parametrize("n", [2, 5, 15])
@pytest.mark.parametrize("layout", ["close", "spread"])
def test_speed_axis_labels_never_overlap(n: int, layout: str) -> None:
    import matplotlib.pyplot as plt

    fps = speeds(n, layout)
    aucs = {name: 0.4 + 0.01 * i for i, name in enumerate(fps)}
    fig, ax, shown, texts = accuracy_speed_figure(aucs, fps)
    try:
        assert len(shown) == n
        fig.canvas.draw()
        renderer = fig.canvas.get_renderer()
        lo, hi = ax.get_xlim()
        labels = [t for t in ax.get_xticklabels(which="both")
                  if t.get_visible() and t.get_text() and lo <= t.get_position()[0] <= hi]
        assert len(labels) >= 2, "the speed axis needs at least two numbers to be read"
        boxes = [t.get_window_extent(renderer) for t in labels]
        for i, b in enumerate(boxes):
            for j in range(i):
                assert not b.overlaps(boxes[j]), (labels[i].get_text(), labels[j].get_text())
        assert_apart_and_inside(fig, ax, texts, [fps[s] for s in shown], [aucs[s] for s in shown])
    finally:
        plt.close(fig)


def drawn_colours(fig: object) -> dict[str, str]:
    """``{tracker: colour}`` of a saved figure of ours, read from its artists: the labelled
    curves (``name [score]``), the accuracy-speed points (labelled with the name) or the bars
    (under their tick labels)."""
    from matplotlib.colors import to_hex

    ax = fig.axes[0]  # type: ignore[attr-defined]
    found: dict[str, set[str]] = {}
    for line in ax.get_lines():
        if not line.get_label().startswith("_"):
            found.setdefault(line.get_label().rsplit(" [", 1)[0], set()).add(
                to_hex(line.get_color()))
    for points in ax.collections:
        if not points.get_label().startswith("_"):
            found.setdefault(points.get_label(), set()).add(to_hex(points.get_facecolor()[0]))
    ticks = [t.get_text() for t in ax.get_xticklabels()]
    for container in ax.containers:
        for name, bar in zip(ticks, container.patches):
            found.setdefault(name, set()).add(to_hex(bar.get_facecolor(), keep_alpha=False))
    assert all(len(c) == 1 for c in found.values()), found  # one colour within the figure
    return {name: c.pop() for name, c in found.items()}


def saved_figures(monkeypatch: pytest.MonkeyPatch) -> dict[str, object]:
    """Record every figure saved from now on, by file name."""
    from matplotlib.figure import Figure

    saved: dict[str, object] = {}
    real = Figure.savefig

    def spy(self: Figure, fname: object, *args: object, **kw: object) -> None:
        saved[Path(str(fname)).name] = self
        real(self, fname, *args, **kw)

    monkeypatch.setattr(Figure, "savefig", spy)
    return saved


def test_a_tracker_has_one_colour_in_every_plot_of_a_run(tmp_path: Path,
                                                         monkeypatch: pytest.MonkeyPatch) -> None:
    """Colours follow the order the trackers were given (the summaries' order), not each plot's
    ranking: "slow" is given first, ranks last by AUC and first by precision."""
    from wmiltrack.eval.report import write_longterm_plots, write_plots

    order = ["slow", "best", "mid"]
    auc, p20, fps, fsc = [0.3, 0.7, 0.5], [0.9, 0.6, 0.2], [5.0, 40.0, 300.0], [0.2, 0.4, 0.6]
    ope = {"summary": {t: {"success_curve": np.linspace(1, 0, 21) * auc[i], "auc": auc[i],
                           "precision_curve": np.linspace(0, 1, 51) * p20[i],
                           "precision_20": p20[i], "fps": fps[i]}
                       for i, t in enumerate(order)}}
    lt = {"summary": {t: {"curve": {"precision": [1.0, 0.8 - 0.1 * i, 0.5],
                                    "recall": [0.0, 0.3, 0.6 + 0.1 * i]},
                          "f_score": fsc[i], "ok_f_score": fsc[i] / 2}
                      for i, t in enumerate(order)}}
    saved = saved_figures(monkeypatch)
    write_plots(ope, tmp_path, 1)
    write_longterm_plots(lt, tmp_path, 1)
    assert sorted(saved) == ["accuracy_speed.png", "fscore_longterm.png", "precision_ope.png",
                             "precision_recall_longterm.png", "success_ope.png"]
    drawn = {name: drawn_colours(fig) for name, fig in saved.items()}
    first = drawn["success_ope.png"]
    assert len(set(first.values())) == 3
    for name, colours in drawn.items():
        assert colours == first, name
    from wmiltrack.eval.plots import tracker_styles

    assert first == {t: s["color"] for t, s in tracker_styles(order).items()}
    titles = [f.axes[0].get_title() for f in saved.values()]  # type: ignore[attr-defined]
    assert all("(1 sequence" in t and "sequences" not in t for t in titles), titles


def test_tracker_styles_keep_the_order_given_past_ten_trackers() -> None:
    from wmiltrack.eval.plots import tracker_styles

    names = [f"t{i}" for i in range(15)]
    styles = tracker_styles(names)
    assert list(styles) == names
    looks = {(s["color"], s["linestyle"]) for s in styles.values()}
    assert len(looks) == 15  # colours come round with the next line style
    assert len({(s["color"], s["marker"]) for s in styles.values()}) == 15
    assert tracker_styles(["b", "a", "b"]) == {k: v for k, v in tracker_styles(["b", "a"]).items()}


def test_every_mark_of_the_long_term_plots_is_in_a_legend(tmp_path: Path,
                                                          monkeypatch: pytest.MonkeyPatch) -> None:
    """The precision-recall plot's best-F dots and the F-score plot's hatched bars each have a
    legend entry of their own look."""
    saved = saved_figures(monkeypatch)
    curve = ([1.0, 0.7, 0.4], [0.0, 0.4, 0.7])
    plot_precision_recall({n: curve for n in NAMES[:3]}, {n: 0.5 for n in NAMES[:3]},
                          tmp_path / "pr.png")
    plot_fscore_bars({n: 0.5 for n in NAMES[:3]}, {n: 0.4 for n in NAMES[:3]}, tmp_path / "f.png")
    ax = saved["pr.png"].axes[0]  # type: ignore[attr-defined]
    legend = ax.get_legend()
    marks = {line.get_marker() for line in ax.get_lines() if line.get_marker() not in ("None", "")}
    assert marks == {"o"}  # the dots are there
    explained = {h.get_marker() for h in legend.legend_handles if hasattr(h, "get_marker")}
    assert marks <= explained, f"no legend entry for the marks {marks - explained}"
    assert [t.get_text() for t in legend.get_texts()][-1] == "best F-score"
    ax = saved["f.png"].axes[0]  # type: ignore[attr-defined]
    hatches = {bar.get_hatch() or "" for c in ax.containers for bar in c.patches}
    legend_hatches = {h.get_hatch() or "" for h in ax.get_legend().legend_handles}
    assert hatches == legend_hatches == {"", "///"}


def test_counts_agree_with_their_nouns() -> None:
    from wmiltrack.eval.report import format_vot_table

    table = format_vot_table({"results": {}, "summary": {}}, 1, skip=1, burnin=1)
    assert "re-initialised 1 frame later" in table and "first 1 frame from" in table
    from wmiltrack.eval.report import plural

    assert (plural(1, "sequence"), plural(0, "sequence"), plural(3, "frame")) == \
        ("1 sequence", "0 sequences", "3 frames")
