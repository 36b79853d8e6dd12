"""**GOT-10k** ``<root>/{train,val,test}/list.txt`` and ``<split>/GOT-10k_Val_000001/00000001.jpg``
with ``groundtruth.txt``, ``absence.label``, ``cover.label`` (one value per line),
``meta_info.ini`` (got10k-toolkit ``got10k/datasets/got10k.py``).  The toolkit's evaluation
(``got10k/experiments/got10k.py``, ``report``) skips the first frame and keeps only frames with
``cover > 0``; here a frame is absent when ``absence.label`` is 1 or ``cover.label`` is 0, and
such frames are excluded (``absent_policy = "exclude"``).  The test split's ``groundtruth.txt``
holds the first box only.  Pointing at the root picks ``val`` when present (the split with ground
truth that the toolkit evaluates), or the only split there is.  ``meta["resolution"]`` is read from
``meta_info.ini`` (the toolkit clips boxes to it before computing overlaps).  Scoring:
:mod:`wmiltrack.eval.got10k_metrics`.
"""

from __future__ import annotations

import re
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

from ..sequences import Sequence
from .files import (
    BoolArray,
    check_flags,
    first_frame_only,
    has_images,
    images_in,
    make_sequence,
    read_box_file,
    read_flags,
    read_list,
    subdirs,
)
from .registry import Entry, Layout, LayoutError, register_layout

__all__ = ["GOT10K", "SEQUENCE_MARKERS"]

_GOT_SPLITS = ("train", "val", "test")
#: Files that only a GOT-10k sequence folder holds (VOT's detection refuses folders with them).
SEQUENCE_MARKERS = ("absence.label", "cover.label", "meta_info.ini")


def _is_got_seq(d: Path) -> bool:
    return (
        (d / "groundtruth.txt").is_file()
        and (d.name.startswith("GOT-10k_") or any((d / m).is_file() for m in SEQUENCE_MARKERS))
    )


def _parse_resolution(ini: Path) -> tuple[int, int] | None:
    for line in ini.read_text(encoding="utf-8-sig", errors="replace").splitlines():
        key, _, value = line.partition(":")
        if key.strip() == "resolution":
            nums = re.findall(r"\d+", value)
            if len(nums) == 2:
                return (int(nums[0]), int(nums[1]))
    return None


def _absent_from_labels(what: str, seq_dir: Path, n: int, meta: dict[str, Any]) -> BoolArray:
    """Frames ``absence.label`` marks absent or ``cover.label`` marks fully covered; the files
    read go to ``meta["absent_sources"]``, the cover values to ``meta["cover"]``."""
    absent = np.zeros(n, dtype=bool)
    sources = []
    absence_file = seq_dir / "absence.label"
    if absence_file.is_file():
        flags = read_flags(absence_file)
        check_flags(what, flags, absence_file, n)
        absent |= flags != 0
        sources.append("absence.label")
    cover_file = seq_dir / "cover.label"
    if cover_file.is_file():
        cover = read_flags(cover_file)
        check_flags(what, cover, cover_file, n)
        absent |= cover <= 0
        sources.append("cover.label")
        meta["cover"] = cover
    meta["absent_sources"] = tuple(sources)
    return absent


def _load_got10k(seq_dir: Path, split: str | None) -> Sequence:
    name = seq_dir.name
    what = f"GOT-10k sequence {name}"
    gt_file = seq_dir / "groundtruth.txt"
    gt = read_box_file(gt_file)
    images = images_in(seq_dir)
    padded = first_frame_only(what, images, seq_dir, gt, gt_file)
    meta: dict[str, Any] = {"layout": "got10k", "absent_policy": "exclude", "split": split}
    if padded is not None:
        absent = np.zeros(len(images), dtype=bool)
        meta["first_frame_only"] = True
        gt = padded
    else:
        absent = _absent_from_labels(what, seq_dir, len(gt), meta)
    ini = seq_dir / "meta_info.ini"
    if ini.is_file():
        res = _parse_resolution(ini)
        if res is not None:
            meta["resolution"] = res
    return make_sequence(name, images, gt, absent, meta)


def _got_split_entries(split_dir: Path, split: str | None) -> list[Entry] | None:
    list_file = split_dir / "list.txt"
    if list_file.is_file():
        names = read_list(list_file)
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
        dirs = [d for d in subdirs(split_dir) if _is_got_seq(d)]
        if not dirs:
            return None
    return [Entry(d.name, partial(_load_got10k, d, split)) for d in dirs]


def _index_got10k(root: Path) -> list[Entry] | None:
    if _is_got_seq(root) and has_images(root):
        return [Entry(root.name, partial(_load_got10k, root, None))]
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


GOT10K = register_layout(
    Layout(
        name="got10k",
        title="GOT-10k",
        expected="train/, val/ or test/ split folders, or a split folder holding list.txt and "
        "sequence folders with images, groundtruth.txt and absence.label/cover.label/meta_info.ini",
        index=_index_got10k,
        aliases=("got-10k", "got_10k"),
        order=30,
    )
)
