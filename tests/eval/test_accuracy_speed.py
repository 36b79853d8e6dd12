"""``eval`` writes an accuracy-speed figure beside the success plot: one point per tracker at
its mean AUC and its FPS, both from the same run, for any trackers."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from conftest import write_generated_otb

from wmiltrack.cli import main
from wmiltrack.eval import plots


@pytest.fixture(scope="module")
def data(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("otb")
    write_generated_otb(root, "SeqA", seed=1, n=12)
    write_generated_otb(root, "SeqB", seed=2, n=12)
    return root


@pytest.mark.parametrize("trackers", ["rcwmil,opencv:MIL", "ct"])
def test_eval_plots_each_tracker_at_its_auc_and_fps(data: Path, tmp_path: Path, trackers: str,
                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    seen: dict[str, Any] = {}
    real = plots.plot_accuracy_speed

    def spy(aucs: dict[str, float], fps: dict[str, float], path: Path, **kw: Any) -> list[str]:
        seen.update(aucs=dict(aucs), fps=dict(fps))
        return real(aucs, fps, path, **kw)

    monkeypatch.setattr(plots, "plot_accuracy_speed", spy)
    out = tmp_path / "out"
    assert main(["eval", str(data), "--trackers", trackers, "--out", str(out), "-q"]) == 0
    figure = out / "accuracy_speed.png"
    assert figure.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert (out / "success_ope.png").parent == figure.parent
    doc = json.loads((out / "eval_ope.json").read_text())
    names = trackers.split(",")
    assert sorted(seen["aucs"]) == sorted(names)
    # the summary keeps the order given, which fixes each tracker's colour in every plot
    assert list(doc["summary"]) == names
    for name in names:  # the figure's point is the run's own summary
        assert seen["aucs"][name] == pytest.approx(doc["summary"][name]["auc"])
        assert seen["fps"][name] == pytest.approx(doc["summary"][name]["fps"])


def test_the_figure_leaves_out_trackers_without_a_speed(tmp_path: Path) -> None:
    shown = plots.plot_accuracy_speed({"a": 0.5, "b": 0.4, "c": float("nan")},
                                      {"a": 100.0, "b": float("nan"), "c": 10.0},
                                      tmp_path / "f.png")
    assert shown == ["a"] and (tmp_path / "f.png").is_file()
    with pytest.raises(ValueError, match="no tracker has both"):
        plots.plot_accuracy_speed({"a": 0.5}, {"a": np.nan}, tmp_path / "g.png")
