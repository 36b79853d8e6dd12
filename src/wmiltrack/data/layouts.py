"""Loaders for the big tracking benchmarks' folder layouts: LaSOT, GOT-10k, UAV123, UAV123_10fps,
UAV20L, TrackingNet, VOT, DTB70 (and OTB, through :mod:`wmiltrack.data.sequences`).

Every loader returns :class:`wmiltrack.data.sequences.Sequence` objects backed by image paths:
**no image is opened while listing or loading a dataset** (frames are decoded when iterated), only
folders are listed and annotation text files read (the OTB layout is the exception: its
loader in :mod:`wmiltrack.data.sequences` decodes each sequence's first image to fail early).
Ground truth is ``(n, 4)`` ``x, y, w, h`` as written in the files, with ``nan`` rows on frames
where the benchmark says the target is absent.

Entry points: :func:`detect_layout`, :func:`list_layout` (names only, reads no annotation),
:func:`load_layout` and :func:`iter_layout` (one sequence loaded at a time, for big datasets).
Each sequence's ``meta`` holds:

``"layout"``
    The layout name (one of :data:`LAYOUTS`).
``"absent"``
    ``(n,)`` bool: frames the benchmark marks as target-absent (their ground-truth rows are ``nan``).
``"absent_policy"``
    How the benchmark's own toolkit scores those frames: ``"exclude"`` (left out of every figure,
    what :func:`wmiltrack.eval.metrics.ope_metrics` does with ``nan`` rows) or ``"fail"`` (kept in
    the frame count and never a success; multiply OPE curves by ``n_scored / n_frames`` to get it).
``"first_frame_only"``
    ``True`` when only the first frame is annotated (GOT-10k ``test``, TrackingNet ``TEST``): the
    other rows are ``nan`` and there is nothing to score locally (those benchmarks score on a server).

Conventions, and the public sources each was checked against (real datasets are not available
where this module was written; the layouts were rebuilt from these sources and tested on
generated data):

**LaSOT** ``<root>/<class>/<class>-<N>/img/00000001.jpg``, ``groundtruth.txt`` (``x,y,w,h`` per
line), ``full_occlusion.txt`` and ``out_of_view.txt`` (one comma-separated 0/1 line).  A frame is
absent when either flag is 1 (pytracking ``pytracking/evaluation/lasotdataset.py``:
``target_visible = full_occlusion == 0 and out_of_view == 0``).  The official MATLAB toolkit
(``HengLan/LaSOT_Evaluation_Toolkit``, ``utils/calc_seq_err_robust.m`` and ``utils/eval_tracker.m``)
removes absent frames from the scored frames but still divides by the full frame count, so an
absent frame counts as a failure at every threshold; pytracking
(``pytracking/analysis/extract_results.py``, ``exclude_invalid_frames=False``) does the same.
Hence ``absent_policy = "fail"``.  The root may also be one class folder, a flat folder of
``<class>-<N>`` sequences, or a single sequence folder.

**GOT-10k** ``<root>/{train,val,test}/list.txt`` and ``<split>/GOT-10k_Val_000001/00000001.jpg``
with ``groundtruth.txt``, ``absence.label``, ``cover.label`` (one value per line),
``meta_info.ini`` (got10k-toolkit ``got10k/datasets/got10k.py``).  The toolkit's evaluation
(``got10k/experiments/got10k.py``, ``report``) skips the first frame and keeps only frames with
``cover > 0``; here a frame is absent when ``absence.label`` is 1 or ``cover.label`` is 0, and
such frames are excluded (``absent_policy = "exclude"``).  The test split's ``groundtruth.txt``
holds the first box only.  Pointing at the root picks ``val`` when present (the split with ground
truth that the toolkit evaluates), or the only split there is.  ``meta["resolution"]`` is read from
``meta_info.ini`` (the toolkit clips boxes to it before computing overlaps).  Scoring:
:mod:`wmiltrack.eval.got10k_metrics`.

**UAV123, UAV123_10fps, UAV20L** ``<root>/data_seq/<frames>/<folder>/000001.jpg`` and
``<root>/anno/<subset>/<seq>.txt``: UAV123 and UAV20L share the 30 fps frames
(``data_seq/UAV123``, one release holding ``anno/UAV123`` and ``anno/UAV20L``); UAV123_10fps is
its own release (``data_seq/UAV123_10fps``, ``anno/UAV123_10fps``).  The root may also be the
download folder one level up.  An annotation file may cover a frame range of a shared folder
(UAV123's ``bird1_2`` = ``bird1`` frames 775-1477; UAV123_10fps's ``bird1_2`` = frames 259-493).
The releases' ``configSeqs.m`` (beside ``anno/``; UAV123_10fps's ``ReadMe.txt`` points to it
for the start and end frames) lists, per subset in a cell array ``seqUAV123`` / ``seqUAV20L`` /
``seqUAV123_10fps``, each sequence's folder, ``startFrame`` and ``endFrame``
(:func:`parse_config_seqs`); when the file is present its ranges are used, else a copy of the
published split tables (UAV123: got10k-toolkit ``got10k/datasets/uav123.json``, which agrees
with pytracking ``pytracking/evaluation/uavdataset.py``; UAV123_10fps: its ``configSeqs.m``),
else the whole folder named like the annotation (UAV20L annotates whole folders).
``meta["frame_range"]`` and ``meta["frame_range_source"]`` say which frames and why.  ``NaN``
annotation lines are absent frames (the ReadMe: fully occluded or out of the frame);
got10k-toolkit's ``ExperimentUAV123._calc_metrics`` (``got10k/experiments/uav123.py``) leaves
them out (``absent_policy = "exclude"``; pytracking's analysis instead counts them as failures).
A folder holding both ``anno/UAV123`` and ``anno/UAV20L`` is detected as UAV123: name
``layout="uav20l"`` for the other.

**TrackingNet** ``<root>/TRAIN_<k>/frames/<seq>/0.jpg ...`` and ``TRAIN_<k>/anno/<seq>.txt``;
``TEST/`` holds first-frame-only annotations (got10k-toolkit ``got10k/datasets/trackingnet.py``,
pytracking ``pytracking/evaluation/trackingnetdataset.py``: frames sorted by their integer name).
The root loads every ``TRAIN_<k>`` chunk present (or ``TEST`` when there is none); point at one
chunk folder to load only that one.

**VOT** ``<root>/list.txt`` and ``<seq>/color/00000001.jpg`` (VOT2017+) or ``<seq>/00000001.jpg``
(older editions), ``groundtruth.txt`` with one region per line (got10k-toolkit
``got10k/datasets/vot.py``; a VOT toolkit workspace's ``sequences/`` folder is found too).  Region
lines follow the VOT toolkit's parser (``votchallenge/toolkit``, ``vot/region/io.py``): 4 values a
rectangle, an even number > 4 a polygon, ``m<x0>,<y0>,<w>,<h>,<RLE...>`` a mask, a single value
a special code.  Polygons become the axis-aligned min/max box (pytracking
``pytracking/evaluation/votdataset.py``; got10k-toolkit's ``VOT._corner2rect`` uses an
area-preserving box instead, available as ``polygon_to_box(..., mode="area")``), masks the box of
their pixels.  Special codes, ``nan`` values and empty regions (``0,0,0,0``, empty masks) are
absent frames (``absent_policy = "exclude"``: VOT's own measures are not OPE figures).

**DTB70** ``<root>/<seq>/img/00001.jpg`` and ``<seq>/groundtruth_rect.txt`` (comma-separated
``x,y,w,h``, one line per image: got10k-toolkit ``got10k/datasets/dtb70.py``).  The structure is
OTB's, so detection calls a folder DTB70 only when every sequence's first frame is
``img/00001.jpg`` (five digits; OTB uses four but for ``Board``) and the folder (or its parent)
is named ``*DTB70*`` or at least half the sequences bear DTB70's names; ``layout="dtb70"``
loads any such folder.  ``absent_policy = "exclude"``.

**OTB** ``<root>/<Seq>/img/`` + ``groundtruth_rect.txt``: :func:`wmiltrack.data.sequences.load_otb_sequence`.

A dataset whose image count and annotation count differ is refused with both counts in the error.
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Callable, Iterable, Iterator
from collections.abc import Sequence as AbcSequence
from dataclasses import dataclass
from functools import lru_cache, partial
from pathlib import Path
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray

from .boxes import read_boxes
from .sequences import (
    GT_FILE,
    IMAGE_EXTENSIONS,
    Sequence,
    list_otb_sequences,
    load_otb_sequence,
    natural_key,
)

__all__ = [
    "LAYOUTS",
    "LayoutError",
    "detect_layout",
    "iter_layout",
    "list_layout",
    "load_layout",
    "parse_config_seqs",
    "parse_vot_region",
    "polygon_to_box",
]

LAYOUTS = ("otb", "lasot", "got10k", "uav123", "uav123_10fps", "uav20l", "trackingnet", "vot", "dtb70")
"""Layout names accepted by :func:`load_layout` (``layout=``) and returned by :func:`detect_layout`."""

_ALIASES = {
    "got-10k": "got10k",
    "got_10k": "got10k",
    "uav": "uav123",
    "uav123-10fps": "uav123_10fps",
    "uav123_10": "uav123_10fps",
    "uav10fps": "uav123_10fps",
    "uav-20l": "uav20l",
    "dtb": "dtb70",
    "dtb-70": "dtb70",
    "tracking-net": "trackingnet",
    "otb100": "otb",
    "otb2015": "otb",
}

_TITLES = {
    "otb": "OTB",
    "lasot": "LaSOT",
    "got10k": "GOT-10k",
    "uav123": "UAV123",
    "uav123_10fps": "UAV123_10fps",
    "uav20l": "UAV20L",
    "trackingnet": "TrackingNet",
    "vot": "VOT",
    "dtb70": "DTB70",
}

_EXPECTED = {
    "otb": "sequence folders <Seq>/img/*.jpg with <Seq>/groundtruth_rect.txt, or one such folder",
    "lasot": "<class>/<class>-<N>/img/*.jpg with groundtruth.txt next to img/ "
    "(or a class folder, or one <class>-<N> folder)",
    "got10k": "train/, val/ or test/ split folders, or a split folder holding list.txt and "
    "sequence folders with images, groundtruth.txt and absence.label/cover.label/meta_info.ini",
    "uav123": "data_seq/UAV123/<folder>/000001.jpg and anno/UAV123/<seq>.txt",
    "uav123_10fps": "data_seq/UAV123_10fps/<folder>/000001.jpg and anno/UAV123_10fps/<seq>.txt "
    "(configSeqs.m beside them gives each sequence's folder and frames)",
    "uav20l": "data_seq/UAV123/<seq>/000001.jpg and anno/UAV20L/<seq>.txt",
    "trackingnet": "TRAIN_<k>/ or TEST/ chunk folders holding frames/<seq>/*.jpg and anno/<seq>.txt, "
    "or one such chunk folder",
    "vot": "list.txt and <seq>/color/*.jpg (or <seq>/*.jpg) with a region groundtruth.txt "
    "per sequence, or one such sequence folder",
    "dtb70": "sequence folders <seq>/img/00001.jpg with <seq>/groundtruth_rect.txt, or one such "
    "folder (detected as DTB70 rather than OTB when the folder is named DTB70 or most "
    "sequences bear DTB70's names)",
}

Boxes = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


class LayoutError(ValueError):
    """A folder is not a dataset in the requested layout, or is a broken one."""


@dataclass(frozen=True)
class _Entry:
    """A sequence found while listing: its name and how to load it (nothing read yet)."""

    name: str
    load: Callable[[], Sequence]


# ---------------------------------------------------------------------- small helpers
def _images_in(folder: Path) -> list[Path]:
    """Image files directly in ``folder`` in natural order (names only: nothing is decoded)."""
    if not folder.is_dir():
        return []
    with os.scandir(folder) as it:
        names = [
            e.name
            for e in it
            if e.is_file() and os.path.splitext(e.name)[1].lower() in IMAGE_EXTENSIONS
        ]
    if all(os.path.splitext(n)[0].isdigit() for n in names):
        # the usual case (00000001.jpg, 0.jpg): numeric order, ~8x faster than natural_key
        names.sort(key=lambda n: (int(os.path.splitext(n)[0]), n))
    else:
        names.sort(key=natural_key)
    return [folder / n for n in names]


def _has_images(folder: Path) -> bool:
    if not folder.is_dir():
        return False
    with os.scandir(folder) as it:
        return any(
            e.is_file() and os.path.splitext(e.name)[1].lower() in IMAGE_EXTENSIONS for e in it
        )


def _subdirs(folder: Path) -> list[Path]:
    if not folder.is_dir():
        return []
    with os.scandir(folder) as it:
        dirs = [Path(e.path) for e in it if e.is_dir() and not e.name.startswith(".")]
    dirs.sort(key=lambda p: natural_key(p.name))
    return dirs


def _read_box_file(path: Path) -> Boxes:
    """``x,y,w,h`` lines; fast path through :func:`numpy.loadtxt`, exact errors from ``read_boxes``."""
    try:
        arr = np.loadtxt(path, delimiter=",", dtype=np.float64, ndmin=2, encoding="utf-8-sig")
    except (ValueError, OSError):
        arr = None
    if arr is not None and arr.size == 0:
        return np.zeros((0, 4), dtype=np.float64)
    if arr is not None and arr.shape[1] == 4:
        return np.ascontiguousarray(arr)
    try:
        return read_boxes(path)  # other separators, or an error naming the line
    except ValueError as exc:
        raise LayoutError(str(exc)) from None


_FLAG_SPLIT = re.compile(r"[,\s]+")


def _read_flags(path: Path) -> NDArray[np.float64]:
    """Per-frame numbers written one per line or comma-separated on one line."""
    text = path.read_text(encoding="utf-8-sig")
    fields = [f for f in _FLAG_SPLIT.split(text) if f]
    try:
        return np.asarray([float(f) for f in fields], dtype=np.float64)
    except ValueError:
        raise LayoutError(f"{path}: expected one number per frame, found {text[:60]!r}") from None


def _check_count(what: str, n_images: int, img_dir: Path, n_boxes: int, gt_file: Path) -> None:
    if n_images != n_boxes:
        raise LayoutError(
            f"{what}: {n_images} images in {img_dir} but {n_boxes} boxes in {gt_file}; the "
            "annotation must have one line per frame (refusing to guess which frames it covers)"
        )


def _check_flags(what: str, flags: NDArray[Any], path: Path, n: int) -> None:
    if len(flags) != n:
        raise LayoutError(f"{what}: {path} has {len(flags)} values for {n} frames")


def _absent_rows(gt: Boxes) -> BoolArray:
    """Rows that cannot be a target box: a ``nan`` or a non-positive width or height."""
    with np.errstate(invalid="ignore"):
        ok = np.all(np.isfinite(gt), axis=1) & (gt[:, 2] > 0) & (gt[:, 3] > 0)
    return np.asarray(~ok)


def _make_sequence(
    name: str,
    images: list[Path],
    gt: Boxes,
    absent: BoolArray,
    meta: dict[str, Any],
) -> Sequence:
    gt = np.array(gt, dtype=np.float64, copy=True)
    gt[absent] = np.nan
    info = {"absent": np.asarray(absent, dtype=bool), "first_frame_only": False}
    info.update(meta)
    return Sequence(name=name, groundtruth=gt, paths=tuple(images), meta=info)


def _first_frame_only(
    what: str, images: list[Path], img_dir: Path, gt: Boxes, gt_file: Path
) -> Boxes | None:
    """Pad a one-line (first frame only) annotation with ``nan`` rows; ``None`` if not that case."""
    if len(gt) == 1 and len(images) > 1:
        full = np.full((len(images), 4), np.nan)
        full[0] = gt[0]
        return full
    if len(gt) == 0:
        raise LayoutError(f"{what}: {gt_file} holds no box")
    _check_count(what, len(images), img_dir, len(gt), gt_file)
    return None


def _frame_numbers(images: list[Path]) -> dict[int, Path]:
    out: dict[int, Path] = {}
    for p in images:
        digits = re.findall(r"\d+", p.stem)
        if digits:
            out.setdefault(int(digits[-1]), p)
    return out


# ---------------------------------------------------------------------- LaSOT
_LASOT_NAME = re.compile(r"^(.+)-(\d+)$")


def _is_lasot_seq(d: Path) -> bool:
    return (
        _LASOT_NAME.match(d.name) is not None
        and (d / "img").is_dir()
        and (d / "groundtruth.txt").is_file()
    )


def _load_lasot(seq_dir: Path) -> Sequence:
    name = seq_dir.name
    what = f"LaSOT sequence {name}"
    gt_file = seq_dir / "groundtruth.txt"
    img_dir = seq_dir / "img"
    gt = _read_box_file(gt_file)
    images = _images_in(img_dir)
    if len(gt) == 0:
        raise LayoutError(f"{what}: {gt_file} holds no box")
    _check_count(what, len(images), img_dir, len(gt), gt_file)
    absent = np.zeros(len(gt), dtype=bool)
    sources = []
    for flag_name in ("full_occlusion.txt", "out_of_view.txt"):
        flag_file = seq_dir / flag_name
        if flag_file.is_file():
            flags = _read_flags(flag_file)
            _check_flags(what, flags, flag_file, len(gt))
            absent |= flags != 0
            sources.append(flag_name)
    meta = {
        "layout": "lasot",
        "absent_policy": "fail",
        "absent_sources": tuple(sources),
        "category": _LASOT_NAME.match(name).group(1),  # type: ignore[union-attr]
    }
    return _make_sequence(name, images, gt, absent, meta)


def _index_lasot(root: Path) -> list[_Entry] | None:
    if _is_lasot_seq(root):
        seq_dirs = [root]
    else:
        children = _subdirs(root)
        seq_dirs = [d for d in children if _is_lasot_seq(d)]  # a class folder or a flat folder
        if not seq_dirs:
            seq_dirs = [
                s
                for c in children
                for s in _subdirs(c)
                if s.name.startswith(c.name + "-") and _is_lasot_seq(s)
            ]
    if not seq_dirs:
        return None
    seq_dirs.sort(key=lambda p: natural_key(p.name))
    return [_Entry(d.name, partial(_load_lasot, d)) for d in seq_dirs]


# ---------------------------------------------------------------------- GOT-10k
_GOT_SPLITS = ("train", "val", "test")
_GOT_MARKERS = ("absence.label", "cover.label", "meta_info.ini")


def _is_got_seq(d: Path) -> bool:
    return (
        (d / "groundtruth.txt").is_file()
        and (d.name.startswith("GOT-10k_") or any((d / m).is_file() for m in _GOT_MARKERS))
    )


def _read_list(list_file: Path) -> list[str]:
    return [line.strip() for line in list_file.read_text(encoding="utf-8-sig").splitlines() if line.strip()]


def _parse_resolution(ini: Path) -> tuple[int, int] | None:
    for line in ini.read_text(encoding="utf-8-sig", errors="replace").splitlines():
        key, _, value = line.partition(":")
        if key.strip() == "resolution":
            nums = re.findall(r"\d+", value)
            if len(nums) == 2:
                return (int(nums[0]), int(nums[1]))
    return None


def _load_got10k(seq_dir: Path, split: str | None) -> Sequence:
    name = seq_dir.name
    what = f"GOT-10k sequence {name}"
    gt_file = seq_dir / "groundtruth.txt"
    gt = _read_box_file(gt_file)
    images = _images_in(seq_dir)
    padded = _first_frame_only(what, images, seq_dir, gt, gt_file)
    meta: dict[str, Any] = {"layout": "got10k", "absent_policy": "exclude", "split": split}
    if padded is not None:
        absent = np.zeros(len(images), dtype=bool)
        meta["first_frame_only"] = True
        gt = padded
    else:
        absent = np.zeros(len(gt), dtype=bool)
        sources = []
        absence_file = seq_dir / "absence.label"
        if absence_file.is_file():
            flags = _read_flags(absence_file)
            _check_flags(what, flags, absence_file, len(gt))
            absent |= flags != 0
            sources.append("absence.label")
        cover_file = seq_dir / "cover.label"
        if cover_file.is_file():
            cover = _read_flags(cover_file)
            _check_flags(what, cover, cover_file, len(gt))
            absent |= cover <= 0
            sources.append("cover.label")
            meta["cover"] = cover
        meta["absent_sources"] = tuple(sources)
    ini = seq_dir / "meta_info.ini"
    if ini.is_file():
        res = _parse_resolution(ini)
        if res is not None:
            meta["resolution"] = res
    return _make_sequence(name, images, gt, absent, meta)


def _got_split_entries(split_dir: Path, split: str | None) -> list[_Entry] | None:
    list_file = split_dir / "list.txt"
    if list_file.is_file():
        names = _read_list(list_file)
        missing = [n for n in names if not (split_dir / n).is_dir()]
        if missing:
            raise LayoutError(
                f"{split_dir} is a broken GOT-10k split: list.txt names {len(missing)} sequence(s) "
                f"with no folder ({', '.join(missing[:5])}{', ...' if len(missing) > 5 else ''})"
            )
        dirs = [split_dir / n for n in names]
        if not dirs or not any(_is_got_seq(d) for d in dirs[:3]):
            return None
    else:
        dirs = [d for d in _subdirs(split_dir) if _is_got_seq(d)]
        if not dirs:
            return None
    return [_Entry(d.name, partial(_load_got10k, d, split)) for d in dirs]


def _index_got10k(root: Path) -> list[_Entry] | None:
    if _is_got_seq(root) and _has_images(root):
        return [_Entry(root.name, partial(_load_got10k, root, None))]
    splits = {s: root / s for s in _GOT_SPLITS if (root / s).is_dir()}
    found = {s: e for s, d in splits.items() if (e := _got_split_entries(d, s))}
    if found:
        if len(found) == 1:
            return next(iter(found.values()))
        if "val" in found:
            return found["val"]
        raise LayoutError(
            f"{root} holds several GOT-10k splits ({', '.join(found)}) and no val/; "
            "point at the split folder to evaluate"
        )
    split = root.name if root.name in _GOT_SPLITS else None
    return _got_split_entries(root, split)


# ---------------------------------------------------------------------- UAV123, UAV123_10fps, UAV20L
# Annotation files covering a frame range of a shared image folder:
# name -> (folder under data_seq/<subset>, first frame, last frame), 1-based and inclusive.
# UAV123 (30 fps): got10k-toolkit got10k/datasets/uav123.json (agrees with pytracking's
# uavdataset.py and with the seqUAV123 table of the release's configSeqs.m).
_UAV123_SPLITS: dict[str, tuple[str, int, int]] = {
    "bird1_1": ("bird1", 1, 253),
    "bird1_2": ("bird1", 775, 1477),
    "bird1_3": ("bird1", 1573, 2437),
    "car1_1": ("car1", 1, 751),
    "car1_2": ("car1", 751, 1627),
    "car1_3": ("car1", 1627, 2629),
    "car6_1": ("car6", 1, 487),
    "car6_2": ("car6", 487, 1807),
    "car6_3": ("car6", 1807, 2953),
    "car6_4": ("car6", 2953, 3925),
    "car6_5": ("car6", 3925, 4861),
    "car8_1": ("car8", 1, 1357),
    "car8_2": ("car8", 1357, 2575),
    "car16_1": ("car16", 1, 415),
    "car16_2": ("car16", 415, 1993),
    "group1_1": ("group1", 1, 1333),
    "group1_2": ("group1", 1333, 2515),
    "group1_3": ("group1", 2515, 3925),
    "group1_4": ("group1", 3925, 4873),
    "group2_1": ("group2", 1, 907),
    "group2_2": ("group2", 907, 1771),
    "group2_3": ("group2", 1771, 2683),
    "group3_1": ("group3", 1, 1567),
    "group3_2": ("group3", 1567, 2827),
    "group3_3": ("group3", 2827, 4369),
    "group3_4": ("group3", 4369, 5527),
    "person2_1": ("person2", 1, 1189),
    "person2_2": ("person2", 1189, 2623),
    "person4_1": ("person4", 1, 1501),
    "person4_2": ("person4", 1501, 2743),
    "person5_1": ("person5", 1, 877),
    "person5_2": ("person5", 877, 2101),
    "person7_1": ("person7", 1, 1249),
    "person7_2": ("person7", 1249, 2065),
    "person8_1": ("person8", 1, 1075),
    "person8_2": ("person8", 1075, 1525),
    "person12_1": ("person12", 1, 601),
    "person12_2": ("person12", 601, 1621),
    "person14_1": ("person14", 1, 847),
    "person14_2": ("person14", 847, 1813),
    "person14_3": ("person14", 1813, 2923),
    "person17_1": ("person17", 1, 1501),
    "person17_2": ("person17", 1501, 2347),
    "person19_1": ("person19", 1, 1243),
    "person19_2": ("person19", 1243, 2791),
    "person19_3": ("person19", 2791, 4357),
    "truck4_1": ("truck4", 1, 577),
    "truck4_2": ("truck4", 577, 1261),
    "uav1_1": ("uav1", 1, 1555),
    "uav1_2": ("uav1", 1555, 2377),
    "uav1_3": ("uav1", 2473, 3469),
}
# UAV123_10fps: the seqUAV123_10fps table of that release's configSeqs.m (used only when the
# file is not in the dataset folder; the file, when present, wins).
_UAV123_10FPS_SPLITS: dict[str, tuple[str, int, int]] = {
    "bird1_1": ("bird1", 1, 85),
    "bird1_2": ("bird1", 259, 493),
    "bird1_3": ("bird1", 525, 813),
    "car1_1": ("car1", 1, 251),
    "car1_2": ("car1", 251, 543),
    "car1_3": ("car1", 543, 877),
    "car6_1": ("car6", 1, 163),
    "car6_2": ("car6", 163, 603),
    "car6_3": ("car6", 603, 985),
    "car6_4": ("car6", 985, 1309),
    "car6_5": ("car6", 1309, 1621),
    "car8_1": ("car8", 1, 453),
    "car8_2": ("car8", 453, 859),
    "car16_1": ("car16", 1, 139),
    "car16_2": ("car16", 139, 665),
    "group1_1": ("group1", 1, 445),
    "group1_2": ("group1", 445, 839),
    "group1_3": ("group1", 839, 1309),
    "group1_4": ("group1", 1309, 1625),
    "group2_1": ("group2", 1, 303),
    "group2_2": ("group2", 303, 591),
    "group2_3": ("group2", 591, 895),
    "group3_1": ("group3", 1, 523),
    "group3_2": ("group3", 523, 943),
    "group3_3": ("group3", 943, 1457),
    "group3_4": ("group3", 1457, 1843),
    "person2_1": ("person2", 1, 397),
    "person2_2": ("person2", 397, 875),
    "person4_1": ("person4", 1, 501),
    "person4_2": ("person4", 501, 915),
    "person5_1": ("person5", 1, 293),
    "person5_2": ("person5", 293, 701),
    "person7_1": ("person7", 1, 417),
    "person7_2": ("person7", 417, 689),
    "person8_1": ("person8", 1, 359),
    "person8_2": ("person8", 359, 509),
    "person12_1": ("person12", 1, 201),
    "person12_2": ("person12", 201, 541),
    "person14_1": ("person14", 1, 283),
    "person14_2": ("person14", 283, 605),
    "person14_3": ("person14", 605, 975),
    "person17_1": ("person17", 1, 501),
    "person17_2": ("person17", 501, 783),
    "person19_1": ("person19", 1, 415),
    "person19_2": ("person19", 415, 931),
    "person19_3": ("person19", 931, 1453),
    "truck4_1": ("truck4", 1, 193),
    "truck4_2": ("truck4", 193, 421),
    "uav1_1": ("uav1", 1, 519),
    "uav1_2": ("uav1", 519, 793),
    "uav1_3": ("uav1", 825, 1157),
}


@dataclass(frozen=True)
class _UavSubset:
    """One benchmark of the UAV123 family: where its annotations and frames are, and how
    annotation files map to frame ranges when ``configSeqs.m`` does not say."""

    layout: str
    anno: str  # folder under anno/
    data: str  # folder under data_seq/
    splits: dict[str, tuple[str, int, int]]


_UAV_FAMILY = {
    "uav123": _UavSubset("uav123", "UAV123", "UAV123", _UAV123_SPLITS),
    "uav123_10fps": _UavSubset("uav123_10fps", "UAV123_10fps", "UAV123_10fps", _UAV123_10FPS_SPLITS),
    # UAV20L annotates whole folders of the 30 fps release (configSeqs.m: startFrame 1).
    "uav20l": _UavSubset("uav20l", "UAV20L", "UAV123", {}),
}
_CONFIG_SEQS = "configSeqs.m"


def _uav_root(root: Path, subset: _UavSubset) -> Path | None:
    """The folder holding ``anno/<subset>`` and ``data_seq/<frames>``: ``root`` or one below."""
    for r in (root, root / subset.anno, root / subset.data):
        if (r / "data_seq" / subset.data).is_dir() and (r / "anno" / subset.anno).is_dir():
            return r
    return None


def _strip_matlab_comments(text: str) -> str:
    """``text`` without MATLAB ``%`` comments (a ``%`` inside a quoted string is kept), so that a
    commented-out struct is not read as a sequence."""
    out = []
    for line in text.splitlines():
        quoted = False
        for i, ch in enumerate(line):
            if ch == "'":
                quoted = not quoted
            elif ch == "%" and not quoted:
                line = line[:i]
                break
        out.append(line)
    return "\n".join(out)


_CLOSER = {"(": ")", "[": "]", "{": "}"}


def _matlab_group(text: str, start: int) -> tuple[list[str], int]:
    """Top-level elements of the bracketed group opened at ``text[start]`` (``(``, ``[`` or
    ``{``) and the index after its closer.  Elements are split at commas, and for ``{``/``[``
    also at ``;`` and line ends; quoted strings and nested groups are kept whole, and ``...``
    continues a line."""
    closer = _CLOSER[text[start]]
    rows = closer != ")"
    depth, quoted, items, cur = 0, False, [], []
    i = start + 1
    while i < len(text):
        ch = text[i]
        if quoted:
            cur.append(ch)
            if ch == "'":
                if text.startswith("''", i):  # a quote inside the string
                    cur.append("'")
                    i += 1
                else:
                    quoted = False
        elif ch == "'":
            quoted = True
            cur.append(ch)
        elif text.startswith("...", i):  # the rest of the line and its end are skipped
            nl = text.find("\n", i)
            i = len(text) if nl < 0 else nl + 1
            continue
        elif ch in _CLOSER:
            depth += 1
            cur.append(ch)
        elif depth == 0 and ch == closer:
            items.append("".join(cur).strip())
            return [s for s in items if s], i + 1
        elif ch in ")]}":
            depth -= 1
            cur.append(ch)
        elif depth == 0 and (ch == "," or (rows and ch in ";\n")):
            items.append("".join(cur).strip())
            cur = []
        else:
            cur.append(ch)
        i += 1
    raise ValueError(f"no closing {closer!r}")


_MATLAB_STRING = re.compile(r"'((?:[^']|'')*)'")
_CELL_START = re.compile(r"\b(seq\w*)\s*=\s*\{")
_STRUCT_CALL = re.compile(r"struct\s*\(")


def _matlab_string(token: str) -> str | None:
    m = _MATLAB_STRING.fullmatch(token.strip())
    return m.group(1).replace("''", "'") if m else None


def parse_config_seqs(path: str | os.PathLike[str]) -> dict[str, dict[str, tuple[str, int, int]]]:
    """Read the sequence tables of a UAV123-style ``configSeqs.m``.

    The UAV123 releases describe each sequence as a MATLAB struct inside a cell array,
    ``seqUAV123_10fps = {struct('name','bird1_2','path','D:\\data_seq\\UAV123_10fps\\bird1\\',
    'startFrame',259,'endFrame',493,'nz',6,'ext','jpg','init_rect',[0,0,0,0]), ...}``: the
    annotation file ``anno/<subset>/<name>.txt`` holds one line per frame ``startFrame`` ..
    ``endFrame`` (1-based, inclusive) of the image folder that ends ``path``.  The path may be a
    literal, ``fullfile(root, 'bird1\\')`` or ``[root '\\bird1\\']``: its last quoted piece
    names the folder (the sequence's own name when there is no path).

    Parameters
    ----------
    path:
        The ``configSeqs.m`` file.

    Returns
    -------
    dict
        Cell-array name without its ``seq`` prefix (``"UAV123_10fps"``, ``"UAV20L"``, ...) ->
        ``{sequence name: (folder, start frame, end frame)}``.

    Raises
    ------
    LayoutError
        If a cell array or struct is not closed, a struct has no name, or its frame numbers
        are missing, not integers, or not ``1 <= startFrame <= endFrame``; the message names
        the file and the struct.
    """
    p = Path(path)
    text = _strip_matlab_comments(p.read_text(encoding="utf-8-sig", errors="replace"))
    tables: dict[str, dict[str, tuple[str, int, int]]] = {}
    pos = 0
    while (cell := _CELL_START.search(text, pos)) is not None:
        var = cell.group(1)
        try:
            items, pos = _matlab_group(text, cell.end() - 1)
        except ValueError:
            raise LayoutError(f"{p}: the cell array {var} is not closed") from None
        table = tables.setdefault(var[3:].lstrip("_"), {})
        for item in items:
            call = _STRUCT_CALL.match(item)
            if call is None:
                continue
            try:
                args, _ = _matlab_group(item, call.end() - 1)
            except ValueError:
                raise LayoutError(f"{p}: a struct of {var} is not closed: {item[:80]!r}") from None
            fields = {(_matlab_string(k) or k): v for k, v in zip(args[0::2], args[1::2])}
            name = _matlab_string(fields.get("name", ""))
            if not name:
                raise LayoutError(f"{p}: a struct of {var} has no 'name': {item[:80]!r}")
            try:
                start, end = int(fields["startFrame"]), int(fields["endFrame"])
            except (KeyError, ValueError):
                raise LayoutError(
                    f"{p}: struct {name!r} of {var} needs integer 'startFrame' and 'endFrame'"
                ) from None
            if not 1 <= start <= end:
                raise LayoutError(
                    f"{p}: struct {name!r} of {var} has startFrame {start} and endFrame {end}"
                )
            pieces = _MATLAB_STRING.findall(fields.get("path", ""))
            parts = [c for c in re.split(r"[\\/]+", pieces[-1]) if c] if pieces else []
            table[name] = (parts[-1] if parts else name, start, end)
    return tables


@lru_cache(maxsize=8)
def _cached_config(path: str, mtime_ns: int, size: int) -> dict[str, dict[str, tuple[str, int, int]]]:
    return parse_config_seqs(path)  # keyed on mtime and size: an edited file is read again


def _uav_config(r: Path, subset: _UavSubset) -> tuple[dict[str, tuple[str, int, int]], Path] | None:
    """This subset's table from the ``configSeqs.m`` beside ``anno/`` (or one folder up)."""
    for cfg in (r / _CONFIG_SEQS, r.parent / _CONFIG_SEQS):
        if cfg.is_file():
            st = cfg.stat()
            for var, table in _cached_config(str(cfg), st.st_mtime_ns, st.st_size).items():
                if var.lower() == subset.anno.lower():
                    return table, cfg
    return None


def _uav_span(r: Path, subset: _UavSubset, name: str) -> tuple[tuple[str, int, int] | None, str]:
    """Folder and frame range of a sequence, and where they come from."""
    config = _uav_config(r, subset)
    if config is not None and name in config[0]:
        return config[0][name], str(config[1])
    if name in subset.splits:
        return subset.splits[name], "wmiltrack's copy of the published table"
    return None, "the image folder"


def _load_uav(root: Path, subset: _UavSubset, name: str) -> Sequence:
    what = f"{subset.anno} sequence {name}"
    gt_file = root / "anno" / subset.anno / f"{name}.txt"
    gt = _read_box_file(gt_file)
    if len(gt) == 0:
        raise LayoutError(f"{what}: {gt_file} holds no box")
    span, source = _uav_span(root, subset, name)
    folder_name = span[0] if span is not None else name
    img_dir = root / "data_seq" / subset.data / folder_name
    images = _images_in(img_dir)
    if not images:
        raise LayoutError(f"{what}: no images in {img_dir}")
    if span is None:
        _check_count(what, len(images), img_dir, len(gt), gt_file)
        frames, start, end = images, 1, len(gt)
    else:
        _, start, end = span
        if end - start + 1 != len(gt):
            raise LayoutError(
                f"{what}: {gt_file} has {len(gt)} boxes but the sequence is frames {start}-{end} "
                f"of {folder_name} ({end - start + 1} frames, from {source})"
            )
        by_number = _frame_numbers(images)
        missing = [i for i in range(start, end + 1) if i not in by_number]
        if missing:
            raise LayoutError(
                f"{what}: frames {start}-{end} of {img_dir} are needed but {len(missing)} are "
                f"missing (first: {missing[0]:06d})"
            )
        frames = [by_number[i] for i in range(start, end + 1)]
    meta = {
        "layout": subset.layout,
        "absent_policy": "exclude",
        "subset": subset.anno,
        "folder": folder_name,
        "frame_range": (start, end),
        "frame_range_source": source,
    }
    return _make_sequence(name, frames, gt, _absent_rows(gt), meta)


def _index_uav(key: str, root: Path) -> list[_Entry] | None:
    subset = _UAV_FAMILY[key]
    r = _uav_root(root, subset)
    if r is None:
        return None
    names = sorted((p.stem for p in (r / "anno" / subset.anno).glob("*.txt")), key=natural_key)
    if not names:
        return None
    return [_Entry(n, partial(_load_uav, r, subset, n)) for n in names]


# ---------------------------------------------------------------------- DTB70
# The 70 sequence names of DTB70 (the list in pytracking-style DTB70 loaders; the folders
# themselves are listed, this only tells DTB70 from OTB when detecting).
_DTB70_NAMES = frozenset(
    "Animal1 Animal2 Animal3 Animal4 Basketball BMX2 BMX3 BMX4 BMX5 Car2 Car4 Car5 Car6 Car8 "
    "ChasingDrones Girl1 Girl2 Gull1 Gull2 Horse1 Horse2 Kiting ManRunning1 ManRunning2 Motor1 "
    "Motor2 MountainBike1 MountainBike5 MountainBike6 Paragliding3 Paragliding5 RaceCar RaceCar1 "
    "RcCar3 RcCar4 RcCar5 RcCar6 RcCar7 RcCar8 RcCar9 Sheep1 Sheep2 SkateBoarding4 Skiing1 "
    "Skiing2 SnowBoarding2 SnowBoarding4 SnowBoarding6 Soccer1 Soccer2 SpeedCar2 SpeedCar4 "
    "StreetBasketball1 StreetBasketball2 StreetBasketball3 SUP2 SUP4 SUP5 Surfing03 Surfing04 "
    "Surfing06 Surfing10 Surfing12 Vaulting Wakeboarding1 Wakeboarding2 Walking Yacht2 Yacht4 "
    "Zebra".split()
)
_DTB70_FIRST = "00001.jpg"  # five-digit frame names (OTB uses four, but for Board)


def _is_dtb70_seq(d: Path) -> bool:
    return (d / "img").is_dir() and (d / GT_FILE).is_file()


def _dtb70_dirs(root: Path) -> list[Path]:
    if _is_dtb70_seq(root):
        return [root]
    return [d for d in _subdirs(root) if _is_dtb70_seq(d)]


def _looks_dtb70(root: Path, dirs: list[Path]) -> bool:
    """Tell a DTB70 folder from an OTB one, which has the same structure: five-digit frame
    names in every sequence, and the folder named DTB70 or most sequences named as DTB70's."""
    if not all((d / "img" / _DTB70_FIRST).is_file() for d in dirs):
        return False
    if any("dtb70" in p.name.lower() for p in (root, root.parent)):
        return True
    return 2 * sum(d.name in _DTB70_NAMES for d in dirs) >= len(dirs)


def _load_dtb70(seq_dir: Path) -> Sequence:
    name = seq_dir.name
    what = f"DTB70 sequence {name}"
    gt_file = seq_dir / GT_FILE
    img_dir = seq_dir / "img"
    gt = _read_box_file(gt_file)
    images = _images_in(img_dir)
    if len(gt) == 0:
        raise LayoutError(f"{what}: {gt_file} holds no box")
    _check_count(what, len(images), img_dir, len(gt), gt_file)
    meta = {"layout": "dtb70", "absent_policy": "exclude"}
    return _make_sequence(name, images, gt, _absent_rows(gt), meta)


def _index_dtb70(root: Path, detecting: bool = False) -> list[_Entry] | None:
    dirs = _dtb70_dirs(root)
    if not dirs or (detecting and not _looks_dtb70(root, dirs)):
        return None
    return [_Entry(d.name, partial(_load_dtb70, d)) for d in dirs]


# ---------------------------------------------------------------------- TrackingNet
_TN_CHUNK = re.compile(r"^(TRAIN_\d+|TEST)$")


def _is_tn_chunk(d: Path) -> bool:
    return (d / "anno").is_dir() and (d / "frames").is_dir()


def _load_trackingnet(chunk: Path, name: str) -> Sequence:
    what = f"TrackingNet sequence {chunk.name}/{name}"
    gt_file = chunk / "anno" / f"{name}.txt"
    img_dir = chunk / "frames" / name
    gt = _read_box_file(gt_file)
    images = _images_in(img_dir)
    if not images:
        raise LayoutError(f"{what}: no images in {img_dir}")
    padded = _first_frame_only(what, images, img_dir, gt, gt_file)
    meta: dict[str, Any] = {"layout": "trackingnet", "absent_policy": "exclude", "chunk": chunk.name}
    if padded is not None:
        meta["first_frame_only"] = True
        return _make_sequence(name, images, padded, np.zeros(len(images), dtype=bool), meta)
    return _make_sequence(name, images, gt, _absent_rows(gt), meta)


def _index_trackingnet(root: Path) -> list[_Entry] | None:
    if _is_tn_chunk(root) and _TN_CHUNK.match(root.name):
        chunks = [root]
    else:
        found = [d for d in _subdirs(root) if _TN_CHUNK.match(d.name) and _is_tn_chunk(d)]
        train = [d for d in found if d.name != "TEST"]
        chunks = train or found
        if not chunks and _is_tn_chunk(root):
            chunks = [root]  # a chunk folder under another name
    entries: list[_Entry] = []
    seen: dict[str, str] = {}
    for chunk in chunks:
        for p in sorted((chunk / "anno").glob("*.txt"), key=lambda p: natural_key(p.name)):
            if p.stem in seen:
                raise LayoutError(
                    f"TrackingNet sequence {p.stem} is in both {seen[p.stem]} and {chunk.name}"
                )
            seen[p.stem] = chunk.name
            entries.append(_Entry(p.stem, partial(_load_trackingnet, chunk, p.stem)))
    return entries or None


# ---------------------------------------------------------------------- VOT
def polygon_to_box(
    values: Iterable[float], mode: Literal["minmax", "area"] = "minmax"
) -> tuple[float, float, float, float]:
    """Axis-aligned ``(x, y, w, h)`` box of a VOT polygon ``x1, y1, x2, y2, ...``.

    Parameters
    ----------
    values:
        An even number (>= 6) of coordinates.
    mode:
        ``"minmax"``: the tightest box holding every vertex (pytracking's VOT loader).
        ``"area"``: got10k-toolkit's ``VOT._corner2rect`` for 4-vertex polygons: the min/max box
        scaled about the polygon's mean point so its area matches the polygon's
        (``|p1 - p2| * |p2 - p3|``), plus 1 to the width and height as the toolkit does.

    Returns
    -------
    tuple of float
        ``nan`` values if any coordinate is ``nan``.

    Raises
    ------
    ValueError
        If the number of values is odd or below 6, or ``mode="area"`` is given something other
        than 4 vertices.
    """
    v = np.asarray(list(values), dtype=np.float64)
    if v.size < 6 or v.size % 2:
        raise ValueError(f"a polygon needs an even number (>= 6) of coordinates, got {v.size}")
    xs, ys = v[0::2], v[1::2]
    if not np.all(np.isfinite(v)):
        return (math.nan, math.nan, math.nan, math.nan)
    x1, x2, y1, y2 = float(xs.min()), float(xs.max()), float(ys.min()), float(ys.max())
    if mode == "minmax":
        return (x1, y1, x2 - x1, y2 - y1)
    if mode != "area":
        raise ValueError(f"mode must be 'minmax' or 'area', not {mode!r}")
    if v.size != 8:
        raise ValueError("mode='area' needs a 4-vertex polygon (8 values)")
    cx, cy = float(xs.mean()), float(ys.mean())
    area1 = float(np.linalg.norm(v[0:2] - v[2:4]) * np.linalg.norm(v[2:4] - v[4:6]))
    area2 = (x2 - x1) * (y2 - y1)
    scale = math.sqrt(area1 / area2) if area2 > 0 else 0.0
    w = scale * (x2 - x1) + 1
    h = scale * (y2 - y1) + 1
    return (cx - w / 2, cy - h / 2, w, h)


def _mask_box(fields: list[str]) -> tuple[float, float, float, float]:
    """Box of the pixels of a VOT mask ``x0, y0, w, h, RLE...`` (RLE: zeros, ones, ... row-major)."""
    nums = [int(float(f)) for f in fields]
    if len(nums) < 4:
        raise ValueError("a mask needs x0, y0, width, height and run lengths")
    x0, y0, w, h = nums[:4]
    runs = nums[4:]
    flat = np.zeros(max(w * h, 0), dtype=bool)
    pos = 0
    for i, run in enumerate(runs):
        if i % 2:
            flat[pos : pos + run] = True
        pos += run
    if pos > w * h:
        raise ValueError(f"mask run lengths cover {pos} pixels of a {w}x{h} region")
    if not flat.any():
        return (math.nan, math.nan, math.nan, math.nan)
    mask = flat.reshape(h, w)
    rows = np.flatnonzero(mask.any(axis=1))
    cols = np.flatnonzero(mask.any(axis=0))
    return (
        float(x0 + cols[0]),
        float(y0 + rows[0]),
        float(cols[-1] - cols[0] + 1),
        float(rows[-1] - rows[0] + 1),
    )


def parse_vot_region(
    line: str, polygon: Literal["minmax", "area"] = "minmax"
) -> tuple[tuple[float, float, float, float], str]:
    """Parse one line of a VOT ``groundtruth.txt`` into an axis-aligned box.

    Parameters
    ----------
    line:
        ``x,y,w,h`` (rectangle), ``x1,y1,...,xn,yn`` (polygon, n >= 3), ``m<x0>,<y0>,<w>,<h>,<RLE>``
        (mask) or a single number (special code), as the VOT toolkit's ``vot/region/io.py`` reads.
    polygon:
        How polygons become boxes, see :func:`polygon_to_box`.

    Returns
    -------
    box, kind
        ``(x, y, w, h)``, ``nan`` values when the target is absent (special code, ``nan`` values,
        an empty mask, or a box or polygon with no area such as ``0,0,0,0``), and the region
        kind: ``"rectangle"``, ``"polygon"``, ``"mask"`` or ``"special"``.

    Raises
    ------
    ValueError
        If the line is none of these.
    """
    text = line.strip()
    nan4 = (math.nan, math.nan, math.nan, math.nan)
    if text.startswith("m"):
        box = _mask_box([f for f in text[1:].split(",") if f.strip()])
        kind = "mask"
    else:
        fields = [f for f in re.split(r"[,\s]+", text) if f]
        try:
            vals = [float(f) for f in fields]
        except ValueError:
            raise ValueError(f"not a VOT region: {text[:80]!r}") from None
        if len(vals) == 1:
            return nan4, "special"
        if len(vals) == 4:
            box = (vals[0], vals[1], vals[2], vals[3])
            kind = "rectangle"
        elif len(vals) >= 6 and len(vals) % 2 == 0:
            box = polygon_to_box(vals, polygon)
            kind = "polygon"
        else:
            raise ValueError(f"not a VOT region ({len(vals)} values): {text[:80]!r}")
    if not all(math.isfinite(v) for v in box) or box[2] <= 0 or box[3] <= 0:
        return nan4, kind
    return box, kind


def _vot_image_dir(seq_dir: Path) -> Path:
    color = seq_dir / "color"
    return color if color.is_dir() else seq_dir


def _is_vot_seq(d: Path) -> bool:
    return (
        (d / "groundtruth.txt").is_file()
        and not (d / GT_FILE).is_file()
        and not any((d / m).is_file() for m in _GOT_MARKERS)
        and _has_images(_vot_image_dir(d))
    )


def _load_vot(seq_dir: Path, polygon: Literal["minmax", "area"] = "minmax") -> Sequence:
    name = seq_dir.name
    what = f"VOT sequence {name}"
    gt_file = seq_dir / "groundtruth.txt"
    img_dir = _vot_image_dir(seq_dir)
    lines = [ln for ln in gt_file.read_text(encoding="utf-8-sig").splitlines() if ln.strip()]
    boxes = np.empty((len(lines), 4), dtype=np.float64)
    kinds: set[str] = set()
    for i, line in enumerate(lines):
        try:
            box, kind = parse_vot_region(line, polygon)
        except ValueError as exc:
            raise LayoutError(f"{gt_file}:{i + 1}: {exc}") from None
        boxes[i] = box
        kinds.add(kind)
    images = _images_in(img_dir)
    if not lines:
        raise LayoutError(f"{what}: {gt_file} holds no region")
    _check_count(what, len(images), img_dir, len(lines), gt_file)
    meta = {
        "layout": "vot",
        "absent_policy": "exclude",
        "region_kinds": tuple(sorted(kinds - {"special"})),
        "polygon_to_box": polygon,
    }
    return _make_sequence(name, images, boxes, _absent_rows(boxes), meta)


def _index_vot(root: Path) -> list[_Entry] | None:
    if _is_vot_seq(root):
        return [_Entry(root.name, partial(_load_vot, root))]
    base = root / "sequences" if (root / "sequences" / "list.txt").is_file() else root
    list_file = base / "list.txt"
    if list_file.is_file():
        names = _read_list(list_file)
        dirs = [base / n for n in names]
        if not any(_is_vot_seq(d) for d in dirs[:3]):
            return None
        missing = [n for n, d in zip(names, dirs) if not d.is_dir()]
        if missing:
            raise LayoutError(
                f"{base} is a broken VOT dataset: list.txt names {len(missing)} sequence(s) with "
                f"no folder ({', '.join(missing[:5])}{', ...' if len(missing) > 5 else ''})"
            )
    else:
        dirs = [d for d in _subdirs(base) if _is_vot_seq(d)]
    if not dirs:
        return None
    return [_Entry(d.name, partial(_load_vot, d)) for d in dirs]


# ---------------------------------------------------------------------- OTB
def _index_otb(root: Path) -> list[_Entry] | None:
    if (root / "img").is_dir() and (root / GT_FILE).is_file():
        return [_Entry(root.name, partial(_load_otb, root))]
    if not root.is_dir():
        return None
    dirs = list_otb_sequences(root)
    if not dirs:
        return None
    return [_Entry(d.name, partial(_load_otb, d)) for d in dirs]


def _load_otb(path: Path) -> Sequence:
    seq = load_otb_sequence(path)
    assert seq.groundtruth is not None
    seq.meta.setdefault("layout", "otb")
    seq.meta.setdefault("absent", np.asarray(~np.all(np.isfinite(seq.groundtruth), axis=1)))
    seq.meta.setdefault("absent_policy", "exclude")
    seq.meta.setdefault("first_frame_only", False)
    return seq


# ---------------------------------------------------------------------- public API
_INDEXERS: dict[str, Callable[[Path], list[_Entry] | None]] = {
    # Order matters for detection: the most specific folder structures first.
    "uav123": partial(_index_uav, "uav123"),
    "uav123_10fps": partial(_index_uav, "uav123_10fps"),
    "uav20l": partial(_index_uav, "uav20l"),  # found when the release has no anno/UAV123
    "trackingnet": _index_trackingnet,
    "got10k": _index_got10k,
    "lasot": _index_lasot,
    "vot": _index_vot,
    "dtb70": _index_dtb70,
    "otb": _index_otb,
}
# Detection asks DTB70 for more than its (OTB-like) structure; see _looks_dtb70.
_DETECTORS: dict[str, Callable[[Path], list[_Entry] | None]] = {
    **_INDEXERS,
    "dtb70": partial(_index_dtb70, detecting=True),
}


def _normalize_layout(layout: str) -> str:
    key = layout.strip().lower()
    key = _ALIASES.get(key, key)
    if key not in _INDEXERS:
        raise ValueError(f"unknown layout {layout!r}; choose one of {', '.join(LAYOUTS)}")
    return key


def _root(path: str | os.PathLike[str]) -> Path:
    p = Path(path).expanduser()
    if not p.exists():
        raise FileNotFoundError(f"dataset folder not found: {p}")
    if not p.is_dir():
        raise LayoutError(f"{p} is a file, not a dataset folder")
    return p


def _not_a(p: Path, layout: str) -> LayoutError:
    hint = ""
    for key, index in _DETECTORS.items():
        try:
            found = key != layout and index(p)
        except LayoutError:
            found = False
        if found:
            hint = f"; it looks like a {_TITLES[key]} dataset (layout {key!r})"
            break
    return LayoutError(
        f"{p} is not a {_TITLES[layout]} dataset: expected {_EXPECTED[layout]}{hint}"
    )


def _entries(path: str | os.PathLike[str], layout: str | None) -> tuple[str, list[_Entry]]:
    p = _root(path)
    if layout is not None:
        key = _normalize_layout(layout)
        found = _INDEXERS[key](p)
        if not found:
            raise _not_a(p, key)
        return key, found
    for key, index in _DETECTORS.items():
        found = index(p)
        if found:
            return key, found
    lines = "\n".join(f"  {_TITLES[k]}: {_EXPECTED[k]}" for k in _INDEXERS)
    raise LayoutError(f"{p} is not a tracking dataset in any known layout; expected one of\n{lines}")


def detect_layout(path: str | os.PathLike[str]) -> str:
    """Name the layout of a dataset folder.

    Parameters
    ----------
    path:
        Dataset root, a split or chunk folder (GOT-10k ``val/``, TrackingNet ``TRAIN_0/``), a
        LaSOT class folder, or a single sequence folder.

    Returns
    -------
    str
        One of :data:`LAYOUTS`.  Only folders are listed: no annotation or image is read.

    Raises
    ------
    FileNotFoundError
        If ``path`` does not exist.
    LayoutError
        If the folder matches no layout (the message lists what each layout expects), or it
        matches one but is broken in a way seen while listing (GOT-10k or VOT ``list.txt``
        naming missing folders, several GOT-10k splits without ``val/``).
    """
    return _entries(path, None)[0]


def list_layout(path: str | os.PathLike[str], layout: str | None = None) -> list[str]:
    """Names of the sequences of a dataset, without reading any annotation or image.

    Parameters
    ----------
    path:
        As for :func:`detect_layout`.
    layout:
        Layout name (see :data:`LAYOUTS`; ``"got-10k"`` and ``"uav"`` are accepted too), or
        ``None`` to detect it.

    Returns
    -------
    list of str
        In ``list.txt`` order where the benchmark has one, else in natural name order.
    """
    return [e.name for e in _entries(path, layout)[1]]


def _chosen(
    path: str | os.PathLike[str], layout: str | None, sequences: AbcSequence[str] | None
) -> list[_Entry]:
    key, entries = _entries(path, layout)
    if sequences is None:
        return entries
    names = [sequences] if isinstance(sequences, str) else list(sequences)
    by_name = {e.name: e for e in entries}
    missing = [n for n in names if n not in by_name]
    if missing:
        avail = sorted(by_name, key=natural_key)
        shown = ", ".join(avail[:10]) + (f", ... ({len(avail)} in all)" if len(avail) > 10 else "")
        raise LayoutError(
            f"sequence(s) not in the {_TITLES[key]} dataset {path}: {', '.join(missing)}; "
            f"available: {shown}"
        )
    return [by_name[n] for n in names]


def load_layout(
    path: str | os.PathLike[str],
    layout: str | None = None,
    sequences: AbcSequence[str] | None = None,
) -> list[Sequence]:
    """Load the sequences of a benchmark dataset.

    Parameters
    ----------
    path:
        As for :func:`detect_layout`.
    layout:
        Layout name, or ``None`` to detect it with :func:`detect_layout`.
    sequences:
        Names to load, in this order (a single string is one name); ``None`` loads every
        sequence.  Only the chosen sequences' annotation files are read.

    Returns
    -------
    list of Sequence
        Image-backed sequences (no image is decoded here), ground truth with ``nan`` rows on
        absent frames, and ``meta`` as described in the module documentation.  Loading costs
        folder listings and annotation parsing, roughly 10 ms per 1 000 frames: for all of LaSOT
        (3.5 M frames) prefer :func:`iter_layout`, which loads one sequence at a time.

    Raises
    ------
    FileNotFoundError
        If ``path`` does not exist.
    LayoutError
        If the folder is not a dataset in ``layout`` (or in any layout), a requested sequence is
        missing, or a sequence is broken: image and annotation counts differ, a flag file has the
        wrong length, or an annotation line cannot be parsed.
    ValueError
        If ``layout`` is not a known name.
    """
    return [e.load() for e in _chosen(path, layout, sequences)]


def iter_layout(
    path: str | os.PathLike[str],
    layout: str | None = None,
    sequences: AbcSequence[str] | None = None,
) -> Iterator[Sequence]:
    """Like :func:`load_layout`, but load each sequence only when the iteration reaches it.

    The dataset is detected and listed (and requested names checked) before the first sequence
    is yielded; a broken sequence raises :class:`LayoutError` when it is reached.
    """
    for entry in _chosen(path, layout, sequences):
        yield entry.load()
