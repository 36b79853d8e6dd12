"""Long runs lose nothing (issue 14): ``wmiltrack track`` writes each box as it is computed, skips
frames it cannot decode with the last box held (``--strict`` stops instead), and SIGINT/SIGTERM
end the run with every box computed written and the ``--video`` file playable.

The boxes expected in the output are computed here with the Python API on the same decoded
frames (the tracker is deterministic for a seed), so a wrong order, a missing or an extra line,
or a held box on the wrong frame shows up as a mismatch, not just as a wrong line count.
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import cv2
import numpy as np
import pytest

from wmiltrack import cli
from wmiltrack.data import sequences, synthetic
from wmiltrack.data.boxes import read_boxes
from wmiltrack.trackers import make_tracker

SIZE = (120, 160)        # frame height, width: small frames keep the runs short
TARGET = (24, 20)        # target width, height
ENV = {**os.environ, "WMILTRACK_NO_PROGRESS": "1"}
SUMMARY = re.compile(r"wmiltrack: (\d+) frames?\b")


def make_frames(n: int, seed: int = 3) -> tuple[list[np.ndarray], tuple[float, ...]]:
    seq = synthetic.make_preset("easy", seed=seed, n_frames=n, size=SIZE, target_size=TARGET)
    assert seq.groundtruth is not None
    return seq.load(), tuple(float(v) for v in seq.groundtruth[0])


def frame_folder(tmp_path: Path, frames: list[np.ndarray]) -> Path:
    """``tmp_path/frames`` holding ``frames`` as 0001.png, 0002.png, ..."""
    folder = tmp_path / "frames"
    folder.mkdir()
    for i, f in enumerate(frames):
        cv2.imwrite(str(folder / f"{i + 1:04d}.png"), f)
    return folder


def box_arg(box: tuple[float, ...]) -> str:
    return ",".join(repr(v) for v in box)


def expected_boxes(frames: list[np.ndarray | None], box: tuple[float, ...]) -> np.ndarray:
    """What ``wmiltrack track`` must write: frame 0 gets ``box`` as the tracker starts from it
    (rounded to whole pixels, clipped to the frame); a ``None`` frame (skipped)
    repeats the previous box; the others get the tracker's box."""
    tracker = make_tracker("rcwmil", seed=0)
    out: list[tuple[float, ...]] = []
    for i, f in enumerate(frames):
        if i == 0:
            assert f is not None
            tracker.init(f, box)
            out.append(tracker.box)
        elif f is None:
            out.append(out[-1])
        else:
            out.append(tuple(tracker.update(f).box))
    return np.asarray(out, dtype=np.float64)


def truncated_jpeg(frame: np.ndarray, keep: float = 0.5) -> bytes:
    data = cv2.imencode(".jpg", frame)[1].tobytes()
    return data[: int(len(data) * keep)]


def summary_count(stderr: str) -> int:
    found = SUMMARY.findall(stderr)
    assert found, f"no summary line in stderr:\n{stderr}"
    return int(found[-1])


def track(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str]:
    status = cli.main(["track", *args])
    return status, capsys.readouterr().err


# ------------------------------------------------------------------------- bad image files
def test_truncated_image_in_the_middle_is_skipped_and_the_box_held(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("WMILTRACK_NO_PROGRESS", "1")
    frames, box = make_frames(8)
    folder = frame_folder(tmp_path, frames)
    (folder / "0004.png").unlink()
    (folder / "0004.jpg").write_bytes(truncated_jpeg(frames[3]))  # frame 4 of 8
    # cv2.imread gives this file back as a grey-padded image: it must not be tracked as a frame
    assert cv2.imread(str(folder / "0004.jpg")) is not None

    out = tmp_path / "out.txt"
    status, err = track(capsys, str(folder), "--box", box_arg(box), "-o", str(out))
    assert status == 0, err
    got = read_boxes(out)
    want = expected_boxes([*frames[:3], None, *frames[4:]], box)
    assert got.shape == (8, 4)
    assert np.array_equal(got, want)
    assert np.array_equal(got[3], got[2])  # the held box
    assert "frame 4 skipped" in err and "0004.jpg" in err
    assert "1 skipped" in err and summary_count(err) == 8


def test_image_of_another_size_is_skipped_and_the_box_held(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("WMILTRACK_NO_PROGRESS", "1")
    frames, box = make_frames(8)
    folder = tmp_path / "frames"
    folder.mkdir()
    for i, f in enumerate(frames):
        img = cv2.resize(f, (SIZE[1] // 2, SIZE[0] // 2)) if i == 5 else f
        cv2.imwrite(str(folder / f"{i + 1:04d}.png"), img)
    out = tmp_path / "out.txt"
    video = tmp_path / "out.avi"
    status, err = track(capsys, str(folder), "--box", box_arg(box), "-o", str(out), "--video", str(video))
    assert status == 0, err
    got = read_boxes(out)
    assert np.array_equal(got, expected_boxes([*frames[:5], None, *frames[6:]], box))
    assert "frame 6 skipped" in err and "80x60 differs from the first frame's 160x120" in err
    # the video keeps one frame per line too (the skipped one shows the last good frame)
    cap = cv2.VideoCapture(str(video))
    n = 0
    while cap.read()[0]:
        n += 1
    assert n == 8


def test_strict_stops_at_the_first_bad_frame_after_writing_the_boxes_so_far(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("WMILTRACK_NO_PROGRESS", "1")
    frames, box = make_frames(8)
    folder = frame_folder(tmp_path, frames)
    data = (folder / "0006.png").read_bytes()
    (folder / "0006.png").write_bytes(data[: len(data) // 3])  # truncated PNG
    out = tmp_path / "out.txt"
    status, err = track(capsys, str(folder), "--box", box_arg(box), "-o", str(out), "--strict")
    assert status == 1
    assert "error: frame 6" in err and "--strict" in err
    got = read_boxes(out)
    assert np.array_equal(got, expected_boxes(frames[:5], box))
    assert summary_count(err) == 5


def test_acceptance_second_of_two_images_truncated(tmp_path: Path) -> None:
    """The issue's acceptance check, run as a user would (a subprocess)."""
    frames, box = make_frames(2)
    folder = tmp_path / "two"
    folder.mkdir()
    cv2.imwrite(str(folder / "0001.jpg"), frames[0])
    (folder / "0002.jpg").write_bytes(truncated_jpeg(frames[1]))

    def run(*extra: str) -> subprocess.CompletedProcess[str]:
        return subprocess.run([sys.executable, "-m", "wmiltrack", "track", str(folder), "--box",
                               box_arg(box), *extra], capture_output=True, text=True, timeout=120,
                              env=ENV)

    out = tmp_path / "out.txt"
    res = run("-o", str(out))
    assert res.returncode == 0, res.stderr
    lines = out.read_text().splitlines()
    assert len(lines) == 2 and lines[1] == lines[0]
    assert "warning: frame 2 skipped" in res.stderr and "Traceback" not in res.stderr

    strict_out = tmp_path / "strict.txt"
    res = run("-o", str(strict_out), "--strict")
    assert res.returncode == 1, res.stderr
    assert strict_out.read_text().splitlines() == lines[:1]
    assert "frame 2" in res.stderr and "Traceback" not in res.stderr


def test_first_frame_unusable_is_an_error(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                          monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("WMILTRACK_NO_PROGRESS", "1")
    frames, box = make_frames(3)
    folder = tmp_path / "frames"
    folder.mkdir()
    (folder / "0001.jpg").write_bytes(truncated_jpeg(frames[0]))  # imread pads it, so it opens
    for i in (1, 2):
        cv2.imwrite(str(folder / f"{i + 1:04d}.png"), frames[i])
    status, err = track(capsys, str(folder), "--box", box_arg(box), "-o", str(tmp_path / "o.txt"))
    # refused either when the folder is opened or by the tracking loop; never tracked
    assert status == 1 and "0001.jpg" in err and "Traceback" not in err


# ------------------------------------------------------------------------- the JPEG checks
def test_jpeg_checks(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    frames, _ = make_frames(1)
    full = cv2.imencode(".jpg", frames[0])[1].tobytes()
    p = tmp_path / "x.jpg"

    def check(data: bytes) -> str | None:
        p.write_bytes(data)
        img, problem = sequences._decode_image_checked(p)
        assert (img is None) == (problem is not None)
        return problem

    assert check(full) is None
    assert check(full + b"trailing data some cameras append") is None  # no false alarm
    assert check(b"") == "empty file"
    assert check(full[: len(full) // 2]) is not None
    # OpenCV versions whose imdecode pads a truncated JPEG instead of failing: the end-marker
    # check alone must catch it (simulated by an imdecode that always returns an image)
    monkeypatch.setattr(sequences.cv2, "imdecode", lambda buf, flags: frames[0].copy())
    assert check(full) is None
    assert "truncated JPEG" in (check(full[: len(full) // 2]) or "")


# ------------------------------------------------------------------------- damaged video
def test_video_with_a_damaged_tail_keeps_every_frame_read(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("WMILTRACK_NO_PROGRESS", "1")
    frames, box = make_frames(40)
    full = tmp_path / "full.avi"
    writer = cv2.VideoWriter(str(full), cv2.VideoWriter.fourcc(*"MJPG"), 30.0, (SIZE[1], SIZE[0]))
    assert writer.isOpened()
    for f in frames:
        writer.write(f)
    writer.release()
    data = full.read_bytes()
    damaged = tmp_path / "damaged.avi"
    damaged.write_bytes(data[: int(len(data) * 0.6)])
    cap = cv2.VideoCapture(str(damaged))
    assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) == 40  # the header still announces 40
    readable = []
    while True:
        ok, img = cap.read()
        if not ok:
            break
        readable.append(img)
    cap.release()
    assert 5 < len(readable) < 40

    out = tmp_path / "out.txt"
    status, err = track(capsys, str(damaged), "--box", box_arg(box), "-o", str(out))
    assert status == 0, err
    got = read_boxes(out)
    assert np.array_equal(got, expected_boxes(list(readable), box))
    msg = f"the video ended after {len(readable)} frames; its container announces 40"
    assert f"warning: {msg}" in err and summary_count(err) == len(readable)

    status, err = track(capsys, str(damaged), "--box", box_arg(box), "-o", str(out), "--strict")
    assert status == 1 and f"error: {msg} (--strict)" in err
    assert np.array_equal(read_boxes(out), got)


# ------------------------------------------------------------------------- interrupts
@pytest.mark.parametrize(("sig", "status"), [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_interrupt_keeps_every_box_and_a_playable_video(tmp_path: Path, sig: signal.Signals,
                                                        status: int) -> None:
    # 400 frames: 100 generated ones played forth and back (smooth motion, cheap to make); the
    # run takes about two seconds here, against a few milliseconds between polls.
    base, box = make_frames(100)
    order = [*range(100), *range(98, 0, -1), *range(100), *range(98, 0, -1)][:400]
    folder = tmp_path / "long"
    folder.mkdir()
    encoded = [cv2.imencode(".png", f)[1].tobytes() for f in base]
    for i, k in enumerate(order):
        (folder / f"{i + 1:04d}.png").write_bytes(encoded[k])
    out = tmp_path / "out.txt"
    video = tmp_path / "out.avi"
    proc = subprocess.Popen([sys.executable, "-m", "wmiltrack", "track", str(folder), "--box",
                             box_arg(box), "-o", str(out), "--video", str(video)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=ENV)
    try:
        deadline = time.monotonic() + 60
        while not (out.exists() and out.read_text().count("\n") >= 5):
            assert proc.poll() is None, f"the run ended before it was interrupted:\n{proc.stderr.read() if proc.stderr else ''}"
            assert time.monotonic() < deadline, "no boxes written within 60 s"
            time.sleep(0.005)
        proc.send_signal(sig)
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == status, err
    assert f"interrupted by {sig.name}" in err and "Traceback" not in err
    n = summary_count(err)
    assert 5 <= n < 400, f"{n} frames: the run was not interrupted"
    got = read_boxes(out)  # every line parses as four numbers
    assert len(out.read_text().splitlines()) == n
    assert np.array_equal(got, expected_boxes([base[k] for k in order[:n]], box))
    cap = cv2.VideoCapture(str(video))
    assert cap.isOpened()
    played = 0
    while cap.read()[0]:
        played += 1
    assert played == n


def test_a_killed_run_keeps_every_box_written_so_far(tmp_path: Path) -> None:
    """SIGKILL cannot be caught: what survives is what was flushed. Each line is flushed as it is
    computed, so the file holds whole lines only, in order (buffered writes would leave nothing,
    or a line cut in the middle at a buffer boundary)."""
    base, box = make_frames(100)
    order = [*range(100), *range(98, 0, -1), *range(100)][:250]
    folder = tmp_path / "long"
    folder.mkdir()
    encoded = [cv2.imencode(".png", f)[1].tobytes() for f in base]
    for i, k in enumerate(order):
        (folder / f"{i + 1:04d}.png").write_bytes(encoded[k])
    out = tmp_path / "out.txt"
    proc = subprocess.Popen([sys.executable, "-m", "wmiltrack", "track", str(folder), "--box",
                             box_arg(box), "-o", str(out)],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=ENV)
    try:
        deadline = time.monotonic() + 60
        while not (out.exists() and out.read_text().count("\n") >= 5):
            assert proc.poll() is None, "the run ended before it was killed"
            assert time.monotonic() < deadline, "no boxes written within 60 s"
            time.sleep(0.005)
        proc.kill()
        proc.wait(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == -signal.SIGKILL
    text = out.read_text()
    assert text.endswith("\n")
    got = read_boxes(out)
    assert 5 <= len(got) < 250
    assert np.array_equal(got, expected_boxes([base[k] for k in order[:len(got)]], box))


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="needs /dev/full (Linux)")
def test_a_full_disk_is_an_error_message_not_a_traceback(tmp_path: Path) -> None:
    frames, box = make_frames(3)
    folder = frame_folder(tmp_path, frames)
    res = subprocess.run([sys.executable, "-m", "wmiltrack", "track", str(folder), "--box", box_arg(box),
                          "-o", "/dev/full"], capture_output=True, text=True, timeout=120, env=ENV)
    assert res.returncode == 1
    assert "cannot write the boxes" in res.stderr and "No space left" in res.stderr
    assert "Traceback" not in res.stderr
