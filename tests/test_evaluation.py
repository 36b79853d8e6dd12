"""Tests of wmiltrack.eval.runner (running, timing, scoring and tables)."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass

import numpy as np
import pytest

from wmiltrack.engine.result import TrackResult
from wmiltrack.eval.runner import (
    EvalRecord,
    evaluate_sequences,
    format_table,
    fps_ratio,
    run_sequence,
    summarize,
)


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


@dataclass
class FakeSeq:
    name: str
    groundtruth: np.ndarray
    frames: list[np.ndarray]

    def load(self) -> list[np.ndarray]:
        return self.frames


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
    with pytest.warns(RuntimeWarning, match="frame 3"):
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


def test_run_sequence_with_opencv_mil() -> None:
    pytest.importorskip("cv2")
    frames, gt = _moving(6)
    r = run_sequence("opencv:MIL", frames, gt[0], seed=0)
    assert r.tracker == "opencv:MIL" and r.completed
    assert r.boxes.shape == (6, 4)
    assert np.isfinite(r.boxes).all()
    assert r.fps > 0 and np.isnan(r.scores[1:]).all()


def _records(repeats: int = 1) -> list[EvalRecord]:
    f1, g1 = _moving(6, seed=1)
    f2, g2 = _moving(9, seed=2, x0=20)
    g2[4] = np.nan  # one frame without ground truth
    seqs = [FakeSeq("A", g1, f1), FakeSeq("B", g2, f2)]

    class Follow(Oracle):
        """Plays back the ground truth of whichever sequence it was started on."""

        name = "follow"

        def __init__(self) -> None:
            super().__init__(g1)

        def init(self, frame: np.ndarray, box: tuple[float, float, float, float]) -> None:
            super().init(frame, box)
            self.boxes = g1 if box == tuple(g1[0]) else np.nan_to_num(g2, nan=0.0)

    class Lost(Oracle):
        """Always far away from the target."""

        name = "lost"

        def __init__(self) -> None:
            super().__init__(np.tile(np.array([300.0, 300.0, 5.0, 5.0]), (10, 1)))

    return evaluate_sequences([Follow, Lost], seqs, repeats=repeats, progress=False)


def test_evaluate_sequences_scores_and_speed() -> None:
    recs = _records()
    assert [(r.tracker, r.sequence) for r in recs] == [
        ("follow", "A"),
        ("lost", "A"),
        ("follow", "B"),
        ("lost", "B"),
    ]
    follow_a, lost_a, follow_b, _ = recs
    assert follow_a.metrics.auc == pytest.approx(20 / 21)
    # frame 0 holds the initialisation box, scored as in OTB: 1 good frame of 6
    assert lost_a.metrics.auc == pytest.approx(20 / 21 / 6)
    assert lost_a.metrics.success_50 == pytest.approx(1 / 6)
    assert follow_b.metrics.n_missing == 1 and follow_b.metrics.n_scored == 8
    assert follow_b.metrics.success_50 == 1.0
    assert all(r.fps > 0 and len(r.fps_runs) == 1 for r in recs)
    assert all(r.deterministic is None for r in recs)
    json.dumps([r.to_dict() for r in recs], allow_nan=False)


def test_repeats_take_median_fps_and_check_determinism() -> None:
    recs = _records(repeats=3)
    for r in recs:
        assert len(r.fps_runs) == 3
        assert r.fps == pytest.approx(float(np.median(r.fps_runs)))
        assert r.deterministic is True


def test_fps_ratio_and_table() -> None:
    recs = _records()
    ratios = fps_ratio(recs, reference="lost")
    for r in recs:
        ref = next(x for x in recs if x.tracker == "lost" and x.sequence == r.sequence)
        assert ratios[(r.tracker, r.sequence)] == pytest.approx(r.fps / ref.fps)
    assert ratios[("lost", "A")] == pytest.approx(1.0)

    summary = summarize(recs, reference="lost")
    assert summary["follow"]["auc"] == pytest.approx(20 / 21)
    assert summary["lost"]["fps_ratio"] == pytest.approx(1.0)
    pooled = (5 + 8) / (5 / recs[0].fps + 8 / recs[2].fps)
    assert summary["follow"]["fps"] == pytest.approx(pooled)

    md = format_table(recs, reference="lost")
    lines = md.splitlines()
    assert lines[0].startswith("| Sequence | Tracker |")
    mean_rows = [ln for ln in lines if ln.startswith("| **mean (2 seq)**")]
    assert len(mean_rows) == 2
    assert "| follow |" in mean_rows[0] and "0.952" in mean_rows[0]
    assert "8/9" in md  # the frame without ground truth shows in the Frames column
    assert "FPS ratio" in md

    plain = format_table(recs, reference="lost", style="plain")
    assert sum(ln.startswith("mean (2 seq)") for ln in plain.splitlines()) == 2
    # without the reference in the run, the ratio column is empty, not invented
    no_ref = format_table(recs, reference="opencv:MIL")
    assert "nan" not in no_ref.lower()
    with pytest.raises(ValueError):
        format_table(recs, style="html")  # type: ignore[arg-type]


def test_table_flags_errors() -> None:
    frames, gt = _moving(6)

    class Crash(Oracle):
        name = "crash"

        def __init__(self) -> None:
            super().__init__(gt, raise_at=2)

    with pytest.warns(RuntimeWarning):
        recs = evaluate_sequences([Crash], [FakeSeq("S", gt, frames)], progress=False)
    assert recs[0].error == "RuntimeError: boom"
    table = format_table(recs)
    assert "crash (!)" in table
    assert "crash on S, frame 2: RuntimeError: boom" in table


def test_bad_arguments() -> None:
    frames, gt = _moving(4)
    with pytest.raises(ValueError):
        evaluate_sequences([], [FakeSeq("S", gt, frames)], progress=False)
    with pytest.raises(ValueError):
        evaluate_sequences(["opencv:MIL"], [FakeSeq("S", gt, frames)], repeats=0, progress=False)


def _load_compare() -> object:
    import importlib.util
    from pathlib import Path

    path = Path(__file__).resolve().parents[1] / "benchmarks" / "compare.py"
    spec = importlib.util.spec_from_file_location("compare_benchmark", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_compare_script_on_a_tiny_otb_folder(
    tmp_path: object, capsys: pytest.CaptureFixture[str]
) -> None:
    cv2 = pytest.importorskip("cv2")
    from pathlib import Path

    root = Path(str(tmp_path)) / "otb"
    for name, x0 in (("Alpha", 40), ("Beta", 20)):
        frames, gt = _moving(5, seed=x0, x0=x0)
        (root / name / "img").mkdir(parents=True)
        for i, f in enumerate(frames, start=1):
            cv2.imwrite(str(root / name / "img" / f"{i:04d}.png"), f)
        lines = [",".join(str(int(v)) for v in row) for row in gt]
        (root / name / "groundtruth_rect.txt").write_text("\n".join(lines) + "\n")
    out = Path(str(tmp_path)) / "res" / "out.json"
    compare = _load_compare()
    rc = compare.main(  # type: ignore[attr-defined]
        [
            str(root),
            "--trackers",
            "opencv:MIL",
            "--repeats",
            "2",
            "--no-progress",
            "--json",
            str(out),
        ]
    )
    assert rc == 0
    text = capsys.readouterr().out
    assert "| Alpha | opencv:MIL | 5 |" in text and "| Beta | opencv:MIL | 5 |" in text
    assert "| No box |" in text
    assert "**mean (2 seq)**" in text
    data = json.loads(out.read_text())
    assert data["args"]["sequences"] == ["Alpha", "Beta"]
    assert len(data["records"]) == 2 and len(data["records"][0]["fps_runs"]) == 2
    assert data["summary"]["opencv:MIL"]["fps_ratio"] == pytest.approx(1.0)
    # unknown sequence and unknown tracker: clear message, exit status 2
    assert compare.main([str(root), "--trackers", "opencv:MIL", "--sequences", "Nope"]) == 2  # type: ignore[attr-defined]
    assert compare.main([str(root), "--trackers", "opencv:Nope"]) == 2  # type: ignore[attr-defined]
    err = capsys.readouterr().err
    assert "available: Alpha, Beta" in err and "valid names" in err


def test_missing_policy_reaches_the_metrics() -> None:
    frames, gt = _moving(5)
    traj = gt.copy()
    traj[2:] = np.nan  # gives no box from frame 2 on

    class Quits(Oracle):
        name = "quits"

        def __init__(self) -> None:
            super().__init__(traj)

    seq = FakeSeq("S", gt, frames)
    miss = evaluate_sequences([Quits], [seq], progress=False)[0]
    hold = evaluate_sequences([Quits], [seq], progress=False, missing="hold")[0]
    assert miss.metrics.n_no_prediction == hold.metrics.n_no_prediction == 3
    assert miss.metrics.success_50 == pytest.approx(2 / 5)
    assert hold.metrics.success_50 > miss.metrics.success_50
    row = next(ln for ln in format_table([miss]).splitlines() if ln.startswith("| S |"))
    assert row.split("|")[8].strip() == "3"  # the No box column
