"""Tests of the evaluation pipeline's stages: wmiltrack.eval.runner (running, timing, tasks,
executors), wmiltrack.eval.scoring (conventions for frames without a box) and
wmiltrack.eval.pipeline (box files written per task, failures reported, interruptions)."""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import pytest

import wmiltrack.eval.runner as runner
import wmiltrack.trackers as peers
from wmiltrack.cli import main
from wmiltrack.data.boxes import read_boxes
from wmiltrack.engine.result import TrackResult
from wmiltrack.eval.metrics import iou
from wmiltrack.eval.pipeline import EvalConfig, make_tasks, run_eval, run_tasks
from wmiltrack.eval.runner import SerialExecutor, run_sequence
from wmiltrack.eval.scoring import scored_boxes


def _moving(n: int = 6, seed: int = 0, x0: int = 40) -> tuple[list[np.ndarray], np.ndarray]:
    rng = np.random.default_rng(seed)
    bg = rng.integers(0, 256, size=(96, 128, 3), dtype=np.uint8)
    patch = rng.integers(0, 256, size=(24, 20, 3), dtype=np.uint8)
    frames, gt = [], []
    for i in range(n):
        f = bg.copy()
        x, y = x0 + 2 * i, 30 + i
        f[y : y + 24, x : x + 20] = patch
        frames.append(f)
        gt.append((x, y, 20, 24))
    return frames, np.asarray(gt, dtype=np.float64)


class Oracle:
    """Follows a given trajectory; can raise on a chosen update."""

    name = "oracle"

    def __init__(self, boxes: np.ndarray, raise_at: int | None = None) -> None:
        self.boxes = boxes
        self.raise_at = raise_at
        self.i = 0

    def init(self, frame: np.ndarray, box: tuple[float, float, float, float]) -> None:
        self.i = 0

    def update(self, frame: np.ndarray) -> TrackResult:
        self.i += 1
        if self.i == self.raise_at:
            raise RuntimeError("boom")
        x, y, w, h = (float(v) for v in self.boxes[self.i])
        return TrackResult((x, y, w, h), 0.75, True)


def test_run_sequence_with_scripted_tracker() -> None:
    frames, gt = _moving(8)
    r = run_sequence(lambda: Oracle(gt), frames, gt[0])
    assert r.tracker == "<lambda>"
    assert r.completed and r.error is None and r.n_updates == 7
    np.testing.assert_array_equal(r.boxes, gt)
    assert math.isnan(r.scores[0]) and np.all(r.scores[1:] == 0.75)
    assert r.oks.all()
    assert math.isnan(r.update_times[0]) and np.all(r.update_times[1:] >= 0)
    assert r.init_time >= 0
    assert r.fps == pytest.approx(7 / np.nansum(r.update_times))
    assert r.median_update_time == pytest.approx(float(np.nanmedian(r.update_times)))
    json.dumps(r.to_dict(per_frame=True), allow_nan=False)


def test_run_sequence_records_errors() -> None:
    frames, gt = _moving(8)
    with pytest.warns(RuntimeWarning, match="frame 4"):  # index 3: frame 4 counted from 1
        r = run_sequence(lambda: Oracle(gt, raise_at=3), frames, gt[0])
    assert not r.completed
    assert r.error == "RuntimeError: boom" and r.error_frame == 3
    assert r.traceback is not None and "boom" in r.traceback
    assert r.n_updates == 2
    assert np.isnan(r.boxes[3:]).all() and not np.isnan(r.boxes[:3]).any()
    with pytest.raises(RuntimeError, match="boom"):
        run_sequence(lambda: Oracle(gt, raise_at=3), frames, gt[0], raise_errors=True)
    with pytest.raises(ValueError):
        run_sequence(lambda: Oracle(gt), [], gt[0])
    with pytest.raises(ValueError):
        run_sequence(lambda: Oracle(gt), frames, (1, 2, 3))


def test_run_sequence_with_opencv_mil_follows_the_target() -> None:
    frames, gt = _moving(6)
    r = run_sequence("opencv:MIL", frames, gt[0], seed=0)
    assert r.tracker == "opencv:MIL" and r.completed and r.n_updates == 5
    # a textured patch on a static background moving 2 px/frame: MIL keeps it
    assert float(iou(r.boxes, gt).min()) > 0.5
    assert np.isnan(r.scores[1:]).all()  # OpenCV gives no confidence


# ----------------------------------------------------------------------------- scoring
def test_scored_boxes_conventions() -> None:
    b = np.array([[1, 1, 5, 5], [2, 2, 5, 5], [np.nan] * 4, [4, 4, 5, 5], [5, 5, 5, 5], [6, 6, 5, 5]])
    ok = np.array([True, True, False, False, True, True])
    hold = scored_boxes(b, ok, missing="hold")
    np.testing.assert_array_equal(hold[2], [2, 2, 5, 5])  # no box -> the last box
    np.testing.assert_array_equal(hold[3], [4, 4, 5, 5])  # a box given with ok False is kept
    miss = scored_boxes(b, ok, missing="miss")
    assert np.isnan(miss[2:4]).all() and np.isfinite(miss[[0, 1, 4, 5]]).all()
    crashed = scored_boxes(b, ok, frames_run=4, missing="hold")  # raised at frame 4
    assert np.isnan(crashed[4:]).all() and np.isfinite(crashed[:4]).all()
    with pytest.raises(ValueError, match="missing"):
        scored_boxes(b, ok, missing="drop")  # type: ignore[arg-type]


# ----------------------------------------------------------------------------- pipeline
H, W = 72, 96


def _write_otb(root: Path, name: str, n: int = 8, x0: int = 30, width: int = W) -> np.ndarray:
    frames, gt = _moving(n, seed=len(name), x0=x0)
    d = root / name / "img"
    d.mkdir(parents=True)
    for i, f in enumerate(frames):
        assert cv2.imwrite(str(d / f"{i + 1:04d}.png"), np.ascontiguousarray(f[:H, :width]))
    (root / name / "groundtruth_rect.txt").write_text(
        "\n".join(",".join(str(float(v)) for v in row) for row in gt) + "\n"
    )
    return gt


class Scripted:
    """Plays back a sequence's ground truth; ``lost`` frames get ``lost_box`` and ok False.

    ``fail_width``: raise RuntimeError on frames of that width; ``interrupt_width``: raise
    KeyboardInterrupt on frames of that width (an interrupted run)."""

    def __init__(self, lost: tuple[int, ...] = (), lost_box: str = "nan", fail_width: int = 0,
                 interrupt_width: int = 0) -> None:
        self.lost, self.lost_box = lost, lost_box
        self.fail_width, self.interrupt_width = fail_width, interrupt_width
        self.i, self.box = 0, (0.0, 0.0, 1.0, 1.0)

    def init(self, frame: np.ndarray, box: tuple[float, float, float, float]) -> None:
        self.i, self.box = 0, box

    def update(self, frame: np.ndarray) -> TrackResult:
        self.i += 1
        if frame.shape[1] == self.fail_width and self.i == 3:
            raise RuntimeError("boom")
        if frame.shape[1] == self.interrupt_width:
            raise KeyboardInterrupt
        x, y, w, h = self.box
        true = (x + 2 * self.i, y + self.i, w, h)  # _moving's motion
        if self.i in self.lost:
            box = (math.nan,) * 4 if self.lost_box == "nan" else (300.0, 300.0, w, h)
            return TrackResult(box, 0.1, False)  # type: ignore[arg-type]
        return TrackResult(true, 0.9, True)


@pytest.fixture
def fakes(monkeypatch: pytest.MonkeyPatch) -> dict[str, Any]:
    """Make ``fake:<name>`` tracker specs available to the pipeline (in this process)."""
    table: dict[str, Any] = {}
    real = peers.make_tracker

    def make(spec: str, seed: int = 0, **params: Any) -> Any:
        return table[spec]() if spec in table else real(spec, seed=seed, **params)

    monkeypatch.setattr(peers, "make_tracker", make)
    monkeypatch.setattr(runner, "make_tracker", make)
    return table


def test_hold_last_box_is_the_default_for_every_tracker(tmp_path: Path, fakes: dict[str, Any]) -> None:
    gt = _write_otb(tmp_path / "data", "A")
    # an OpenCV-like tracker: no box on frames 3-5; a wmiltrack-like one: a wrong box, ok False
    fakes["fake:nobox"] = lambda: Scripted(lost=(3, 4, 5), lost_box="nan")
    fakes["fake:okfalse"] = lambda: Scripted(lost=(3, 4, 5), lost_box="far")
    config = EvalConfig(tmp_path / "data", tmp_path / "hold",
                        trackers=["fake:nobox", "fake:okfalse"], plots=False, show_progress=False)
    doc = run_eval(config)
    held = read_boxes(tmp_path / "hold" / "boxes" / "fake_nobox" / "A.txt")
    np.testing.assert_array_equal(held[3:6], np.tile(gt[2], (3, 1)))  # the last box, held
    nobox = doc["results"]["fake:nobox"]["A"]["runs"][0]
    assert nobox["n_no_prediction"] == 0 and nobox["n_lost"] == 3
    assert nobox["mean_center_error"] == pytest.approx(float(np.mean(
        np.hypot(*(((gt[2, :2] - gt[3:6, :2])).T)))) * 3 / 8)
    assert doc["settings"]["missing"] == "hold" and doc["settings"]["cv_threads"] == 1
    assert "hold the last box" in doc["caption"] and "OpenCV threads: 1" in doc["caption"]

    # the other convention: every frame a tracker reports lost is a miss, for both trackers
    doc = run_eval(dataclasses.replace(config, out=tmp_path / "miss", missing="miss"))
    for name, folder in (("fake:nobox", "fake_nobox"), ("fake:okfalse", "fake_okfalse")):
        run = doc["results"][name]["A"]["runs"][0]
        assert run["n_no_prediction"] == 3 and run["precision_20"] == pytest.approx(5 / 8)
        assert run["mean_center_error"] == "inf"  # the misses count in the centre error
        assert np.isnan(read_boxes(tmp_path / "miss" / "boxes" / folder / "A.txt")[3:6]).all()
    table = (tmp_path / "miss" / "eval_ope.md").read_text()
    assert "a frame a tracker reports lost is a miss" in table.splitlines()[0]


def test_a_failing_sequence_is_reported_and_the_rest_goes_on(
    tmp_path: Path, fakes: dict[str, Any], capsys: pytest.CaptureFixture[str]
) -> None:
    data = tmp_path / "data"
    _write_otb(data, "A")
    _write_otb(data, "B", width=W - 8)  # the tracker fails on this one
    _write_otb(data, "C")
    fakes["fake:flaky"] = lambda: Scripted(fail_width=W - 8)
    fakes["fake:ok"] = lambda: Scripted()
    out = tmp_path / "out"
    rc = main(["eval", str(data), "--trackers", "fake:flaky,fake:ok", "--out", str(out),
               "--no-plots", "--no-progress", "--repeats", "2"])
    assert rc == 1  # an error is an exit status, not silence
    text = capsys.readouterr()
    # the 3rd update raises: frame 4 counted from 1, as every message counts frames
    assert "fake:flaky on B (seed 0) failed: RuntimeError: boom (frame 4)" in text.err
    doc = json.loads((out / "eval_ope.json").read_text())
    assert doc["summary"]["fake:flaky"]["errors"] == 2  # both repeats on B
    assert doc["results"]["fake:flaky"]["B"]["runs"][1]["error"] == "RuntimeError: boom (frame 4)"
    assert doc["results"]["fake:flaky"]["A"]["runs"][0]["error"] is None
    for seq in "ABC":
        for suffix in ("", ".r1"):
            assert (out / "boxes" / "fake_flaky" / f"{seq}{suffix}.txt").is_file()
    b = read_boxes(out / "boxes" / "fake_flaky" / "B.txt")
    assert np.isfinite(b[:3]).all() and np.isnan(b[3:]).all()  # not held after the crash
    table = (out / "eval_ope.md").read_text()
    assert "| B | fake:flaky (!) |" in table and "fake:flaky on B: RuntimeError: boom" in table


def test_an_interrupted_run_keeps_the_finished_box_files(tmp_path: Path, fakes: dict[str, Any]) -> None:
    data = tmp_path / "data"
    _write_otb(data, "A")
    _write_otb(data, "B")
    _write_otb(data, "C", width=W - 8)
    fakes["fake:stop"] = lambda: Scripted(interrupt_width=W - 8)
    with pytest.raises(KeyboardInterrupt):  # (the keyword call: run_eval(dataset, out, ...))
        run_eval(data, tmp_path / "out", trackers=["fake:stop"], plots=False,
                 show_progress=False, repeats=2)
    written = sorted(p.name for p in (tmp_path / "out" / "boxes" / "fake_stop").iterdir())
    assert written == ["A.r1.run.json", "A.r1.txt", "A.run.json", "A.txt",
                       "B.r1.run.json", "B.r1.txt", "B.run.json", "B.txt"]
    assert not (tmp_path / "out" / "eval_ope.json").exists()


def test_tasks_are_tracker_sequence_seed_and_repeats_use_their_own_seed(
    tmp_path: Path, fakes: dict[str, Any]
) -> None:
    data = tmp_path / "data"
    _write_otb(data, "A")
    _write_otb(data, "B")
    tasks = make_tasks([data / "A", data / "B"], ["rcwmil", "fake:x"], [5, 6])
    assert [(t.tracker, Path(t.sequence).name, t.seed, t.repeat) for t in tasks[:4]] == [
        ("rcwmil", "A", 5, 0), ("fake:x", "A", 5, 0), ("rcwmil", "A", 6, 1), ("fake:x", "A", 6, 1)
    ]
    seen: list[tuple[str, str, int]] = []
    fakes["fake:x"] = lambda: Scripted()
    runs = run_tasks(tasks, SerialExecutor(), lambda r: seen.append((r.tracker, r.sequence, r.seed)))
    assert len(seen) == 8 and [(r.tracker, r.sequence, r.seed) for r in runs] == seen
    a0, a1 = (r for r in runs if r.tracker == "rcwmil" and r.sequence == "A")
    assert (a0.seed, a1.seed) == (5, 6)
    assert not np.array_equal(a0.boxes, a1.boxes)  # another seed draws another feature bank


def test_serial_executor_sets_and_restores_opencv_threads(tmp_path: Path, fakes: dict[str, Any]) -> None:
    _write_otb(tmp_path, "A", n=3)
    seen: list[int] = []

    class Probe(Scripted):
        def update(self, frame: np.ndarray) -> TrackResult:
            seen.append(cv2.getNumThreads())
            return super().update(frame)

    fakes["fake:probe"] = Probe
    before = cv2.getNumThreads()
    cv2.setNumThreads(2)
    try:
        run_tasks(make_tasks([tmp_path / "A"], ["fake:probe"], [0]), SerialExecutor(1))
        assert seen == [1, 1] and cv2.getNumThreads() == 2
    finally:
        cv2.setNumThreads(before)


def test_run_eval_takes_one_config_or_the_keywords(tmp_path: Path) -> None:
    config = EvalConfig(tmp_path / "data", tmp_path / "out")
    assert config.trackers == ("rcwmil",) and config.seeds == (0,)
    assert dataclasses.replace(config, seed=3, repeats=2).seeds == (3, 4)
    with pytest.raises(TypeError, match="takes no other argument"):
        run_eval(config, tmp_path / "elsewhere")
    with pytest.raises(TypeError, match="needs out"):
        run_eval(tmp_path / "data")
    with pytest.raises(TypeError):
        run_eval(tmp_path / "data", tmp_path / "out", no_such_option=1)
