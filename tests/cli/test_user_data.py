"""The user's data is kept: ``eval --out`` may not be a file or lie inside the dataset, ``track
-o`` may not write into the sequence an image folder belongs to or among the frames, and one
frame that cannot be decoded costs ``eval`` that frame, not the sequence."""

from __future__ import annotations

from pathlib import Path

import pytest
from conftest import write_generated_otb

from wmiltrack import cli


@pytest.fixture()
def data(tmp_path: Path) -> Path:
    write_generated_otb(tmp_path / "data", "Seq", seed=3, n=12)
    return tmp_path / "data"


def snapshot(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


@pytest.mark.parametrize("inside", ["Seq/img", "Seq", "Seq/img/plots", "Seq/results"])
def test_eval_out_inside_the_dataset_is_refused(data: Path, inside: str,
                                                capsys: pytest.CaptureFixture[str]) -> None:
    before = snapshot(data)
    status = cli.main(["eval", str(data), "--trackers", "rcwmil", "--out", str(data / inside),
                       "--no-progress"])
    err = capsys.readouterr().err
    assert status == 2, err
    assert "inside the input folder" in err and "Traceback" not in err
    assert snapshot(data) == before
    assert not (data / "Seq" / "results").exists() and not (data / "Seq" / "img" / "plots").exists()


def test_eval_out_beside_the_sequences_is_allowed(data: Path) -> None:
    """A new folder next to the sequences is no sequence: no reader takes it."""
    assert cli.main(["eval", str(data), "--trackers", "rcwmil", "--out", str(data / "results"),
                     "--no-progress", "--no-plots"]) == 0
    assert cli.main(["eval", str(data), "--trackers", "rcwmil", "--out", str(data / "results"),
                     "--no-progress", "--no-plots"]) == 0  # the next run reads the same dataset


def test_eval_out_that_is_a_file_is_a_usage_error(data: Path, tmp_path: Path,
                                                  capsys: pytest.CaptureFixture[str]) -> None:
    target = tmp_path / "notes.txt"
    target.write_text("mine\n")
    status = cli.main(["eval", str(data), "--trackers", "rcwmil", "--out", str(target)])
    err = capsys.readouterr().err
    assert status == 2 and "is an existing file" in err and "Traceback" not in err
    assert target.read_text() == "mine\n"


def test_track_of_an_img_folder_may_not_replace_its_sequence_ground_truth(
        data: Path, capsys: pytest.CaptureFixture[str]) -> None:
    seq = data / "Seq"
    before = snapshot(data)
    status = cli.main(["track", str(seq / "img"), "--box", "40,30,24,20",
                       "-o", str(seq / "groundtruth_rect.txt")])
    err = capsys.readouterr().err
    assert status == 2 and "inside the input folder" in err
    assert snapshot(data) == before


@pytest.mark.parametrize("name", ["img/0001.png", "img/new.jpg", "groundtruth_rect.2.txt"])
@pytest.mark.parametrize("given", ["Seq", "Seq/img"])
def test_track_may_not_add_files_to_the_input_sequence(data: Path, name: str, given: str,
                                                       capsys: pytest.CaptureFixture[str]) -> None:
    seq = data / "Seq"
    before = snapshot(data)
    status = cli.main(["track", str(data / given), "--box", "40,30,24,20", "-o", str(seq / name)])
    assert status == 2, capsys.readouterr().err
    assert snapshot(data) == before


def test_track_output_beside_the_dataset_is_fine(data: Path, tmp_path: Path) -> None:
    out = tmp_path / "boxes.txt"
    assert cli.main(["track", str(data / "Seq" / "img"), "--box", "40,30,24,20", "-o", str(out),
                     "--quiet"]) == 0
    assert len(out.read_text().splitlines()) == 12


def truncate(path: Path) -> None:
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])


def test_eval_skips_one_corrupt_frame_and_scores_the_rest(data: Path, tmp_path: Path,
                                                          capfd: pytest.CaptureFixture[str]) -> None:
    import json

    import numpy as np

    good = tmp_path / "good"
    assert cli.main(["eval", str(data), "--trackers", "rcwmil", "--out", str(good), "--no-progress",
                     "--no-plots"]) == 0
    truncate(data / "Seq" / "img" / "0007.jpg")
    capfd.readouterr()
    bad = tmp_path / "bad"
    status = cli.main(["eval", str(data), "--trackers", "rcwmil", "--out", str(bad), "--no-progress",
                       "--no-plots"])
    out, err = capfd.readouterr()
    assert status == 0, err
    # said once, in wmiltrack's words; no raw decoder line (libjpeg's "Premature end ...")
    assert "frame 7: 0007.jpg" in err and "Premature" not in err and "Corrupt JPEG" not in err
    assert "could not be decoded" in out  # the table's notes
    doc = json.loads((bad / "eval_ope.json").read_text())
    assert doc["summary"]["rcwmil"]["errors"] == 0
    boxes_good = np.loadtxt(good / "boxes" / "rcwmil" / "Seq.txt", delimiter=",")
    boxes_bad = np.loadtxt(bad / "boxes" / "rcwmil" / "Seq.txt", delimiter=",")
    # the frames before the damaged one are tracked as before, it holds the last box, and
    # the tracker goes on after it
    assert np.array_equal(boxes_bad[:6], boxes_good[:6])
    assert np.array_equal(boxes_bad[6], boxes_bad[5])
    assert np.all(np.isfinite(boxes_bad))
    assert doc["summary"]["rcwmil"]["auc"] > 0
