"""Benchmark layouts (wmiltrack.data.layouts) on tiny datasets generated in tmp_path.

Frame ``k`` of every generated sequence is a uniform image of grey level ``_level(k)`` and its
ground-truth box has ``x = k + 1``, so a test can tell from a decoded frame and a ground-truth row
which frame they belong to (alignment), whatever order the files were listed in.
"""

from __future__ import annotations

import math
from pathlib import Path

import cv2
import numpy as np
import pytest

from wmiltrack.data.layouts import (
    LayoutError,
    detect_layout,
    list_layout,
    load_layout,
    parse_vot_region,
    polygon_to_box,
    uav,
)
from wmiltrack.data.sequences import Sequence

H, W = 16, 20


def _level(k: int) -> int:
    return 10 + 19 * k  # k <= 12 stays below 255


def _frame_id(img: np.ndarray) -> int:
    return int(round((float(img.mean()) - 10) / 19))


def _write_frames(folder: Path, ks: list[int], name=lambda k: f"{k + 1:08d}.jpg") -> None:
    folder.mkdir(parents=True, exist_ok=True)
    for k in ks:
        img = np.full((H, W, 3), _level(k), np.uint8)
        assert cv2.imwrite(str(folder / name(k)), img)


def _box(k: int) -> list[float]:
    return [k + 1.0, 2.0, 6.0, 5.0]


def _write_lines(path: Path, rows: list[list[float]] | list[str]) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    lines = [r if isinstance(r, str) else ",".join(f"{v:g}" for v in r) for r in rows]
    path.write_text("\n".join(lines) + "\n")


def _assert_aligned(seq: Sequence, n: int) -> None:
    """Frame k decodes to level k and ground-truth row k (if present) is _box(k)."""
    assert len(seq) == n
    assert seq.groundtruth is not None and seq.groundtruth.shape == (n, 4)
    frames = list(seq)
    assert len(frames) == n
    for k, img in enumerate(frames):
        assert img.shape == (H, W, 3)
        assert _frame_id(img) == k
        row = seq.groundtruth[k]
        if np.all(np.isfinite(row)):
            assert row.tolist() == _box(k)


# ---------------------------------------------------------------------- LaSOT
def _lasot_seq(root: Path, cls: str, idx: int, n: int = 5, occ=None, oov=None) -> Path:
    d = root / cls / f"{cls}-{idx}"
    _write_frames(d / "img", list(range(n)))
    _write_lines(d / "groundtruth.txt", [_box(k) for k in range(n)])
    occ = occ if occ is not None else [0] * n
    oov = oov if oov is not None else [0] * n
    (d / "full_occlusion.txt").write_text(",".join(map(str, occ)) + "\n")
    (d / "out_of_view.txt").write_text(",".join(map(str, oov)) + "\n")
    (d / "nlp.txt").write_text("a small grey square\n")
    return d


def test_lasot_root_class_folder_and_sequence_folder(tmp_path: Path) -> None:
    _lasot_seq(tmp_path, "airplane", 1, occ=[0, 0, 1, 0, 0], oov=[0, 0, 0, 0, 1])
    _lasot_seq(tmp_path, "airplane", 10)
    _lasot_seq(tmp_path, "airplane", 2)
    _lasot_seq(tmp_path, "bird", 1)
    assert detect_layout(tmp_path) == "lasot"
    assert list_layout(tmp_path) == ["airplane-1", "airplane-2", "airplane-10", "bird-1"]

    (seq,) = load_layout(tmp_path, sequences=["airplane-1"])
    _assert_aligned(seq, 5)
    assert seq.meta["layout"] == "lasot"
    assert seq.meta["absent"].tolist() == [False, False, True, False, True]
    assert np.isnan(seq.groundtruth[[2, 4]]).all()
    assert seq.valid.tolist() == [True, True, False, True, False]
    assert seq.meta["absent_policy"] == "fail"
    assert seq.meta["category"] == "airplane"
    assert seq.init_box == tuple(_box(0))

    # A class folder and a single sequence folder are LaSOT too.
    assert list_layout(tmp_path / "airplane") == ["airplane-1", "airplane-2", "airplane-10"]
    assert detect_layout(tmp_path / "bird" / "bird-1") == "lasot"
    assert [s.name for s in load_layout(tmp_path / "bird" / "bird-1", "lasot")] == ["bird-1"]


def test_lasot_refuses_count_mismatch_and_bad_flags(tmp_path: Path) -> None:
    d = _lasot_seq(tmp_path, "cat", 1, n=5)
    _write_frames(d / "img", [5])  # a sixth image, no sixth box
    with pytest.raises(LayoutError, match=r"6 images in .* but 5 boxes"):
        load_layout(tmp_path)
    d2 = _lasot_seq(tmp_path / "other", "cat", 2, n=4)
    (d2 / "out_of_view.txt").write_text("0,0,1\n")
    with pytest.raises(LayoutError, match=r"out_of_view.txt has 3 values for 4 frames"):
        load_layout(tmp_path / "other")


def test_listing_and_loading_decode_no_image(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Loading a dataset must not open a single image (1 400 LaSOT sequences would take minutes)."""
    for i in range(1, 31):
        d = tmp_path / "dog" / f"dog-{i}"
        (d / "img").mkdir(parents=True)
        for k in range(3):
            (d / "img" / f"{k + 1:08d}.jpg").write_bytes(b"not a jpeg")  # undecodable
        _write_lines(d / "groundtruth.txt", [_box(k) for k in range(3)])

    def boom(*args: object, **kwargs: object) -> None:
        raise AssertionError("an image was read while loading")

    monkeypatch.setattr(cv2, "imread", boom)
    seqs = load_layout(tmp_path)
    assert len(seqs) == 30 and all(len(s) == 3 for s in seqs)
    monkeypatch.undo()
    with pytest.raises(ValueError, match="could not decode"):
        seqs[0].frame(0)


# ---------------------------------------------------------------------- GOT-10k
def _got_seq(
    split_dir: Path, name: str, n: int = 6, absence=None, cover=None, gt_rows=None, meta_ini: bool = True
) -> Path:
    d = split_dir / name
    _write_frames(d, list(range(n)))
    _write_lines(d / "groundtruth.txt", gt_rows if gt_rows is not None else [_box(k) for k in range(n)])
    if absence is not None:
        _write_lines(d / "absence.label", [str(v) for v in absence])
    if cover is not None:
        _write_lines(d / "cover.label", [str(v) for v in cover])
    if meta_ini:
        (d / "meta_info.ini").write_text(
            "[METAINFO]\nurl: https://example.invalid\nobject_class: grey square\n"
            f"resolution: ({W}, {H})\nmotion_class: moving\n"
        )
    return d


def _got_split(root: Path, split: str, specs: dict[str, dict]) -> Path:
    sd = root / split
    for name, kw in specs.items():
        _got_seq(sd, name, **kw)
    (sd / "list.txt").write_text("\n".join(specs) + "\n")
    return sd


def test_got10k_root_splits_and_absent_frames(tmp_path: Path) -> None:
    n = 6
    _got_split(tmp_path, "train", {"GOT-10k_Train_000001": {"n": 3, "absence": [0] * 3, "cover": [8] * 3}})
    _got_split(
        tmp_path,
        "val",
        {
            # listed out of natural order on purpose: list.txt order is kept
            "GOT-10k_Val_000002": {"absence": [0] * n, "cover": [8] * n},
            "GOT-10k_Val_000001": {
                "absence": [0, 0, 1, 0, 0, 0],
                "cover": [8, 5, 0, 0, 3, 8],  # frame 3: cover 0 without the absence flag
            },
        },
    )
    first_only = [_box(0)]
    # the test split: first box only, no labels, no meta_info.ini (found by the folder names)
    _got_split(tmp_path, "test", {"GOT-10k_Test_000001": {"gt_rows": first_only, "meta_ini": False}})

    assert detect_layout(tmp_path) == "got10k"
    assert list_layout(tmp_path) == ["GOT-10k_Val_000002", "GOT-10k_Val_000001"]  # val by default
    seqs = load_layout(tmp_path, "got-10k", sequences="GOT-10k_Val_000001")
    (seq,) = seqs
    _assert_aligned(seq, n)
    assert seq.meta["absent"].tolist() == [False, False, True, True, False, False]
    assert np.isnan(seq.groundtruth[[2, 3]]).all() and np.isfinite(seq.groundtruth[[0, 1, 4, 5]]).all()
    assert seq.meta["resolution"] == (W, H)
    assert seq.meta["split"] == "val" and seq.meta["absent_policy"] == "exclude"
    assert seq.meta["cover"].tolist() == [8, 5, 0, 0, 3, 8]

    assert detect_layout(tmp_path / "test") == "got10k"
    (test_seq,) = load_layout(tmp_path / "test")
    assert test_seq.meta["first_frame_only"] is True and "resolution" not in test_seq.meta
    assert len(test_seq) == n and test_seq.init_box == tuple(_box(0))
    assert np.isnan(test_seq.groundtruth[1:]).all()
    _assert_aligned(test_seq, n)

    (train_seq,) = load_layout(tmp_path / "train")
    assert train_seq.meta["split"] == "train" and len(train_seq) == 3


def test_got10k_split_without_list_and_broken_splits(tmp_path: Path) -> None:
    sd = tmp_path / "mine"
    _got_seq(sd, "GOT-10k_Val_000007", n=4, absence=[0, 0, 0, 0])
    assert detect_layout(sd) == "got10k"
    assert list_layout(sd) == ["GOT-10k_Val_000007"]
    assert detect_layout(sd / "GOT-10k_Val_000007") == "got10k"  # one sequence folder

    # list.txt naming a folder that is not there
    (sd / "list.txt").write_text("GOT-10k_Val_000007\nGOT-10k_Val_000008\n")
    with pytest.raises(LayoutError, match=r"list.txt names 1 sequence\(s\) with no folder \(GOT-10k_Val_000008\)"):
        load_layout(sd)

    # images and boxes disagree
    bad = tmp_path / "bad"
    _got_seq(bad, "GOT-10k_Val_000001", n=4, gt_rows=[_box(k) for k in range(3)])
    with pytest.raises(LayoutError, match=r"GOT-10k sequence GOT-10k_Val_000001: 4 images .* but 3 boxes"):
        load_layout(bad)

    # labels of the wrong length
    lab = tmp_path / "lab"
    _got_seq(lab, "GOT-10k_Val_000001", n=4, absence=[0, 0, 0])
    with pytest.raises(LayoutError, match=r"absence.label has 3 values for 4 frames"):
        load_layout(lab)

    # several splits and no val/
    two = tmp_path / "two"
    _got_split(two, "train", {"GOT-10k_Train_000001": {"n": 3}})
    _got_split(two, "test", {"GOT-10k_Test_000001": {"n": 3, "gt_rows": [_box(0)]}})
    with pytest.raises(LayoutError, match=r"several GOT-10k splits \(train, test\) and no val/"):
        detect_layout(two)


# ---------------------------------------------------------------------- UAV123
def _uav_frames(root: Path, folder: str, numbers: list[int]) -> None:
    # frame number f holds level f - 1 so that alignment can be checked against numbers
    d = root / "data_seq" / "UAV123" / folder
    _write_frames(d, [f - 1 for f in numbers], name=lambda k: f"{k + 1:06d}.jpg")


def test_uav123_layout_nan_lines_and_split_sequences(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    root = tmp_path / "Dataset_UAV123"
    inner = root / "UAV123"
    _uav_frames(inner, "bike1", [1, 2, 3, 4])
    _write_lines(
        inner / "anno" / "UAV123" / "bike1.txt",
        [_box(0), "NaN,NaN,NaN,NaN", _box(2), _box(3)],
    )
    # A sequence that covers frames 5..8 of a shared folder (the real table has hundreds of
    # frames per part; a tiny stand-in entry exercises the same code).
    monkeypatch.setitem(uav.UAV123_SPLITS, "bird1_2", ("bird1", 5, 8))
    _uav_frames(inner, "bird1", list(range(1, 11)))
    _write_lines(inner / "anno" / "UAV123" / "bird1_2.txt", [_box(k) for k in range(4, 8)])

    assert detect_layout(root) == "uav123"  # the outer download folder
    assert list_layout(inner) == ["bike1", "bird1_2"]
    bike, bird = load_layout(root)
    _assert_aligned(bike, 4)
    assert bike.meta["absent"].tolist() == [False, True, False, False]
    assert bike.meta["absent_policy"] == "exclude"
    assert bird.meta["frame_range"] == (5, 8) and bird.meta["folder"] == "bird1"
    assert [_frame_id(f) for f in bird] == [4, 5, 6, 7]
    assert bird.groundtruth.tolist() == [_box(k) for k in range(4, 8)]


def test_uav123_split_table_matches_published_ranges() -> None:
    # got10k-toolkit got10k/datasets/uav123.json; pytracking's uavdataset.py agrees.
    table = uav.UAV123_SPLITS
    assert len(table) == 51
    assert table["bird1_2"] == ("bird1", 775, 1477)
    assert table["car1_2"] == ("car1", 751, 1627)
    assert table["uav1_3"] == ("uav1", 2473, 3469)
    assert table["group3_4"] == ("group3", 4369, 5527)


def test_uav123_refuses_missing_frames_and_count_mismatch(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(uav.UAV123_SPLITS, "car1_2", ("car1", 3, 6))
    _uav_frames(tmp_path, "car1", [1, 2, 3, 4, 6])  # 5 missing
    _write_lines(tmp_path / "anno" / "UAV123" / "car1_2.txt", [_box(k) for k in range(2, 6)])
    with pytest.raises(LayoutError, match=r"frames 3-6 of .* are needed but 1 are missing \(first: 000005\)"):
        load_layout(tmp_path, "uav123", sequences=["car1_2"])
    _uav_frames(tmp_path, "bike2", [1, 2, 3])
    _write_lines(tmp_path / "anno" / "UAV123" / "bike2.txt", [_box(k) for k in range(4)])
    with pytest.raises(LayoutError, match=r"UAV123 sequence bike2: 3 images .* but 4 boxes"):
        load_layout(tmp_path, "uav", sequences=["bike2"])


def test_uav20l_when_only_that_annotation_folder_exists(tmp_path: Path) -> None:
    _uav_frames(tmp_path, "bird1", [1, 2, 3])  # UAV20L uses whole folders
    _write_lines(tmp_path / "anno" / "UAV20L" / "bird1.txt", [_box(k) for k in range(3)])
    assert detect_layout(tmp_path) == "uav20l"
    (seq,) = load_layout(tmp_path)
    assert seq.meta["subset"] == "UAV20L" and seq.meta["layout"] == "uav20l"
    _assert_aligned(seq, 3)


def _config_seqs(path: Path, tables: dict[str, list[tuple[str, str, int, int]]], style: str = "literal") -> None:
    """Write a configSeqs.m in the releases' form: one cell array of structs per subset."""
    out = ["function seqs=configSeqs", "% written by the tests: name, folder, startFrame, endFrame", ""]
    for var, rows in tables.items():
        items = []
        for name, folder, start, end in rows:
            if style == "literal":
                where = f"'D:\\data_seq\\{var}\\{folder}\\'"
            elif style == "fullfile":
                where = f"fullfile(dataset_path, '{folder}\\')"
            else:  # concatenation
                where = f"[dataSet '\\{folder}\\']"
            items.append(
                f"struct('name','{name}','path',{where},'startFrame',{start},'endFrame',{end},"
                "'nz',6,'ext','jpg','init_rect', [0,0,0,0])"
            )
        out.append(f"seq{var} = {{" + ",...\n    ".join(items) + "};")
        out.append("")
    out.append(f"seqs = seq{next(iter(tables))};")
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(out) + "\n")


def _uav10_frames(root: Path, folder: str, numbers: list[int]) -> None:
    d = root / "data_seq" / "UAV123_10fps" / folder
    _write_frames(d, [f - 1 for f in numbers], name=lambda k: f"{k + 1:06d}.jpg")


def test_uav123_10fps_release_configseqs_ranges_and_nan_lines(tmp_path: Path) -> None:
    outer = tmp_path / "Dataset_UAV123_10fps"
    root = outer / "UAV123_10fps"
    _uav10_frames(root, "bike1", list(range(1, 8)))  # 7 images, the sequence is frames 1-5
    _write_lines(
        root / "anno" / "UAV123_10fps" / "bike1.txt",
        [_box(0), "NaN,NaN,NaN,NaN", _box(2), _box(3), "NaN,NaN,NaN,NaN"],
    )
    _uav10_frames(root, "bird1", list(range(1, 13)))
    _write_lines(root / "anno" / "UAV123_10fps" / "bird1_2.txt", [_box(k) for k in range(5, 9)])  # frames 6-9
    _uav10_frames(root, "uav2", [1, 2, 3])  # not in configSeqs.m: the whole folder
    _write_lines(root / "anno" / "UAV123_10fps" / "uav2.txt", [_box(k) for k in range(3)])
    _config_seqs(
        root / "configSeqs.m",
        {
            "UAV123_10fps": [("bike1", "bike1", 1, 5), ("bird1_2", "bird1", 6, 9)],
            # another subset's table in the same file must not be used for this one
            "UAV123": [("bike1", "bike1", 1, 7), ("bird1_2", "bird1", 2, 5)],
        },
    )

    # The 10 fps release used to be refused ("is not a UAV123 dataset"); now detected.
    assert detect_layout(outer) == "uav123_10fps"
    assert detect_layout(root) == "uav123_10fps"
    assert list_layout(root) == ["bike1", "bird1_2", "uav2"]
    bike, bird, whole = load_layout(outer, "uav123_10fps")
    assert [s.name for s in load_layout(root)] == ["bike1", "bird1_2", "uav2"]

    _assert_aligned(bike, 5)  # frames 6 and 7 of the folder are not part of the sequence
    assert [p.name for p in bike.paths] == [f"{k:06d}.jpg" for k in range(1, 6)]
    assert bike.meta["absent"].tolist() == [False, True, False, False, True]
    assert np.isnan(bike.groundtruth[[1, 4]]).all()
    assert bike.valid.tolist() == [True, False, True, True, False]
    assert bike.meta["absent_policy"] == "exclude"
    assert bike.meta["layout"] == "uav123_10fps" and bike.meta["subset"] == "UAV123_10fps"
    assert bike.meta["frame_range"] == (1, 5)
    assert bike.meta["frame_range_source"] == str(root / "configSeqs.m")

    assert bird.meta["folder"] == "bird1" and bird.meta["frame_range"] == (6, 9)
    assert [_frame_id(f) for f in bird] == [5, 6, 7, 8]
    assert bird.groundtruth.tolist() == [_box(k) for k in range(5, 9)]
    assert bird.init_box == tuple(_box(5))

    _assert_aligned(whole, 3)
    assert whole.meta["frame_range"] == (1, 3) and whole.meta["frame_range_source"] == "the image folder"

    # Named as another layout: refused, and the message says what it looks like.
    with pytest.raises(LayoutError, match=r"is not a UAV123 dataset: .*it looks like a UAV123_10fps dataset"):
        load_layout(root, "uav123")


def test_uav123_10fps_without_configseqs_uses_the_published_table(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setitem(uav.UAV123_10FPS_SPLITS, "car1_2", ("car1", 4, 7))
    _uav10_frames(tmp_path, "car1", list(range(1, 10)))
    _write_lines(tmp_path / "anno" / "UAV123_10fps" / "car1_2.txt", [_box(k) for k in range(3, 7)])
    (seq,) = load_layout(tmp_path)
    assert seq.meta["layout"] == "uav123_10fps" and seq.meta["frame_range"] == (4, 7)
    assert seq.meta["frame_range_source"] == "wmiltrack's copy of the published table"
    assert [_frame_id(f) for f in seq] == [3, 4, 5, 6]

    # a configSeqs.m, when present, wins over the table
    _config_seqs(tmp_path / "configSeqs.m", {"UAV123_10fps": [("car1_2", "car1", 2, 5)]}, style="concat")
    (seq,) = load_layout(tmp_path)
    assert seq.meta["frame_range"] == (2, 5) and [_frame_id(f) for f in seq] == [1, 2, 3, 4]


def test_uav123_10fps_split_table_matches_published_ranges() -> None:
    # the seqUAV123_10fps cell array of the UAV123_10fps release's configSeqs.m
    table = uav.UAV123_10FPS_SPLITS
    assert len(table) == 51
    assert set(table) == set(uav.UAV123_SPLITS)  # the same sequences are split at 30 and 10 fps
    assert table["bird1_2"] == ("bird1", 259, 493)
    assert table["car6_5"] == ("car6", 1309, 1621)
    assert table["uav1_3"] == ("uav1", 825, 1157)
    assert table["group3_4"] == ("group3", 1457, 1843)
    for name, (folder, start, end) in table.items():
        assert name.rsplit("_", 1)[0] == folder and 1 <= start < end


def test_uav_configseqs_mismatch_and_missing_frames_are_refused(tmp_path: Path) -> None:
    _uav10_frames(tmp_path, "boat1", list(range(1, 6)))
    _write_lines(tmp_path / "anno" / "UAV123_10fps" / "boat1.txt", [_box(k) for k in range(4)])
    _config_seqs(tmp_path / "configSeqs.m", {"UAV123_10fps": [("boat1", "boat1", 1, 5)]})
    with pytest.raises(LayoutError, match=r"has 4 boxes but the sequence is frames 1-5 of boat1 \(5 frames, from .*configSeqs.m\)"):
        load_layout(tmp_path)
    _config_seqs(tmp_path / "configSeqs.m", {"UAV123_10fps": [("boat1", "boat1", 3, 6)]})
    with pytest.raises(LayoutError, match=r"frames 3-6 of .* are needed but 1 are missing \(first: 000006\)"):
        load_layout(tmp_path)


def test_parse_config_seqs_reads_the_releases_struct_forms(tmp_path: Path) -> None:
    from wmiltrack.data.layouts import parse_config_seqs

    cfg = tmp_path / "configSeqs.m"
    cfg.write_text(
        "function seqs=configSeqs(dataSet)\n"
        "% struct('name','commented','startFrame',1,'endFrame',2)\n"
        "seqUAV123_10fps = {struct('name','bike1','path','D:\\data_seq\\UAV123_10fps\\bike1\\',"
        "'startFrame',1,'endFrame',1029,'nz',6,'ext','jpg','init_rect',[0,0,0,0]),... % bike\n"
        "    struct('name','bird1_2','path',[dataSet '\\bird1\\'],'startFrame',259,...\n"
        "           'endFrame',493,'nz',6,'ext','jpg','init_rect', [0,0,0,0])\n"
        "    struct('name','uav1_3','path',fullfile(dataSet, 'uav1/'),'startFrame',825,'endFrame',1157)\n"
        "    struct('name','car1_s','startFrame',1,'endFrame',492)};\n"
        "seqUAV20L={struct('name','bird1','path','bird1\\','startFrame',1,'endFrame',2437)};\n"
        "seqs = seqUAV123_10fps;\n"
    )
    assert parse_config_seqs(cfg) == {
        "UAV123_10fps": {
            "bike1": ("bike1", 1, 1029),
            "bird1_2": ("bird1", 259, 493),
            "uav1_3": ("uav1", 825, 1157),
            "car1_s": ("car1_s", 1, 492),  # no path: the folder is the name
        },
        "UAV20L": {"bird1": ("bird1", 1, 2437)},
    }
    cfg.write_text("seqUAV123={struct('name','a','startFrame',9,'endFrame',3)};\n")
    with pytest.raises(LayoutError, match=r"struct 'a' of seqUAV123 has startFrame 9 and endFrame 3"):
        parse_config_seqs(cfg)
    cfg.write_text("seqUAV123={struct('name','a','startFrame',1)};\n")
    with pytest.raises(LayoutError, match=r"struct 'a' of seqUAV123 needs integer 'startFrame' and 'endFrame'"):
        parse_config_seqs(cfg)
    cfg.write_text("seqUAV123={struct('name','a','startFrame',1,'endFrame',3),\n")
    with pytest.raises(LayoutError, match=r"the cell array seqUAV123 is not closed"):
        parse_config_seqs(cfg)


def test_uav20l_in_the_uav123_release(tmp_path: Path) -> None:
    root = tmp_path / "Dataset_UAV123" / "UAV123"
    _uav_frames(root, "bird1", list(range(1, 11)))
    _write_lines(root / "anno" / "UAV123" / "bird1_2.txt", [_box(k) for k in range(4, 8)])
    _write_lines(
        root / "anno" / "UAV20L" / "bird1.txt",
        [_box(k) if k not in (3, 4) else "NaN,NaN,NaN,NaN" for k in range(10)],
    )
    _config_seqs(
        root / "configSeqs.m",
        {"UAV123": [("bird1_2", "bird1", 5, 8)], "UAV20L": [("bird1", "bird1", 1, 10)]},
        style="fullfile",
    )
    assert detect_layout(root.parent) == "uav123"  # both subsets: UAV123 unless named
    (b2,) = load_layout(root.parent)
    assert b2.meta["frame_range"] == (5, 8) and [_frame_id(f) for f in b2] == [4, 5, 6, 7]
    assert list_layout(root.parent, "uav20l") == ["bird1"]
    (long,) = load_layout(root.parent, "uav20l")
    _assert_aligned(long, 10)
    assert long.meta["layout"] == "uav20l" and long.meta["subset"] == "UAV20L"
    assert long.meta["absent"].tolist() == [k in (3, 4) for k in range(10)]
    assert long.meta["frame_range"] == (1, 10)


# ---------------------------------------------------------------------- TrackingNet
def _tn_seq(chunk: Path, name: str, n: int, rows=None) -> None:
    _write_frames(chunk / "frames" / name, list(range(n)), name=lambda k: f"{k}.jpg")
    _write_lines(chunk / "anno" / f"{name}.txt", rows if rows is not None else [_box(k) for k in range(n)])


def test_trackingnet_chunks_numeric_frame_order_and_test_split(tmp_path: Path) -> None:
    _tn_seq(tmp_path / "TRAIN_0", "a_vid_0", 12)  # 0..11: "10.jpg" sorts before "2.jpg" as text
    _tn_seq(tmp_path / "TRAIN_1", "b_vid_3", 4)
    _tn_seq(tmp_path / "TEST", "c_vid_1", 5, rows=[_box(0)])

    assert detect_layout(tmp_path) == "trackingnet"
    assert list_layout(tmp_path) == ["a_vid_0", "b_vid_3"]  # the TRAIN chunks, not TEST
    a, b = load_layout(tmp_path)
    _assert_aligned(a, 12)
    _assert_aligned(b, 4)
    assert a.meta["chunk"] == "TRAIN_0" and not a.meta["first_frame_only"]

    assert list_layout(tmp_path / "TRAIN_1") == ["b_vid_3"]
    (t,) = load_layout(tmp_path / "TEST", "trackingnet")
    assert t.meta["first_frame_only"] is True and t.init_box == tuple(_box(0))
    assert np.isnan(t.groundtruth[1:]).all()
    _assert_aligned(t, 5)


def test_trackingnet_refuses_mismatch_and_duplicates(tmp_path: Path) -> None:
    _tn_seq(tmp_path / "TRAIN_0", "v", 4, rows=[_box(k) for k in range(3)])
    with pytest.raises(LayoutError, match=r"TrackingNet sequence TRAIN_0/v: 4 images .* but 3 boxes"):
        load_layout(tmp_path)
    _tn_seq(tmp_path / "TRAIN_1", "v", 3)
    with pytest.raises(LayoutError, match=r"sequence v is in both TRAIN_0 and TRAIN_1"):
        list_layout(tmp_path)


# ---------------------------------------------------------------------- VOT
def _poly(k: int) -> str:
    # a rotated square-ish quadrilateral whose min/max box is _box(k) = (k+1, 2, 6, 5)
    x0, y0, x1, y1 = k + 1.0, 2.0, k + 7.0, 7.0
    return f"{x0:g},{(y0 + y1) / 2:g},{(x0 + x1) / 2:g},{y0:g},{x1:g},{(y0 + y1) / 2:g},{(x0 + x1) / 2:g},{y1:g}"


def test_vot_polygons_rectangles_masks_and_absent_lines(tmp_path: Path) -> None:
    # VOT2017+ style: color/ sub-folder, polygon regions, one empty "0,0,0,0" rectangle
    a = tmp_path / "ants"
    _write_frames(a / "color", list(range(5)))
    _write_lines(a / "groundtruth.txt", [_poly(0), _poly(1), "0,0,0,0", _poly(3), _poly(4)])
    # old style: images in the sequence folder, rectangles and a nan line
    b = tmp_path / "ball"
    _write_frames(b, list(range(4)))
    _write_lines(b / "groundtruth.txt", [_box(0), "nan,nan,nan,nan", _box(2), _box(3)])
    # masks (VOT2020+): "m x0,y0,w,h,RLE"; and a special code line
    c = tmp_path / "car"
    _write_frames(c / "color", list(range(3)))
    # 8x6 region at (k+1-1, 1): zeros then a 6x5 block of ones starting at column 1, row 1
    rle = []
    mask = np.zeros((6, 8), bool)
    mask[1:6, 1:7] = True
    flat = mask.ravel()
    run_val, run = False, 0
    for v in flat:
        if v == run_val:
            run += 1
        else:
            rle.append(run)
            run_val, run = v, 1
    rle.append(run)
    mask_line = lambda k: f"m{k},1," + "8,6," + ",".join(map(str, rle))  # noqa: E731
    _write_lines(c / "groundtruth.txt", [mask_line(0), "0", mask_line(2)])
    (tmp_path / "list.txt").write_text("ants\nball\ncar\n")

    assert detect_layout(tmp_path) == "vot"
    ants, ball, car = load_layout(tmp_path)
    _assert_aligned(ants, 5)
    assert ants.meta["absent"].tolist() == [False, False, True, False, False]
    assert ants.meta["region_kinds"] == ("polygon", "rectangle")
    _assert_aligned(ball, 4)
    assert ball.meta["absent"].tolist() == [False, True, False, False]
    _assert_aligned(car, 3)
    assert car.meta["absent"].tolist() == [False, True, False]
    assert car.meta["region_kinds"] == ("mask",)

    # the VOT toolkit's workspace keeps the sequences under sequences/
    ws = tmp_path / "workspace"
    (ws / "sequences").mkdir(parents=True)
    _write_frames(ws / "sequences" / "ants" / "color", list(range(2)))
    _write_lines(ws / "sequences" / "ants" / "groundtruth.txt", [_poly(0), _poly(1)])
    (ws / "sequences" / "list.txt").write_text("ants\n")
    assert list_layout(ws) == ["ants"]
    assert detect_layout(ws / "sequences" / "ants") == "vot"


def test_vot_refuses_bad_lines_and_mismatch(tmp_path: Path) -> None:
    s = tmp_path / "seq"
    _write_frames(s / "color", list(range(3)))
    _write_lines(s / "groundtruth.txt", [_box(0), "1,2,3", _box(2)])
    with pytest.raises(LayoutError, match=r"groundtruth.txt:2: not a VOT region \(3 values\)"):
        load_layout(tmp_path, "vot")
    _write_lines(s / "groundtruth.txt", [_box(0), _box(1)])
    with pytest.raises(LayoutError, match=r"VOT sequence seq: 3 images .* but 2 boxes"):
        load_layout(tmp_path, "vot")
    (tmp_path / "list.txt").write_text("seq\nmissing\n")
    with pytest.raises(LayoutError, match=r"list.txt names 1 sequence\(s\) with no folder \(missing\)"):
        list_layout(tmp_path)


def test_parse_vot_region_and_polygon_to_box() -> None:
    assert parse_vot_region("1,2,3,4") == ((1.0, 2.0, 3.0, 4.0), "rectangle")
    box, kind = parse_vot_region("0")
    assert kind == "special" and all(math.isnan(v) for v in box)
    box, kind = parse_vot_region("1.5,2,4.5,1,6,3,3,4")
    assert kind == "polygon" and box == (1.5, 1.0, 4.5, 3.0)
    box, kind = parse_vot_region("m0,0,2,2,4")  # empty mask
    assert kind == "mask" and all(math.isnan(v) for v in box)
    # 3x2 region at (3, 4); runs 1 zero, 2 ones, 1 zero, 1 one, (1 zero): rows "011" and "010",
    # so the pixels are columns 1-2 of row 0 and column 1 of row 1 -> box (3+1, 4+0, 2, 2)
    assert parse_vot_region("m3,4,3,2,1,2,1,1")[0] == (4.0, 4.0, 2.0, 2.0)
    with pytest.raises(ValueError, match="run lengths cover 7 pixels of a 3x2 region"):
        parse_vot_region("m3,4,3,2,1,2,1,3")
    with pytest.raises(ValueError, match="even number"):
        polygon_to_box([1, 2, 3, 4, 5])
    # area mode, hand-computed: an axis-aligned 4x2 rectangle keeps its size, plus 1 (toolkit)
    assert polygon_to_box([0, 0, 4, 0, 4, 2, 0, 2], mode="area") == (-0.5, -0.5, 5.0, 3.0)


@pytest.mark.extras("got10k", "six")
def test_polygon_area_mode_matches_got10k_toolkit() -> None:
    import got10k.datasets.vot as vot_mod
    rng = np.random.default_rng(3)
    corners = []
    for _ in range(20):
        cx, cy, w, h, a = rng.uniform(20, 80), rng.uniform(20, 80), rng.uniform(5, 30), rng.uniform(5, 30), rng.uniform(0, np.pi)
        pts = np.array([[-w, -h], [w, -h], [w, h], [-w, h]]) / 2
        rot = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
        corners.append((pts @ rot.T + [cx, cy]).ravel())
    corners_arr = np.array(corners)
    expected = vot_mod.VOT._corner2rect(None, corners_arr)
    ours = np.array([polygon_to_box(c, mode="area") for c in corners_arr])
    np.testing.assert_allclose(ours, expected, rtol=0, atol=1e-9)


# ---------------------------------------------------------------------- DTB70
def _dtb_seq(root: Path, name: str, n: int, digits: int = 5, rows=None) -> Path:
    d = root / name
    _write_frames(d / "img", list(range(n)), name=lambda k: f"{k + 1:0{digits}d}.jpg")
    _write_lines(d / "groundtruth_rect.txt", rows if rows is not None else [_box(k) for k in range(n)])
    return d


def test_dtb70_layout_detection_and_loading(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    root = tmp_path / "DTB70"
    _dtb_seq(root, "Gull2", 4)
    _dtb_seq(root, "Animal1", 12)  # 00010.jpg after 00009.jpg
    _dtb_seq(root, "RcCar3", 3, rows=[_box(0), "NaN,NaN,NaN,NaN", _box(2)])
    assert detect_layout(root) == "dtb70"
    assert detect_layout(root / "Gull2") == "dtb70"  # one sequence folder, its parent named DTB70
    assert list_layout(root) == ["Animal1", "Gull2", "RcCar3"]

    def boom(*args: object, **kwargs: object) -> None:
        raise AssertionError("an image was read while loading")

    monkeypatch.setattr(cv2, "imread", boom)  # unlike the OTB loader, no image is decoded
    animal, gull, car = load_layout(root)
    monkeypatch.undo()
    _assert_aligned(animal, 12)
    _assert_aligned(gull, 4)
    assert animal.meta["layout"] == "dtb70" and animal.meta["absent_policy"] == "exclude"
    assert car.meta["absent"].tolist() == [False, True, False]

    # Folder named otherwise: DTB70 when most sequences bear DTB70's names.
    other = tmp_path / "drones"
    _dtb_seq(other, "Animal2", 3)
    _dtb_seq(other, "Zebra", 3)
    _dtb_seq(other, "my_clip", 3)
    assert detect_layout(other) == "dtb70"


def test_dtb70_is_told_from_otb(tmp_path: Path) -> None:
    # OTB names its frames with four digits, also for sequences both benchmarks have.
    otb = tmp_path / "otb"
    _dtb_seq(otb, "Basketball", 3, digits=4)
    _dtb_seq(otb, "Walking", 3, digits=4)
    assert detect_layout(otb) == "otb"
    # OTB's Board has five-digit frames but is no DTB70 name, in no DTB70 folder
    board = tmp_path / "benchmarks" / "Board"
    _dtb_seq(board.parent, "Board", 3)
    assert detect_layout(board) == "otb"
    # named, any OTB-structured folder loads as DTB70
    (seq,) = load_layout(board, "dtb70")
    assert seq.meta["layout"] == "dtb70"
    _assert_aligned(seq, 3)


def test_dtb70_refuses_count_mismatch(tmp_path: Path) -> None:
    _dtb_seq(tmp_path / "DTB70", "Kiting", 5, rows=[_box(k) for k in range(4)])
    with pytest.raises(LayoutError, match=r"DTB70 sequence Kiting: 5 images in .* but 4 boxes"):
        load_layout(tmp_path / "DTB70")


# ---------------------------------------------------------------------- OTB and detection errors
def test_otb_layout_through_sequences_module(tmp_path: Path) -> None:
    d = tmp_path / "Dog"
    _write_frames(d / "img", list(range(4)), name=lambda k: f"{k + 1:04d}.jpg")
    _write_lines(d / "groundtruth_rect.txt", [_box(k) for k in range(4)])
    assert detect_layout(tmp_path) == "otb"
    assert detect_layout(d) == "otb"
    (seq,) = load_layout(tmp_path)
    _assert_aligned(seq, 4)
    assert seq.meta["layout"] == "otb" and seq.meta["absent"].tolist() == [False] * 4


def test_detection_errors_name_the_layout_and_what_it_expects(tmp_path: Path) -> None:
    (tmp_path / "empty").mkdir()
    with pytest.raises(LayoutError) as exc:
        detect_layout(tmp_path / "empty")
    msg = str(exc.value)
    assert "is not a tracking dataset in any known layout" in msg
    for title in ("LaSOT", "GOT-10k", "UAV123", "UAV123_10fps", "UAV20L", "TrackingNet", "VOT", "DTB70", "OTB"):
        assert title in msg

    _lasot_seq(tmp_path / "ls", "cat", 1)
    with pytest.raises(LayoutError, match=r"is not a GOT-10k dataset: expected train/, val/ or test/"):
        load_layout(tmp_path / "ls", layout="got10k")
    with pytest.raises(LayoutError, match=r"is not a UAV123 dataset: expected data_seq/UAV123"):
        load_layout(tmp_path / "ls", layout="uav123")
    with pytest.raises(ValueError, match=r"unknown layout 'imagenet'"):
        load_layout(tmp_path / "ls", layout="imagenet")
    with pytest.raises(LayoutError, match=r"sequence\(s\) not in the LaSOT dataset .*: cat-9; available: cat-1"):
        load_layout(tmp_path / "ls", sequences=["cat-9"])
    with pytest.raises(FileNotFoundError, match="dataset folder not found"):
        detect_layout(tmp_path / "nowhere")


# ---------------------------------------------------------------------- scoring loaded sequences
def test_benchmark_scores_follow_each_benchmarks_absent_policy(tmp_path: Path) -> None:
    from wmiltrack.eval.benchmark_scores import benchmark_scores

    _lasot_seq(tmp_path / "lasot", "cat", 1, occ=[0, 0, 1, 0, 0], oov=[0, 0, 0, 0, 1])
    (ls,) = load_layout(tmp_path / "lasot")
    pred = np.array([_box(k) for k in range(5)])  # exact on every frame
    s = benchmark_scores(pred, ls)
    assert s.layout == "lasot" and s.got10k is None and s.ope is not None
    # LaSOT toolkit: 3 visible frames succeed, divided by all 5 frames
    assert (s.ope.n_frames, s.ope.n_scored) == (5, 3)
    assert s.ope.success_50 == pytest.approx(3 / 5)
    assert s.ope.auc == pytest.approx(20 / 21 * 3 / 5)
    assert s.ope.precision_20 == pytest.approx(3 / 5)
    assert "failures" in s.note

    _got_seq(tmp_path / "got", "GOT-10k_Val_000001", n=6, absence=[0, 0, 1, 0, 0, 0], cover=[8, 8, 0, 8, 8, 8])
    (gs,) = load_layout(tmp_path / "got")
    g = benchmark_scores(np.array([_box(k) for k in range(6)]), gs)
    assert g.got10k is not None and g.ope is not None
    assert g.got10k.n_scored == 4 and g.got10k.ao == pytest.approx(1.0)  # frame 0 and frame 2 left out
    assert g.ope.n_scored == 5 and g.ope.success_50 == pytest.approx(1.0)  # left out, not failed
    assert g.to_dict()["got10k"]["sr75"] == pytest.approx(1.0)

    _tn_seq(tmp_path / "tn" / "TEST", "v", 3, rows=[_box(0)])
    (ts,) = load_layout(tmp_path / "tn")
    t = benchmark_scores(np.array([_box(k) for k in range(3)]), ts)
    assert t.ope is None and t.got10k is None and "server" in t.note


def test_count_absent_as_failures_reproduces_lasot_formula() -> None:
    """LaSOT toolkit (eval_tracker.m): sum over visible frames of [iou > t], divided by all frames."""
    from wmiltrack.eval.benchmark_scores import count_absent_as_failures
    from wmiltrack.eval.metrics import SUCCESS_THRESHOLDS, iou, ope_metrics

    rng = np.random.default_rng(11)
    n = 60
    gt = np.column_stack([rng.uniform(0, 100, n), rng.uniform(0, 100, n), rng.uniform(10, 40, n), rng.uniform(10, 40, n)])
    pred = gt + rng.normal(0, 6, (n, 4))
    absent = rng.random(n) < 0.25
    absent[0] = False
    gt_nan = gt.copy()
    gt_nan[absent] = np.nan
    r = count_absent_as_failures(ope_metrics(pred, gt_nan))
    ov = iou(pred[~absent], gt[~absent])
    expected = np.array([(ov > t).sum() / n for t in SUCCESS_THRESHOLDS])
    np.testing.assert_allclose(r.success_curve, expected, atol=1e-12)
    assert r.auc == pytest.approx(expected.mean())
    assert r.n_missing == absent.sum()


def test_iter_layout_loads_one_sequence_at_a_time(tmp_path: Path) -> None:
    from wmiltrack.data.layouts import iter_layout

    _lasot_seq(tmp_path, "cat", 1)
    d = _lasot_seq(tmp_path, "cat", 2)
    (d / "groundtruth.txt").write_text("1,2,3\n")  # broken, but only when reached
    it = iter_layout(tmp_path)
    first = next(it)
    assert first.name == "cat-1" and len(first) == 5
    with pytest.raises(LayoutError, match=r"groundtruth.txt:1: expected 4 values"):
        next(it)
    with pytest.raises(LayoutError, match="not in the LaSOT dataset"):
        iter_layout(tmp_path, sequences=["cat-3"]).__next__()


# ---------------------------------------------------------------------- end to end, every layout
def _build_from(seq: Sequence, root: Path, layout: str) -> Path:
    """Write a generated sequence's frames and boxes in a benchmark's layout under root."""
    assert seq.groundtruth is not None
    gt = seq.groundtruth
    rows = [[float(v) for v in r] for r in gt]
    n = len(gt)
    if layout == "lasot":
        d = root / "toy" / "toy-1"
        img_dir, names = d / "img", [f"{k + 1:08d}.jpg" for k in range(n)]
        _write_lines(d / "groundtruth.txt", rows)
        (d / "full_occlusion.txt").write_text(",".join("0" * n) + "\n")
        (d / "out_of_view.txt").write_text(",".join("0" * n) + "\n")
    elif layout == "got10k":
        d = root / "val" / "GOT-10k_Val_000001"
        img_dir, names = d, [f"{k + 1:08d}.jpg" for k in range(n)]
        _write_lines(d / "groundtruth.txt", rows)
        _write_lines(d / "absence.label", ["0"] * n)
        _write_lines(d / "cover.label", ["8"] * n)
        h, w = seq.frame(0).shape[:2]
        (d / "meta_info.ini").write_text(f"[METAINFO]\nresolution: ({w}, {h})\n")
        (root / "val" / "list.txt").write_text("GOT-10k_Val_000001\n")
    elif layout == "uav123":
        img_dir, names = root / "data_seq" / "UAV123" / "toy", [f"{k + 1:06d}.jpg" for k in range(n)]
        _write_lines(root / "anno" / "UAV123" / "toy.txt", rows)
    elif layout == "uav123_10fps":  # the folder holds 2 frames before and 1 after the sequence
        img_dir = root / "data_seq" / "UAV123_10fps" / "toy"
        names = [f"{k + 3:06d}.jpg" for k in range(n)]
        _write_frames(img_dir, [0, 1, n + 2], name=lambda k: f"{k + 1:06d}.jpg")
        _write_lines(root / "anno" / "UAV123_10fps" / "toy.txt", rows)
        _config_seqs(root / "configSeqs.m", {"UAV123_10fps": [("toy", "toy", 3, n + 2)]})
    elif layout == "uav20l":
        img_dir, names = root / "data_seq" / "UAV123" / "toy", [f"{k + 1:06d}.jpg" for k in range(n)]
        _write_lines(root / "anno" / "UAV20L" / "toy.txt", rows)
    elif layout == "dtb70":
        img_dir, names = root / "Animal1" / "img", [f"{k + 1:05d}.jpg" for k in range(n)]
        _write_lines(root / "Animal1" / "groundtruth_rect.txt", rows)
    elif layout == "trackingnet":
        img_dir, names = root / "TRAIN_0" / "frames" / "toy", [f"{k}.jpg" for k in range(n)]
        _write_lines(root / "TRAIN_0" / "anno" / "toy.txt", rows)
    else:  # vot: 8-value polygons, the corners of each box
        img_dir, names = root / "toy" / "color", [f"{k + 1:08d}.jpg" for k in range(n)]
        polys = [[x, y, x + w, y, x + w, y + h, x, y + h] for x, y, w, h in rows]
        _write_lines(root / "toy" / "groundtruth.txt", polys)
        (root / "list.txt").write_text("toy\n")
    img_dir.mkdir(parents=True, exist_ok=True)
    for name, frame in zip(names, seq):
        assert cv2.imwrite(str(img_dir / name), frame)
    return img_dir


_ALL = ["lasot", "got10k", "uav123", "uav123_10fps", "uav20l", "trackingnet", "vot", "dtb70"]


@pytest.mark.parametrize("layout", _ALL)
def test_every_layout_runs_through_tracker_and_scoring(tmp_path: Path, layout: str) -> None:
    import pickle

    from wmiltrack.data.sequences import open_input
    from wmiltrack.data.synthetic import make_sequence
    from wmiltrack.engine.tracker import Tracker
    from wmiltrack.eval.benchmark_scores import benchmark_scores
    from wmiltrack.eval.metrics import ope_metrics

    syn = make_sequence(10, size=(96, 128), target_size=(24, 20), seed=3, occlusion=False, clutter=False)
    img_dir = _build_from(syn, tmp_path, layout)
    assert detect_layout(tmp_path) == layout
    (seq,) = load_layout(tmp_path)
    assert syn.groundtruth is not None and seq.groundtruth is not None
    np.testing.assert_allclose(seq.groundtruth, syn.groundtruth, atol=1e-3)  # written with 6 digits
    # each decoded (JPEG) frame is closest to the generated frame of the same index
    originals = [f.astype(np.float64) for f in syn]
    for k, frame in enumerate(seq):
        diffs = [np.abs(frame - o).mean() for o in originals]
        assert int(np.argmin(diffs)) == k
    seq = pickle.loads(pickle.dumps(seq))  # sequences travel to worker processes as they are
    pred = Tracker("rcwmil", seed=0).track(seq, seq.init_box)
    # the same files opened as a plain image folder give the same trajectory (deterministic tracker)
    if layout == "uav123_10fps":  # the folder's frames outside configSeqs.m's range are not used
        assert [p.name for p in seq.paths] == [f"{k + 3:06d}.jpg" for k in range(10)]
        ref = Tracker("rcwmil", seed=0).track(list(seq), seq.init_box)
    else:
        ref = Tracker("rcwmil", seed=0).track(open_input(img_dir), seq.init_box)
    np.testing.assert_array_equal(pred, ref)
    s = benchmark_scores(pred, seq)
    assert s.ope is not None and s.ope.n_scored == 10
    assert s.ope.auc == pytest.approx(ope_metrics(pred, syn.groundtruth).auc, abs=0.01)
    assert (s.got10k is not None) == (layout == "got10k")


@pytest.mark.parametrize("layout", ["uav123_10fps", "uav20l", "dtb70"])
def test_wmiltrack_eval_runs_on_the_new_layouts(tmp_path: Path, layout: str) -> None:
    """`wmiltrack eval` on each new layout, detected and named: the boxes are the tracker's own on
    the loader's frames (for UAV123_10fps the configSeqs.m range, not the whole folder)."""
    import json

    from wmiltrack.cli import main
    from wmiltrack.data.boxes import read_boxes
    from wmiltrack.data.synthetic import make_sequence
    from wmiltrack.engine.tracker import Tracker

    syn = make_sequence(10, size=(96, 128), target_size=(24, 20), seed=5, occlusion=False, clutter=False)
    data = tmp_path / "data"
    _build_from(syn, data, layout)
    (seq,) = load_layout(data, layout)
    expected = Tracker("rcwmil", seed=0).track(seq, seq.init_box)
    for named in (False, True):
        out = tmp_path / f"out{int(named)}"
        argv = ["eval", str(data), "--trackers", "rcwmil", "--out", str(out), "--no-plots", "--no-progress"]
        assert main(argv + (["--layout", layout] if named else [])) == 0
        doc = json.loads((out / "eval_ope.json").read_text())
        assert doc["layout"] == layout and doc["sequences"] == [seq.name]
        got = read_boxes(out / "boxes" / "rcwmil" / f"{seq.name}.txt")
        assert got.shape == (10, 4)
        np.testing.assert_array_equal(got[1:], expected[1:])
        np.testing.assert_array_equal(got[0], seq.groundtruth[0])


# ---------------------------------------------------------------------- a layout from outside
def _index_toy(root: Path):
    """A made-up benchmark: a TOY marker file, then <seq>/frames/*.jpg and <seq>/boxes.csv."""
    from wmiltrack.data.layouts import Entry
    from wmiltrack.data.layouts.files import absent_rows, images_in, make_sequence, read_box_file, subdirs

    if not (root / "TOY").is_file():
        return None

    def load(d: Path) -> Sequence:
        gt = read_box_file(d / "boxes.csv")
        meta = {"layout": "toy", "absent_policy": "exclude"}
        return make_sequence(d.name, images_in(d / "frames"), gt, absent_rows(gt), meta)

    dirs = [d for d in subdirs(root) if (d / "boxes.csv").is_file()]
    return [Entry(d.name, lambda d=d: load(d)) for d in dirs] or None


def test_a_layout_registered_from_a_test_module_is_detected_and_loaded(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Adding a benchmark needs no edit of wmiltrack: a Layout and one register_layout call."""
    from wmiltrack.data.layouts import Layout, register_layout, registry

    root = tmp_path / "toybench"
    (root / "b").mkdir(parents=True)
    (root / "TOY").write_text("")
    for name, n in (("a", 3), ("b", 4)):
        _write_frames(root / name / "frames", list(range(n)))
        _write_lines(root / name / "boxes.csv", [_box(k) for k in range(n)])
    with pytest.raises(LayoutError, match="any known layout"):
        detect_layout(root)

    with monkeypatch.context() as mp:
        mp.setattr(registry, "LAYOUT_REGISTRY", dict(registry.LAYOUT_REGISTRY))  # undone on exit
        toy = Layout(name="toy", title="Toy", expected="TOY and <seq>/frames/", index=_index_toy,
                     aliases=("toy-bench",))
        assert register_layout(toy) is toy
        assert detect_layout(root) == "toy"
        assert list_layout(root) == ["a", "b"]
        seqs = load_layout(root, layout="Toy-Bench", sequences=["b", "a"])
        assert [s.name for s in seqs] == ["b", "a"]
        _assert_aligned(seqs[0], 4)
        _assert_aligned(seqs[1], 3)
        assert seqs[0].meta["layout"] == "toy" and seqs[0].meta["absent"].tolist() == [False] * 4
        # The other layouts name it in their errors, and a second "toy" is refused.
        with pytest.raises(LayoutError, match=r"it looks like a Toy dataset \(layout 'toy'\)"):
            load_layout(root, layout="lasot")
        with pytest.raises(ValueError, match="already registered: toy"):
            register_layout(Layout(name="other", title="O", expected="-", index=_index_toy, aliases=("toy",)))
        # Nothing is registered by a failed call.
        assert "other" not in registry.LAYOUT_REGISTRY
    with pytest.raises(ValueError, match="unknown layout 'toy'"):
        load_layout(root, layout="toy")
