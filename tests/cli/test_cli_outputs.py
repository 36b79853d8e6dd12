"""Outputs never overwrite inputs: ``-o``, ``--video`` and ``--list``'s box files that are the
input, a file the run reads (a sequence's images or ground truth) or each other are refused with
exit status 2 before anything is written, and a run that cannot start changes no existing file."""

from __future__ import annotations

import os
from pathlib import Path

import cv2
import numpy as np
import pytest
from conftest import write_generated_otb
from test_cli_usage import write_video

from wmiltrack import cli


@pytest.fixture()
def clip(tmp_path: Path) -> tuple[Path, str]:
    path, box = write_video(tmp_path / "clip.mp4")
    return path, ",".join(f"{v:g}" for v in box)


@pytest.fixture()
def otb(tmp_path: Path) -> Path:
    write_generated_otb(tmp_path / "data", "Seq", seed=3, n=10)
    return tmp_path / "data" / "Seq"


def snapshot(folder: Path) -> dict[str, bytes]:
    """Every file below ``folder`` with its bytes."""
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def test_output_that_is_the_ground_truth_is_refused(otb: Path, tmp_path: Path,
                                                    capsys: pytest.CaptureFixture[str]) -> None:
    before = snapshot(tmp_path)
    status = cli.main(["track", str(otb), "-o", str(otb / "groundtruth_rect.txt")])
    err = capsys.readouterr().err
    assert status == 2 and "overwritten" in err
    assert snapshot(tmp_path) == before


def test_output_that_is_one_of_the_frames_is_refused(otb: Path, tmp_path: Path,
                                                     capsys: pytest.CaptureFixture[str]) -> None:
    frame = sorted((otb / "img").iterdir())[3]
    before = snapshot(tmp_path)
    for option in ("-o", "--video"):
        args = ["track", str(otb), option, str(frame)]
        assert cli.main(args) == 2, option
        assert "input folder" in capsys.readouterr().err
    assert snapshot(tmp_path) == before


@pytest.mark.parametrize("option", ["-o", "--video"])
def test_output_that_is_the_input_video_is_refused(clip: tuple[Path, str], option: str,
                                                   capsys: pytest.CaptureFixture[str]) -> None:
    path, box = clip
    before = path.read_bytes()
    assert cli.main(["track", str(path), "--box", box, option, str(path)]) == 2
    assert "is the input" in capsys.readouterr().err
    assert path.read_bytes() == before


def test_the_input_under_another_name_is_refused(clip: tuple[Path, str], tmp_path: Path) -> None:
    """A hard link and a path with ``..`` name the same file: compared as files, not strings."""
    path, box = clip
    link = tmp_path / "sub" / "link.mp4"
    link.parent.mkdir()
    os.link(path, link)
    before = path.read_bytes()
    assert cli.main(["track", str(path), "--box", box, "-o", str(link)]) == 2
    assert cli.main(["track", str(path), "--box", box, "-o", str(tmp_path / "sub" / ".." / "clip.mp4")]) == 2
    assert path.read_bytes() == before


def test_boxes_file_is_an_input_too(clip: tuple[Path, str], tmp_path: Path) -> None:
    path, box = clip
    targets = tmp_path / "targets.txt"
    targets.write_text(box + "\n")
    assert cli.main(["track", str(path), "--boxes", str(targets), "-o", str(targets)]) == 2
    assert targets.read_text() == box + "\n"


def test_two_outputs_that_are_one_file_are_refused(clip: tuple[Path, str], tmp_path: Path,
                                                   capsys: pytest.CaptureFixture[str]) -> None:
    path, box = clip
    out = tmp_path / "x.avi"
    out.write_text("keep\n")
    assert cli.main(["track", str(path), "--box", box, "-o", str(out), "--video", str(out)]) == 2
    assert "same file" in capsys.readouterr().err
    assert out.read_text() == "keep\n"
    fresh = tmp_path / "y.avi"  # not there yet: compared by resolved path
    assert cli.main(["track", str(path), "--box", box, "-o", str(fresh),
                     "--video", str(tmp_path / "." / "y.avi")]) == 2
    assert not fresh.exists()


def test_a_video_that_cannot_be_written_leaves_the_box_file_alone(
        otb: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    keep = tmp_path / "keep.txt"
    keep.write_text("K1\nK2\n")
    status = cli.main(["track", str(otb), "-o", str(keep), "--video", str(tmp_path / "no" / "out.avi")])
    assert status == 1 and "cannot write video" in capsys.readouterr().err
    assert keep.read_text() == "K1\nK2\n"
    new = tmp_path / "new.txt"  # a box file the failed run created is removed again
    assert cli.main(["track", str(otb), "-o", str(new), "--video", str(tmp_path / "no" / "out.avi")]) == 1
    assert not new.exists()


def test_a_good_run_still_replaces_its_own_earlier_output(otb: Path, tmp_path: Path) -> None:
    out = tmp_path / "boxes.txt"
    out.write_text("old line that is longer than any box line, to see it truncated\n" * 50)
    assert cli.main(["track", str(otb), "-o", str(out), "--video", str(tmp_path / "v.avi")]) == 0
    lines = out.read_text().splitlines()
    assert len(lines) == 10 and all(line.count(",") == 3 for line in lines)
    cap = cv2.VideoCapture(str(tmp_path / "v.avi"))
    assert cap.isOpened() and cap.read()[0]
    cap.release()


def test_list_box_files_may_not_overwrite_a_clip(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A list whose box folder is a clip's own folder, where the clip's box file would be its
    ground truth (the clip is named like the ground-truth file)."""
    write_generated_otb(tmp_path, "groundtruth_rect", seed=1, n=6)  # folder name = box file name
    seq = tmp_path / "groundtruth_rect"
    listing = tmp_path / "clips.txt"
    listing.write_text("groundtruth_rect 10,10,20,20\n")
    before = snapshot(tmp_path)
    assert cli.main(["track", "--list", str(listing), "-o", str(seq)]) == 2
    assert "overwritten" in capsys.readouterr().err
    assert snapshot(tmp_path) == before


def test_list_clips_with_one_name_in_two_folders_get_two_box_files(tmp_path: Path) -> None:
    for folder in ("cam1", "cam2"):
        write_generated_otb(tmp_path / folder, "Seq", seed=len(folder), n=6)
    listing = tmp_path / "clips.txt"
    listing.write_text("cam1/Seq 10,10,20,20\ncam2/Seq 12,12,20,20\n")
    out = tmp_path / "boxes"
    assert cli.main(["track", "--list", str(listing), "-o", str(out)]) == 0
    files = sorted(p.name for p in out.iterdir())
    assert len(files) == 2 and all(p.endswith(".txt") for p in files)
    first = [np.loadtxt(out / f, delimiter=",")[0] for f in files]
    assert {tuple(b) for b in first} == {(10, 10, 20, 20), (12, 12, 20, 20)}


def test_frames_behind_a_linked_img_folder_are_inputs_too(tmp_path: Path) -> None:
    """An OTB folder whose ``img/`` is a link to the frames elsewhere: a frame reached through
    the link is still one of the run's inputs."""
    write_generated_otb(tmp_path / "store", "Seq", seed=2, n=6)
    seq = tmp_path / "linked"
    seq.mkdir()
    (seq / "img").symlink_to(tmp_path / "store" / "Seq" / "img", target_is_directory=True)
    (seq / "groundtruth_rect.txt").write_bytes((tmp_path / "store" / "Seq" / "groundtruth_rect.txt").read_bytes())
    frame = tmp_path / "store" / "Seq" / "img" / "0002.jpg"
    before = frame.read_bytes()
    assert cli.main(["track", str(seq), "-o", str(frame)]) == 2
    assert frame.read_bytes() == before
