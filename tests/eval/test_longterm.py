"""The long-term protocol (VOT-LT tracking precision, recall and F-score): a case worked out by
hand, the published formulas recomputed independently on random data, and ``wmiltrack eval
--protocol longterm`` end to end (table, both plots, figures that agree with a recomputation
from the files it wrote)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from conftest import write_generated_otb

from wmiltrack import cli
from wmiltrack.eval.longterm import confidences, longterm_scores, sequence_curve, thresholds_from
from wmiltrack.eval.runner import RunOutcome

NAN = math.nan
GT = np.array([[0, 0, 10, 10], [0, 0, 10, 10], [0, 0, 10, 10], [NAN] * 4, [0, 0, 10, 10]], float)
# frame 0 is the start; frames 1..4: IoU 1.0, IoU 0.6, target absent (a box given), IoU 0
BOXES = np.array([[0, 0, 10, 10], [0, 0, 10, 10], [0, 0, 10, 6], [0, 0, 10, 10], [50, 50, 10, 10]],
                 float)
SCORES = np.array([NAN, 0.9, 0.6, 0.3, 0.8])
OKS = np.array([True, True, True, False, False])


def run(tracker: str, seq: str, boxes: np.ndarray, scores: np.ndarray, oks: np.ndarray,
        repeat: int = 0) -> RunOutcome:
    return RunOutcome(tracker, seq, repeat, repeat, boxes, oks, scores=scores)


def test_hand_computed_case() -> None:
    """Three frames with the target present (frames 1, 2, 4), one absent (3).

    tau = 0.9: frame 1 reported, Pr 1, Re 1/3, F 0.5; tau = 0.8: frames 1, 4, Pr 0.5, Re 1/3,
    F 0.4; tau = 0.6: frames 1, 4, 2, IoU sum 1.6, Pr = Re = 1.6/3, F = 0.5333; tau = 0.3 and
    -inf: all four, Pr 0.4, Re 0.5333, F 0.4571. Best: tau = 0.6. At the lost flag (frames 1
    and 2 reported): Pr 0.8, Re 0.5333, F 0.64."""
    conf = confidences(SCORES, OKS, BOXES)
    thr = thresholds_from(conf[1:])
    assert list(thr) == [np.inf, 0.9, 0.8, 0.6, 0.3, -np.inf]
    pr, re = sequence_curve(BOXES, conf, GT, thr)
    assert pr == pytest.approx([1.0, 1.0, 0.5, 1.6 / 3, 0.4, 0.4])
    assert re == pytest.approx([0.0, 1 / 3, 1 / 3, 1.6 / 3, 1.6 / 3, 1.6 / 3])
    s = longterm_scores([run("t", "A", BOXES, SCORES, OKS)], {"A": GT})
    t = s["summary"]["t"]
    assert t["f_score"] == pytest.approx(1.6 / 3)
    assert t["precision"] == pytest.approx(1.6 / 3) and t["recall"] == pytest.approx(1.6 / 3)
    assert t["threshold"] == pytest.approx(0.6)
    assert t["ok_precision"] == pytest.approx(0.8) and t["ok_recall"] == pytest.approx(1.6 / 3)
    assert t["ok_f_score"] == pytest.approx(0.64)
    assert t["confidence"] == "score"
    assert s["results"]["t"]["A"]["absent_frames"] == 1


def test_a_tracker_without_scores_is_scored_at_its_lost_flag() -> None:
    """OpenCV's trackers give no score: their confidence is ok (1) or not (0), so the best
    threshold reports the frames it says it has, as its lost flag does."""
    nan_scores = np.full(5, NAN)
    s = longterm_scores([run("cv", "A", BOXES, nan_scores, OKS)], {"A": GT})["summary"]["cv"]
    assert s["confidence"] == "ok"
    assert s["f_score"] == pytest.approx(s["ok_f_score"]) == pytest.approx(0.64)


def test_never_saying_lost_is_not_free_when_the_target_is_absent() -> None:
    """Two trackers with the same boxes on present frames: the one that reports the absent frames
    (and the missed one) as lost has the higher F at its lost flag."""
    always = np.ones(5, dtype=bool)
    s = longterm_scores([run("honest", "A", BOXES, np.full(5, NAN), OKS),
                         run("never-lost", "A", BOXES, np.full(5, NAN), always)], {"A": GT})
    assert s["summary"]["honest"]["ok_f_score"] > s["summary"]["never-lost"]["ok_f_score"]


def reference(runs: list[tuple[str, np.ndarray, np.ndarray]], gts: dict[str, np.ndarray]
              ) -> tuple[float, float, float]:
    """The published definitions, frame by frame with plain loops: thresholds = every score
    (few enough here) plus +-inf; per sequence Pr = mean IoU over frames with score >= tau (1 if
    none), Re = IoU summed over them / frames with the target present; averaged over
    sequences per tau; F = 2PrRe/(Pr+Re) on the average; the maximum and its Pr, Re."""
    def overlap(a: np.ndarray, b: np.ndarray) -> float:
        if not (np.all(np.isfinite(a)) and np.all(np.isfinite(b)) and b[2] > 0 and b[3] > 0):
            return 0.0
        iw = max(0.0, min(a[0] + a[2], b[0] + b[2]) - max(a[0], b[0]))
        ih = max(0.0, min(a[1] + a[3], b[1] + b[3]) - max(a[1], b[1]))
        inter = iw * ih
        return inter / (a[2] * a[3] + b[2] * b[3] - inter)

    taus = sorted({float(v) for _, _, sc in runs for v in sc[1:] if np.isfinite(v)}, reverse=True)
    taus = [math.inf, *taus, -math.inf]
    best = (-1.0, 0.0, 0.0)
    for tau in taus:
        prs, res = [], []
        for seq, boxes, sc in runs:
            gt = gts[seq]
            ious = [overlap(boxes[i], gt[i]) for i in range(1, len(gt))]
            present = [bool(np.all(np.isfinite(gt[i])) and gt[i][2] > 0) for i in range(1, len(gt))]
            rep = [np.isfinite(sc[i]) and sc[i] >= tau for i in range(1, len(gt))]
            n_rep = sum(rep)
            total = sum(v for v, r in zip(ious, rep) if r)
            prs.append(total / n_rep if n_rep else 1.0)
            res.append(total / sum(present))
        pr, re = sum(prs) / len(prs), sum(res) / len(res)
        f = 2 * pr * re / (pr + re) if pr + re > 0 else 0.0
        if f > best[0]:
            best = (f, pr, re)
    return best


def test_figures_agree_with_the_published_formulas_on_random_runs() -> None:
    rng = np.random.default_rng(7)
    gts: dict[str, np.ndarray] = {}
    runs = []
    for k in range(4):
        n = 30 + 7 * k
        gt = np.column_stack([rng.uniform(0, 50, (n, 2)), rng.uniform(5, 20, (n, 2))])
        gt[rng.random(n) < 0.2] = NAN  # absent frames
        gt[0] = [10, 10, 10, 10]
        boxes = gt + rng.normal(0, 4, gt.shape)
        boxes[~np.isfinite(boxes)] = 20.0  # a box where the target is absent
        boxes[rng.random(n) < 0.1] = NAN  # frames without a box
        boxes[:, 2:] = np.abs(boxes[:, 2:]) + 1
        scores = rng.random(n)
        scores[0] = NAN
        gts[f"s{k}"] = gt
        runs.append((f"s{k}", boxes, scores))
    got = longterm_scores([run("t", s, b, sc, np.ones(len(b), dtype=bool)) for s, b, sc in runs],
                          gts)["summary"]["t"]
    # a frame without a box is never reported, whatever its score
    want = reference([(s, b, np.where(np.all(np.isfinite(b), axis=1), sc, NAN)) for s, b, sc in runs],
                     gts)
    assert (got["f_score"], got["precision"], got["recall"]) == pytest.approx(want)


def test_thresholds_are_thinned_to_the_resolution() -> None:
    thr = thresholds_from(np.linspace(0, 1, 1000), resolution=10)
    assert thr.size == 10 and thr[0] == np.inf and thr[-1] == -np.inf
    assert np.all(np.diff(thr[1:-1]) < 0)


@pytest.fixture()
def absent_dataset(tmp_path: Path) -> Path:
    """Two generated sequences, the second with the target marked absent on frames 20-29."""
    root = tmp_path / "data"
    write_generated_otb(root, "A", seed=1, n=40)
    write_generated_otb(root, "B", seed=2, n=40)
    gt_file = root / "B" / "groundtruth_rect.txt"
    lines = gt_file.read_text().splitlines()
    lines[20:30] = ["NaN,NaN,NaN,NaN"] * 10
    gt_file.write_text("\n".join(lines) + "\n")
    return root


def test_eval_longterm_writes_the_table_and_both_plots_and_agrees_with_its_files(
        absent_dataset: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    pytest.importorskip("matplotlib")
    import cv2

    from wmiltrack.data.boxes import read_boxes

    out = tmp_path / "out"
    status = cli.main(["eval", str(absent_dataset), "--protocol", "longterm", "--trackers",
                       "rcwmil,opencv:MIL", "--out", str(out), "--no-progress"])
    printed = capsys.readouterr().out
    assert status == 0
    assert "| Tracker | F | Pr | Re |" in printed and "B (10)" in printed  # 10 absent frames
    for name in ("precision_recall_longterm.png", "fscore_longterm.png"):
        img = cv2.imread(str(out / name))
        assert img is not None and img.shape[1] >= 700  # 150 dpi
    doc = json.loads((out / "eval_longterm.json").read_text())
    gts = {s: read_boxes(absent_dataset / s / "groundtruth_rect.txt") for s in ("A", "B")}
    for tracker, folder in (("rcwmil", "rcwmil"), ("opencv:MIL", "opencv_MIL")):
        runs = []
        for s in ("A", "B"):
            boxes = read_boxes(out / "boxes_longterm" / folder / f"{s}.txt")
            record = json.loads((out / "boxes_longterm" / folder / f"{s}.run.json").read_text())
            sc = np.array([NAN if v is None else v for v in record["scores"]])
            ok = np.array(record["oks"])
            if not np.any(np.isfinite(sc[1:])):  # no score: the lost flag is the confidence
                sc = np.where(ok, 1.0, NAN)
            sc[~np.all(np.isfinite(boxes), axis=1)] = NAN
            runs.append((s, boxes, sc))
        # 78 frames: fewer scores than the 98 thresholds, so every score is a threshold
        assert len({v for _, _, sc in runs for v in sc[1:] if np.isfinite(v)}) <= 98
        got = doc["summary"][tracker]
        assert (got["f_score"], got["precision"], got["recall"]) == pytest.approx(reference(runs, gts))
        assert 0.0 <= got["ok_f_score"] <= 1.0
    assert doc["summary"]["opencv:MIL"]["confidence"] == "ok"
    assert doc["summary"]["rcwmil"]["confidence"] == "score"


@pytest.mark.parametrize("extra", [["--resume"], ["--results", "RESULTS"]])
def test_longterm_refuses_what_has_no_scores(absent_dataset: Path, tmp_path: Path, extra: list[str],
                                             capsys: pytest.CaptureFixture[str]) -> None:
    extra = [str(tmp_path) if e == "RESULTS" else e for e in extra]
    status = cli.main(["eval", str(absent_dataset), "--protocol", "longterm", "--out",
                       str(tmp_path / "o"), *extra])
    assert status == 2 and "long-term" in capsys.readouterr().err


def test_a_sequence_without_the_target_after_the_first_frame_is_left_out_and_said() -> None:
    gone = GT.copy()
    gone[1:] = NAN
    s = longterm_scores([run("t", "A", BOXES, SCORES, OKS), run("t", "Gone", BOXES, SCORES, OKS)],
                        {"A": GT, "Gone": gone})
    assert s["left_out"] == ["Gone"] and list(s["results"]["t"]) == ["A"]
    assert s["summary"]["t"]["f_score"] == pytest.approx(1.6 / 3)


def test_the_table_prints_a_threshold_a_reader_understands() -> None:
    """With more confidences than thresholds the lowest kept threshold is above the lowest
    confidence, so reporting every frame with a box (threshold -inf) can give the best F; the
    table says "any" there, never "-inf"."""
    from wmiltrack.eval.report import format_longterm_table

    n = 200
    gt = np.tile([0.0, 0.0, 10.0, 10.0], (n, 1))
    scores = np.linspace(1.0, 0.01, n)  # perfect boxes: the more frames reported, the better
    scored = longterm_scores([run("t", "S", gt.copy(), scores, np.ones(n, bool))], {"S": gt})
    assert scored["summary"]["t"]["threshold"] == -math.inf  # the case the table must word
    table = format_longterm_table(scored, title="caption")
    row = next(line for line in table.splitlines() if line.startswith("| t |"))
    assert row.split(" | ")[4] == "any" and "inf" not in table
    from wmiltrack.eval.report import threshold_text

    assert (threshold_text(math.inf), threshold_text(0.53251), threshold_text(None)) == \
        ("none", "0.533", "-")
