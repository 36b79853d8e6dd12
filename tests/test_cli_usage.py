"""The command line as a new user meets it (issue 27): a failed run leaves an existing output
file alone, usage errors are one ``wmiltrack: error:`` line with exit status 2, and the
library's own noise stays out of the way. Videos are generated from the synthetic sequences."""

from __future__ import annotations

from pathlib import Path

import cv2
import pytest

from wmiltrack import cli
from wmiltrack.data import synthetic

SIZE = (96, 128)    # frame height, width
TARGET = (24, 20)   # target width, height


def write_video(path: Path, n: int = 12, seed: int = 1) -> tuple[Path, tuple[float, ...]]:
    """A generated sequence as an mp4 (mp4v) video; returns its path and first true box."""
    seq = synthetic.make_preset("easy", seed=seed, n_frames=n, size=SIZE, target_size=TARGET)
    assert seq.groundtruth is not None
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter.fourcc(*"mp4v"), 20.0, (SIZE[1], SIZE[0]))
    assert writer.isOpened(), "OpenCV cannot write mp4v here"
    for f in seq.load():
        writer.write(f if f.ndim == 3 else cv2.cvtColor(f, cv2.COLOR_GRAY2BGR))
    writer.release()
    return path, tuple(float(v) for v in seq.groundtruth[0])


@pytest.fixture(scope="module")
def video(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, tuple[float, ...]]:
    return write_video(tmp_path_factory.mktemp("video") / "clip.mp4")


# ------------------------------------------------------------------- output left alone
@pytest.mark.parametrize("box", ["10,10,0,20", "500,500,20,20"], ids=["zero-width", "outside"])
def test_a_run_that_cannot_start_leaves_the_output_byte_identical(
        video: tuple[Path, tuple[float, ...]], tmp_path: Path, box: str,
        capsys: pytest.CaptureFixture[str]) -> None:
    keep = tmp_path / "keep.txt"
    content = "".join(f"{i},{i},20,20\n" for i in range(500)).encode()
    keep.write_bytes(content)
    status = cli.main(["track", str(video[0]), f"--box={box}", "-o", str(keep)])
    err = capsys.readouterr().err
    assert status == 1 and "wmiltrack: error:" in err
    assert keep.read_bytes() == content
    # and a good run does replace it
    assert cli.main(["track", str(video[0]), "--box", ",".join(map(str, video[1])), "-o", str(keep)]) == 0
    assert len(keep.read_text().splitlines()) == 12
