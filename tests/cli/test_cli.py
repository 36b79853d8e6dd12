"""The command line: demo and track."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from wmiltrack import cli
from wmiltrack.data import synthetic
from wmiltrack.data.boxes import read_boxes


def run(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "wmiltrack", *args], capture_output=True, text=True,
                          timeout=300, env={"WMILTRACK_NO_PROGRESS": "1", "PATH": ""})


def test_demo_prints_auc_and_fps() -> None:
    out = run("demo", "--frames", "80")
    assert out.returncode == 0, out.stderr
    line = [ln for ln in out.stdout.splitlines() if ln.startswith("rcwmil")][0]
    auc, sr, prec, fps = (float(v) for v in line.split()[1:])
    assert 0.4 < auc <= 1.0 and 0.0 <= sr <= 1.0 and 0.0 <= prec <= 1.0
    assert "fps" in out.stdout.splitlines()[1]  # the speed column is shown (its value is not tested)


@pytest.fixture()
def image_folder(tmp_path: Path) -> tuple[Path, np.ndarray]:
    seq = synthetic.make_preset("easy", seed=2, n_frames=25)
    folder = tmp_path / "frames"
    folder.mkdir()
    for i, f in enumerate(seq.load()):
        cv2.imwrite(str(folder / f"{i + 1:04d}.png"), f)
    assert seq.groundtruth is not None
    return folder, seq.groundtruth


def test_track_image_folder_writes_one_box_per_frame(image_folder, tmp_path: Path) -> None:
    folder, gt = image_folder
    box = ",".join(f"{v:.1f}" for v in gt[0])
    out = tmp_path / "boxes.txt"
    res = run("track", str(folder), "--box", box, "-o", str(out))
    assert res.returncode == 0, res.stderr
    boxes = read_boxes(out)
    assert boxes.shape == (25, 4)
    assert np.abs(boxes[-1, :2] - gt[-1, :2]).max() < 8


def test_track_writes_a_video(image_folder, tmp_path: Path) -> None:
    folder, gt = image_folder
    video = tmp_path / "out.avi"
    assert cli.main(["track", str(folder), "--box", ",".join(map(str, gt[0])), "-o",
                     str(tmp_path / "b.txt"), "--video", str(video)]) == 0
    cap = cv2.VideoCapture(str(video))
    n = 0
    while cap.read()[0]:
        n += 1
    assert n == 25


def test_track_errors_are_messages_not_tracebacks(image_folder, tmp_path: Path) -> None:
    folder, _ = image_folder
    res = run("track", str(folder))  # no box and no ground truth
    assert res.returncode != 0 and "--box" in res.stderr and "Traceback" not in res.stderr
    res = run("track", str(tmp_path / "missing"), "--box", "1,2,3,4")
    assert res.returncode != 0 and "Traceback" not in res.stderr
    res = run("track", str(folder), "--box", "1,2,3")
    assert res.returncode != 0 and "four numbers" in res.stderr
    res = run("track", str(folder), "--box", "5000,5000,30,30")
    assert res.returncode == 2 and "outside" in res.stderr  # a bad --box: bad input, 2
