"""The GOT-10k toolkit's ExperimentOTB runs wmiltrack offline on two shared OTB sequences."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import import_extra

pytestmark = pytest.mark.extras("got10k", "six")
import_extra("got10k")
import_extra("six")     # got10k imports it without declaring it

import matplotlib  # noqa: E402

matplotlib.use("Agg")

from wmiltrack.data.sequences import load_otb_sequence  # noqa: E402
from wmiltrack.eval.metrics import ope_metrics  # noqa: E402
from wmiltrack.integrations.got10k import GOT10kTracker, local_otb_experiment  # noqa: E402

SEQUENCES = ("Crossing", "Couple")


@pytest.mark.parametrize("variant", ["rcwmil", "rcwmil-plus"])
def test_experiment_otb_matches_wmiltrack_metrics(otb_root: Path, tmp_path: Path, variant: str) -> None:
    e = local_otb_experiment(otb_root, SEQUENCES, result_dir=tmp_path / "results",
                             report_dir=tmp_path / "reports")
    assert sorted(e.dataset.seq_names) == sorted(SEQUENCES)
    tracker = GOT10kTracker(variant, seed=0)
    e.run(tracker)
    perf = e.report([tracker.name])[tracker.name]
    assert (Path(e.report_dir) / tracker.name / "success_plots.png").is_file()

    aucs = []
    for name in SEQUENCES:
        boxes = np.loadtxt(Path(e.result_dir) / tracker.name / f"{name}.txt", delimiter=",")
        seq = load_otb_sequence(otb_root / name)
        gt = np.asarray(seq.groundtruth)
        boxes[0] = gt[0]                               # the toolkit scores frame 1 as the GT box
        m = ope_metrics(boxes, gt)
        got = perf["seq_wise"][name]
        assert got["success_score"] == pytest.approx(m.auc, abs=1e-9)
        assert got["success_rate"] == pytest.approx(m.success_50, abs=1e-9)
        aucs.append(m.auc)
        # same boxes as wmiltrack run directly on OpenCV-decoded frames (RGB PIL -> BGR)
        import wmiltrack

        direct = wmiltrack.Tracker(variant, seed=0).track(seq, gt[0])
        np.testing.assert_array_equal(direct[1:], boxes[1:])
    assert perf["overall"]["success_score"] == pytest.approx(float(np.mean(aucs)), abs=1e-9)
    assert perf["overall"]["success_score"] > 0.3


def test_unknown_sequence_is_refused(otb_root: Path, tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="NoSuchSeq"):
        local_otb_experiment(otb_root, ["Crossing", "NoSuchSeq"], result_dir=tmp_path)
