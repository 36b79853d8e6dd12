"""Tests for wmiltrack.data.sequences on tiny generated folders and on the shared OTB data."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from wmiltrack.data.boxes import read_boxes, write_boxes
from wmiltrack.data.sequences import (
    DATA_ENV,
    Sequence,
    default_otb_root,
    list_otb_sequences,
    load_dataset,
    load_otb_sequence,
    natural_key,
    open_input,
)

H, W = 24, 32


def _img(i: int) -> np.ndarray:
    """A small frame whose mean encodes ``i`` (robust to JPEG/PNG round trips)."""
    img = np.full((H, W, 3), (i * 10) % 250, np.uint8)
    img[:, :, 2] = 200 - (i * 3) % 150  # make the channels differ: BGR order is checkable
    return img


def _frame_id(img: np.ndarray) -> int:
    return round(float(img[:, :, 0].mean()) / 10)


def make_otb(
    root: Path,
    name: str = "Seq",
    n_images: int = 6,
    gt_lines: list[str] | None = None,
    first_number: int = 1,
    start: str | None = None,
    ext: str = ".png",
) -> Path:
    seq = root / name
    (seq / "img").mkdir(parents=True)
    for k in range(n_images):
        assert cv2.imwrite(str(seq / "img" / f"{first_number + k:04d}{ext}"), _img(k))
    if gt_lines is None:
        gt_lines = [f"{k},{k + 1},10,12" for k in range(n_images)]
    (seq / "groundtruth_rect.txt").write_text("\n".join(gt_lines) + "\n")
    if start is not None:
        (seq / "start.txt").write_text(start)
    return seq


# ---------------------------------------------------------------------- boxes files
def test_read_boxes_delimiters_nan_and_blank_lines(tmp_path: Path) -> None:
    f = tmp_path / "gt.txt"
    f.write_text("1,2,3,4\r\n5\t6\t7\t8\n\n9 10  11 12\nNaN,NaN,NaN,NaN\n1.5, 2.25 ,3,4\n")
    boxes = read_boxes(f)
    assert boxes.shape == (5, 4)
    assert boxes.dtype == np.float64
    np.testing.assert_array_equal(boxes[:3], [[1, 2, 3, 4], [5, 6, 7, 8], [9, 10, 11, 12]])
    assert np.isnan(boxes[3]).all()
    np.testing.assert_array_equal(boxes[4], [1.5, 2.25, 3, 4])


def test_read_boxes_errors(tmp_path: Path) -> None:
    with pytest.raises(FileNotFoundError):
        read_boxes(tmp_path / "missing.txt")
    bad = tmp_path / "bad.txt"
    bad.write_text("1,2,3,4\n1,2,3\n")
    with pytest.raises(ValueError, match=r"bad\.txt:2"):
        read_boxes(bad)
    bad.write_text("1,2,x,4\n")
    with pytest.raises(ValueError, match="not a number"):
        read_boxes(bad)
    empty = tmp_path / "empty.txt"
    empty.write_text("")
    assert read_boxes(empty).shape == (0, 4)


def test_write_read_round_trip(tmp_path: Path) -> None:
    boxes = np.array([[1, 2, 3, 4], [152.34, 103.12, 24.9, 1 / 3], [np.nan] * 4])
    f = tmp_path / "sub" / "out.txt"
    write_boxes(f, boxes)
    lines = f.read_text().splitlines()
    assert lines[0] == "1,2,3,4"
    assert lines[2] == "NaN,NaN,NaN,NaN"
    back = read_boxes(f)
    np.testing.assert_array_equal(back, boxes)  # exact, NaN == NaN for this helper


def test_write_boxes_accepts_objects_with_box(tmp_path: Path) -> None:
    class R:
        def __init__(self, box: tuple[float, float, float, float]) -> None:
            self.box = box

    f = tmp_path / "r.txt"
    write_boxes(f, [R((1.0, 2.0, 3.0, 4.0)), R((5.5, 6.0, 7.0, 8.0))])
    np.testing.assert_array_equal(read_boxes(f), [[1, 2, 3, 4], [5.5, 6, 7, 8]])
    with pytest.raises(ValueError, match="shape"):
        write_boxes(f, np.zeros((2, 3)))


def test_natural_key_orders_numbers() -> None:
    names = ["img10.png", "img2.png", "img1.png", "Img3.png"]
    assert sorted(names, key=natural_key) == ["img1.png", "img2.png", "Img3.png", "img10.png"]


# ---------------------------------------------------------------------- OTB layout
def test_load_otb_basic(tmp_path: Path) -> None:
    seq = load_otb_sequence(make_otb(tmp_path))
    assert seq.name == "Seq"
    assert len(seq) == 6
    assert seq.groundtruth is not None and seq.groundtruth.shape == (6, 4)
    assert seq.init_box == (0.0, 1.0, 10.0, 12.0)  # used as written: no 1-based shift
    f = seq.frame(2)
    assert f.dtype == np.uint8 and f.shape == (H, W, 3)
    assert _frame_id(f) == 2
    assert _frame_id(seq.frame(-1)) == 5
    assert [_frame_id(x) for x in seq] == list(range(6))
    with pytest.raises(IndexError):
        seq.frame(6)
    frames = seq.load()
    assert len(frames) == 6 and seq.frame(3) is frames[3]
    assert seq.fps is None
    assert seq.valid.all()


def test_more_images_than_boxes_is_refused_unless_the_range_is_known(tmp_path: Path) -> None:
    # an unknown sequence with 8 images and 5 lines: nothing says which 5 are annotated
    with pytest.raises(ValueError, match="8 images but 5 ground-truth lines.*start.txt"):
        load_otb_sequence(make_otb(tmp_path, n_images=8, gt_lines=["1,1,5,5"] * 5))
    # Football1 (81 images, 74 lines): OTB-100 annotates images 1..74
    seq = load_otb_sequence(
        make_otb(tmp_path, "Football1", n_images=81, gt_lines=[f"{k},1,5,5" for k in range(74)])
    )
    assert len(seq) == 74 and seq.paths is not None and seq.paths[-1].name == "0074.png"
    assert seq.groundtruth is not None and seq.groundtruth[-1, 0] == 73


def test_known_start_frame_lines_up_by_image_number(tmp_path: Path) -> None:
    # David as OTB-100 ships it: images 0001..0770, 471 lines for images 300..770
    lines = [f"{k},2,5,5" for k in range(471)]
    seq = load_otb_sequence(make_otb(tmp_path, "David", n_images=770, gt_lines=lines))
    assert len(seq) == 471 and seq.paths is not None
    assert seq.paths[0].name == "0300.png" and seq.paths[-1].name == "0770.png"
    assert _frame_id(seq.frame(0)) == 299 % 25  # _img(k) encodes k mod 25 in its mean
    # Tiger1: 354 lines for images 1..354, OTB-100 starts at image 6 -> lines 6..354
    tiger = make_otb(tmp_path, "Tiger1", n_images=354, gt_lines=[f"{k},2,5,5" for k in range(354)])
    seq = load_otb_sequence(tiger)
    assert len(seq) == 349 and seq.paths is not None and seq.paths[0].name == "0006.png"
    assert seq.groundtruth is not None and seq.groundtruth[0, 0] == 5


def test_images_missing_from_the_annotated_range_are_refused(tmp_path: Path) -> None:
    path = make_otb(tmp_path, n_images=6)
    (path / "img" / "0003.png").unlink()
    with pytest.raises(ValueError, match=r"image\(s\) 3 are missing"):
        load_otb_sequence(path)


def test_two_target_sequences_load_as_name_dot_k(tmp_path: Path) -> None:
    seq_dir = make_otb(tmp_path, "Jogging", n_images=4)
    (seq_dir / "groundtruth_rect.txt").unlink()
    (seq_dir / "groundtruth_rect.1.txt").write_text("1,1,5,5\n" * 4)
    (seq_dir / "groundtruth_rect.2.txt").write_text("9,9,6,6\n" * 4)
    make_otb(tmp_path, "Coke", n_images=3)
    assert [p.name for p in list_otb_sequences(tmp_path)] == ["Coke", "Jogging.1", "Jogging.2"]
    one = load_otb_sequence(tmp_path / "Jogging.1")
    two = load_otb_sequence(tmp_path / "Jogging.2")
    assert (one.name, two.name) == ("Jogging.1", "Jogging.2")
    assert one.init_box == (1.0, 1.0, 5.0, 5.0) and two.init_box == (9.0, 9.0, 6.0, 6.0)
    assert [s.name for s in load_dataset(tmp_path, ["Jogging.2"])] == ["Jogging.2"]
    with pytest.raises(ValueError, match="2 targets: load one of Jogging.1, Jogging.2"):
        load_otb_sequence(seq_dir)
    with pytest.raises(FileNotFoundError, match="groundtruth_rect.3.txt"):
        load_otb_sequence(tmp_path / "Jogging.3")


def test_start_file_by_image_number(tmp_path: Path) -> None:
    # images 0300..0307; start.txt names image 302 -> the 4 GT lines belong to 0302..0305
    path = make_otb(tmp_path, n_images=8, first_number=300, start="302\n", gt_lines=["1,2,3,4"] * 4)
    seq = load_otb_sequence(path)
    assert len(seq) == 4
    assert seq.paths is not None and seq.paths[0].name == "0302.png"
    assert _frame_id(seq.frame(0)) == 2


def test_start_file_by_position(tmp_path: Path) -> None:
    # no image is numbered 3 -> the 3rd image (1-based)
    path = make_otb(tmp_path, n_images=6, first_number=100, start="3", gt_lines=["1,2,3,4"] * 4)
    seq = load_otb_sequence(path)
    assert seq.paths is not None and seq.paths[0].name == "0102.png"
    assert len(seq) == 4


def test_bad_start_file(tmp_path: Path) -> None:
    path = make_otb(tmp_path, n_images=4, start="99", gt_lines=["1,2,3,4"])
    with pytest.raises(ValueError, match="start image 99"):
        load_otb_sequence(path)


def test_nan_lines_and_tab_delimiter(tmp_path: Path) -> None:
    lines = ["10\t20\t30\t40", "NaN\tNaN\tNaN\tNaN", "11\t21\t30\t40"]
    seq = load_otb_sequence(make_otb(tmp_path, n_images=3, gt_lines=lines, ext=".jpg"))
    assert seq.groundtruth is not None
    assert np.isnan(seq.groundtruth[1]).all()
    np.testing.assert_array_equal(seq.valid, [True, False, True])
    assert seq.init_box == (10.0, 20.0, 30.0, 40.0)


def test_init_box_errors() -> None:
    frames = [_img(0), _img(1)]
    with pytest.raises(ValueError, match="no ground truth"):
        _ = Sequence("a", frames=frames).init_box
    gt = np.array([[np.nan] * 4, [1, 2, 3, 4]])
    with pytest.raises(ValueError, match="not annotated in frame 0"):
        _ = Sequence("b", groundtruth=gt, frames=frames).init_box


def test_sequence_validation() -> None:
    with pytest.raises(ValueError, match="exactly one"):
        Sequence("x")
    with pytest.raises(ValueError, match="2 ground-truth boxes for 1 frames"):
        Sequence("x", groundtruth=np.zeros((2, 4)), frames=[_img(0)])
    with pytest.raises(ValueError, match="uint8"):
        Sequence("x", frames=[np.zeros((4, 4, 3), np.float32)])
    gray = Sequence("g", frames=[np.zeros((4, 5), np.uint8)])
    assert gray.frame(0).shape == (4, 5, 3)


def test_missing_pieces(tmp_path: Path) -> None:
    with pytest.raises(FileNotFoundError):
        load_otb_sequence(tmp_path / "nope")
    (tmp_path / "noimg").mkdir()
    (tmp_path / "noimg" / "groundtruth_rect.txt").write_text("1,2,3,4\n")
    with pytest.raises(FileNotFoundError, match="img/"):
        load_otb_sequence(tmp_path / "noimg")
    (tmp_path / "nogt" / "img").mkdir(parents=True)
    with pytest.raises(FileNotFoundError, match="groundtruth_rect.txt"):
        load_otb_sequence(tmp_path / "nogt")
    (tmp_path / "empty" / "img").mkdir(parents=True)
    (tmp_path / "empty" / "groundtruth_rect.txt").write_text("1,2,3,4\n")
    with pytest.raises(ValueError, match="no images"):
        load_otb_sequence(tmp_path / "empty")


def test_list_and_load_dataset(tmp_path: Path) -> None:
    make_otb(tmp_path, "B")
    make_otb(tmp_path, "A", n_images=3)
    (tmp_path / "not_a_sequence").mkdir()
    (tmp_path / "file.txt").write_text("x")
    assert [p.name for p in list_otb_sequences(tmp_path)] == ["A", "B"]
    assert [s.name for s in load_dataset(tmp_path)] == ["A", "B"]
    assert [s.name for s in load_dataset(tmp_path, ["B", "A"])] == ["B", "A"]
    assert [s.name for s in load_dataset(tmp_path, "A")] == ["A"]
    with pytest.raises(FileNotFoundError, match="C.*available: A, B"):
        load_dataset(tmp_path, ["A", "C"])
    with pytest.raises(FileNotFoundError, match=DATA_ENV):
        list_otb_sequences(tmp_path / "missing")


def test_default_otb_root(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.setenv(DATA_ENV, str(tmp_path))
    assert default_otb_root() == tmp_path
    monkeypatch.delenv(DATA_ENV)
    monkeypatch.chdir(tmp_path)
    assert default_otb_root() == (tmp_path.parent / "shared" / "data" / "otb").resolve()


# ---------------------------------------------------------------------- open_input
def test_open_input_image_folder_natural_order(tmp_path: Path) -> None:
    d = tmp_path / "frames"
    d.mkdir()
    for k in (1, 2, 10, 3):
        cv2.imwrite(str(d / f"f{k}.png"), _img(k))
    (d / "notes.txt").write_text("ignored")
    seq = open_input(d)
    assert seq.groundtruth is None
    assert seq.paths is not None and [p.name for p in seq.paths] == [
        "f1.png",
        "f2.png",
        "f3.png",
        "f10.png",
    ]
    assert [_frame_id(f) for f in seq] == [1, 2, 3, 10]
    with pytest.raises(ValueError, match="no ground truth"):
        _ = seq.init_box


def test_open_input_otb_folder_and_img_only(tmp_path: Path) -> None:
    seq = open_input(make_otb(tmp_path, n_images=4))
    assert seq.groundtruth is not None and len(seq) == 4
    d = tmp_path / "imgonly"
    (d / "img").mkdir(parents=True)
    cv2.imwrite(str(d / "img" / "0001.jpg"), _img(0))
    seq2 = open_input(d)
    assert seq2.groundtruth is None and len(seq2) == 1


def test_open_input_errors(tmp_path: Path) -> None:
    with pytest.raises(FileNotFoundError):
        open_input(tmp_path / "missing.mp4")
    (tmp_path / "empty").mkdir()
    with pytest.raises(ValueError, match="no images"):
        open_input(tmp_path / "empty")
    bad = tmp_path / "bad"
    bad.mkdir()
    (bad / "0001.jpg").write_bytes(b"not a jpeg at all")
    with pytest.raises(ValueError, match="could not decode"):
        open_input(bad)
    junk = tmp_path / "junk.mp4"
    junk.write_bytes(b"\x00garbage" * 10)
    with pytest.raises(ValueError, match="junk.mp4"):
        open_input(junk)
    img = tmp_path / "one.png"
    cv2.imwrite(str(img), _img(0))
    with pytest.raises(ValueError, match="single image"):
        open_input(img)


def _write_video(path: Path, n: int) -> bool:
    for fourcc in ("MJPG", "mp4v"):
        target = path.with_suffix(".avi" if fourcc == "MJPG" else ".mp4")
        writer = cv2.VideoWriter(str(target), cv2.VideoWriter.fourcc(*fourcc), 20.0, (W, H))
        if not writer.isOpened():
            continue
        for k in range(n):
            writer.write(_img(k))
        writer.release()
        if target.is_file() and target.stat().st_size > 0:
            if target != path:
                target.rename(path)
            return True
    return False


def test_open_input_video(tmp_path: Path) -> None:
    video = tmp_path / "clip.avi"
    if not _write_video(video, 7):
        pytest.skip("no OpenCV video codec (MJPG/mp4v) available to write a test video")
    seq = open_input(video)
    assert seq.name == "clip"
    assert seq.groundtruth is None
    assert seq.fps == pytest.approx(20.0)
    assert len(seq) == 7
    ids = [_frame_id(f) for f in seq]
    assert ids == list(range(7))
    # random access, forwards and backwards
    assert _frame_id(seq.frame(5)) == 5
    assert _frame_id(seq.frame(2)) == 2
    assert _frame_id(seq.frame(3)) == 3
    assert seq.frame(0).shape == (H, W, 3) and seq.frame(0).dtype == np.uint8
    frames = seq.load()
    assert len(frames) == 7 and seq.frame(6) is frames[6]
    seq.close()
    with_gt = Sequence("v", groundtruth=np.ones((7, 4)), video=video)
    assert with_gt.init_box == (1.0, 1.0, 1.0, 1.0)
    with pytest.raises(ValueError, match="8 ground-truth boxes for 7 frames"):
        Sequence("v", groundtruth=np.ones((8, 4)), video=video)


def test_in_memory_sequence() -> None:
    frames = [_img(k) for k in range(3)]
    seq = Sequence("mem", groundtruth=np.zeros((3, 4)), fps=30.0, frames=frames)
    assert len(seq) == 3 and seq.load() is seq.load()
    assert seq.frames is not None and seq.frame(1) is seq.frames[1]
    assert "mem" in repr(seq)


def test_module_does_not_import_extension() -> None:
    code = (
        "import sys, wmiltrack.data.sequences; "
        "bad = [m for m in sys.modules if m.startswith('wmiltrack.') and "
        "m.split('.')[-1].startswith('_')]; "
        "assert not bad, bad"
    )
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    subprocess.run([sys.executable, "-c", code], check=True, env=env, timeout=60)


# ---------------------------------------------------------------------- real data
EXPECTED = {
    "Car4": 659, "Coke": 291, "Couple": 140, "Crossing": 120, "David": 471, "Dog": 127,
    "Football1": 74, "Girl": 500, "Jumping": 313, "MotorRolling": 164, "MountainBike": 228,
    "Panda": 1000, "Pedestrian3": 184, "Skiing": 81, "Surfer": 376, "Woman_first129": 129,
    "vot15_bag": 196,
}  # fmt: skip


def _manifest(otb_root: Path) -> dict[str, tuple[int, int, int]]:
    """name -> (frames, width, height) from MANIFEST.tsv next to otb/ ("81 (GT 74)" -> 74)."""
    path = otb_root.parent / "MANIFEST.tsv"
    if not path.is_file():
        return {}
    out: dict[str, tuple[int, int, int]] = {}
    lines = path.read_text().splitlines()
    header = lines[0].split("\t")
    for line in lines[1:]:
        row = dict(zip(header, line.split("\t")))
        nums = [int(x) for x in re.findall(r"\d+", row["frames"])]
        out[row["name"]] = (nums[-1], int(row["width"]), int(row["height"]))
    return out


def test_real_all_sequences_load(otb_root: Path) -> None:
    seqs = load_dataset(otb_root)
    names = {s.name for s in seqs}
    assert set(EXPECTED) <= names
    manifest = _manifest(otb_root)
    for s in seqs:
        if s.name not in EXPECTED:
            continue
        n = EXPECTED[s.name]
        assert len(s) == n, s.name
        assert s.groundtruth is not None and s.groundtruth.shape == (n, 4), s.name
        first = s.frame(0)
        assert first.dtype == np.uint8 and first.ndim == 3 and first.shape[2] == 3
        _, _, w, h = s.init_box
        assert w > 0 and h > 0
        if s.name in manifest:
            frames, width, height = manifest[s.name]
            assert frames == n, s.name
            assert first.shape[:2] == (height, width), s.name
            assert s.frame(-1).shape[:2] == (height, width), s.name


def test_real_special_cases(otb_root: Path) -> None:
    ped = load_otb_sequence(otb_root / "Pedestrian3")
    assert ped.groundtruth is not None
    assert int((~ped.valid).sum()) == 28
    assert np.isnan(ped.groundtruth[52]).all()  # file line 53 is NaN
    football = load_otb_sequence(otb_root / "Football1")
    assert len(football) == 74
    assert football.paths is not None and football.paths[-1].name == "0074.jpg"
    david = load_otb_sequence(otb_root / "David")
    assert david.paths is not None and david.paths[0].name == "0300.jpg"
    assert david.init_box == (129.0, 80.0, 64.0, 78.0)
    bag = load_otb_sequence(otb_root / "vot15_bag")
    assert bag.init_box == pytest.approx((291.827, 124.711, 150.346, 139.578))
    girl = open_input(otb_root / "Girl")  # tab delimited with CRLF line ends
    assert girl.init_box == (57.0, 21.0, 31.0, 45.0)
