"""``wmiltrack track --list FILE``: many clips, each from its own first box, on the executors of
``eval``; each box file complete or absent, and a second run resumes (issue 27 point 8).
The clips are generated (synthetic sequences written as videos and an image folder)."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from wmiltrack import cli
from wmiltrack.data import synthetic
from wmiltrack.data.boxes import read_boxes
from wmiltrack.trackers import make_tracker

SIZE = (96, 128)
TARGET = (24, 20)
N = 10


def _frames(seed: int) -> tuple[list[np.ndarray], tuple[float, ...]]:
    seq = synthetic.make_preset("easy", seed=seed, n_frames=N, size=SIZE, target_size=TARGET)
    assert seq.groundtruth is not None
    return seq.load(), tuple(float(v) for v in seq.groundtruth[0])


@pytest.fixture(scope="module")
def clips(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[str, tuple[float, ...]]]:
    """Two mp4 clips and an image folder, and the list file naming them with their first box."""
    root = tmp_path_factory.mktemp("clips")
    firsts: dict[str, tuple[float, ...]] = {}
    (root / "videos").mkdir()
    for k, name in enumerate(("walk.mp4", "run.mp4")):
        frames, box = _frames(10 + k)
        writer = cv2.VideoWriter(str(root / "videos" / name), cv2.VideoWriter.fourcc(*"mp4v"), 20.0,
                                 (SIZE[1], SIZE[0]))
        assert writer.isOpened()
        for f in frames:
            writer.write(f)
        writer.release()
        firsts[Path(name).stem] = box
    frames, box = _frames(12)
    (root / "stills").mkdir()
    for i, f in enumerate(frames):
        assert cv2.imwrite(str(root / "stills" / f"{i + 1:04d}.png"), f)
    firsts["stills"] = box
    lines = ["# clip  first box", f"videos/walk.mp4 {','.join(map(repr, firsts['walk']))}", "",
             f"videos/run.mp4\t{' '.join(map(repr, firsts['run']))}", f"stills {','.join(map(repr, firsts['stills']))}"]
    (root / "clips.txt").write_text("\n".join(lines) + "\n")
    return root / "clips.txt", firsts


def _files(out: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(out.iterdir())}


def _track(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str]:
    status = cli.main(["track", *args])
    return status, capsys.readouterr().err


@pytest.fixture(scope="module")
def serial(clips: tuple[Path, dict[str, tuple[float, ...]]], tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("serial")
    assert cli.main(["track", "--list", str(clips[0]), "-o", str(out), "-j", "1"]) == 0
    return out


def test_one_box_file_per_clip_as_single_track_gives(clips: tuple[Path, dict[str, tuple[float, ...]]],
                                                      serial: Path) -> None:
    assert sorted(p.name for p in serial.iterdir()) == ["run.txt", "stills.txt", "walk.txt"]
    # the image folder's boxes equal the Python API's on the same (lossless) frames
    frames, box = _frames(12)
    t = make_tracker("rcwmil", seed=0)
    t.init(frames[0], box)
    want = [t.box] + [t.update(f).box for f in frames[1:]]  # type: ignore[attr-defined]
    np.testing.assert_array_equal(read_boxes(serial / "stills.txt"), np.asarray(want))
    for name in ("walk", "run"):
        assert read_boxes(serial / f"{name}.txt").shape == (N, 4)


@pytest.mark.extras("distributed")
def test_dask_gives_the_same_box_files_as_j1(clips: tuple[Path, dict[str, tuple[float, ...]]], serial: Path,
                                             tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "dask"
    status, err = _track(capsys, "--list", str(clips[0]), "-o", str(out), "--executor", "dask", "-j", "2")
    assert status == 0, err
    assert _files(out) == _files(serial)
    assert "3 clips: 3 tracked" in err


def test_worker_processes_give_the_same_box_files(clips: tuple[Path, dict[str, tuple[float, ...]]],
                                                  serial: Path, tmp_path: Path) -> None:
    out = tmp_path / "proc"
    assert cli.main(["track", "--list", str(clips[0]), "-o", str(out), "-j", "2"]) == 0
    assert _files(out) == _files(serial)


def test_a_second_run_resumes_and_a_partial_file_is_not_taken_for_done(
        clips: tuple[Path, dict[str, tuple[float, ...]]], serial: Path, tmp_path: Path,
        capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "resume"
    out.mkdir()
    want = _files(serial)
    (out / "walk.txt").write_bytes(want["walk.txt"])              # finished by an earlier run
    (out / "run.txt.partial").write_text("1,2,3,4\n")             # a run killed while writing
    (out / "stills.txt").write_text("not touched: exists\n")      # exists: taken as done
    status, err = _track(capsys, "--list", str(clips[0]), "-o", str(out))
    assert status == 0, err
    assert "3 clips: 1 tracked; 2 already done" in err
    assert (out / "run.txt").read_bytes() == want["run.txt"] and not (out / "run.txt.partial").exists()
    assert (out / "stills.txt").read_text() == "not touched: exists\n"
    status, err = _track(capsys, "--list", str(clips[0]), "-o", str(out))
    assert status == 0 and "0 tracked; 3 already done" in err


def test_a_failing_clip_is_named_and_the_others_are_written(
        clips: tuple[Path, dict[str, tuple[float, ...]]], serial: Path, tmp_path: Path,
        capsys: pytest.CaptureFixture[str]) -> None:
    lst = tmp_path / "clips.txt"
    root = clips[0].parent
    lst.write_text(f"{root / 'videos' / 'walk.mp4'} 10,10,0,20\n{root / 'stills'} "
                   + ",".join(map(repr, clips[1]["stills"])) + "\n")
    out = tmp_path / "out"
    status, err = _track(capsys, "--list", str(lst), "-o", str(out))
    assert status == 1
    assert "wmiltrack: error: walk.mp4 (line 1): ValueError" in err and "1 failed" in err
    assert _files(out) == {"stills.txt": _files(serial)["stills.txt"]}  # no file for the failed clip


@pytest.mark.parametrize(("text", "msg"), [
    ("videos/walk.mp4\n", ":1: expected 'PATH x,y,w,h'"),
    ("videos/nope.mp4 1,2,3,4\n", ":1: "),
    ("videos/walk.mp4 1,2,3,4\nvideos/walk.mp4 5,6,7,8\n", ":2: its box file"),
    ("# nothing\n", "lists no clip"),
])
def test_list_file_errors_name_the_line(clips: tuple[Path, dict[str, tuple[float, ...]]], tmp_path: Path,
                                        text: str, msg: str, capsys: pytest.CaptureFixture[str]) -> None:
    lst = clips[0].parent / f"bad{abs(hash(text))}.txt"
    lst.write_text(text)
    status, err = _track(capsys, "--list", str(lst), "-o", str(tmp_path / "o"))
    assert status == 1 and msg in err, err


def test_list_usage_errors(clips: tuple[Path, dict[str, tuple[float, ...]]], tmp_path: Path,
                           capsys: pytest.CaptureFixture[str]) -> None:
    lst = str(clips[0])
    for args in (["--list", lst],                                        # no -o
                 ["--list", lst, "-o", str(tmp_path), "--box", "1,2,3,4"],
                 ["--list", lst, "-o", str(tmp_path), "--scheduler", "tcp://x:1"],
                 ["--list", lst, "-o", str(tmp_path), "-t", "nope"],
                 ["x.mp4", "-j", "2"],
                 []):
        status, err = _track(capsys, *args)
        assert status == 2 and err.strip().splitlines()[-1].startswith("wmiltrack: error: "), (args, err)
    assert not any(tmp_path.iterdir())
