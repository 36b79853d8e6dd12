"""**LaSOT** ``<root>/<class>/<class>-<N>/img/00000001.jpg``, ``groundtruth.txt`` (``x,y,w,h`` per
line), ``full_occlusion.txt`` and ``out_of_view.txt`` (one comma-separated 0/1 line).  A frame is
absent when either flag is 1 (pytracking ``pytracking/evaluation/lasotdataset.py``:
``target_visible = full_occlusion == 0 and out_of_view == 0``).  The official MATLAB toolkit
(``HengLan/LaSOT_Evaluation_Toolkit``, ``utils/calc_seq_err_robust.m`` and ``utils/eval_tracker.m``)
removes absent frames from the scored frames but still divides by the full frame count, so an
absent frame counts as a failure at every threshold; pytracking
(``pytracking/analysis/extract_results.py``, ``exclude_invalid_frames=False``) does the same.
Hence ``absent_policy = "fail"``.  The root may also be one class folder, a flat folder of
``<class>-<N>`` sequences, or a single sequence folder.
"""

from __future__ import annotations

import re
from functools import partial
from pathlib import Path

import numpy as np

from ..sequences import Sequence, natural_key
from .files import check_count, check_flags, images_in, make_sequence, read_box_file, read_flags, subdirs
from .registry import Entry, Layout, LayoutError, register_layout

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
    gt = read_box_file(gt_file)
    images = images_in(img_dir)
    if len(gt) == 0:
        raise LayoutError(f"{what}: {gt_file} holds no box")
    check_count(what, len(images), img_dir, len(gt), gt_file)
    absent = np.zeros(len(gt), dtype=bool)
    sources = []
    for flag_name in ("full_occlusion.txt", "out_of_view.txt"):
        flag_file = seq_dir / flag_name
        if flag_file.is_file():
            flags = read_flags(flag_file)
            check_flags(what, flags, flag_file, len(gt))
            absent |= flags != 0
            sources.append(flag_name)
    meta = {
        "layout": "lasot",
        "absent_policy": "fail",
        "absent_sources": tuple(sources),
        "category": _LASOT_NAME.match(name).group(1),  # type: ignore[union-attr]
    }
    return make_sequence(name, images, gt, absent, meta)


def _index_lasot(root: Path) -> list[Entry] | None:
    if _is_lasot_seq(root):
        seq_dirs = [root]
    else:
        children = subdirs(root)
        seq_dirs = [d for d in children if _is_lasot_seq(d)]  # a class folder or a flat folder
        if not seq_dirs:
            seq_dirs = [
                s
                for c in children
                for s in subdirs(c)
                if s.name.startswith(c.name + "-") and _is_lasot_seq(s)
            ]
    if not seq_dirs:
        return None
    seq_dirs.sort(key=lambda p: natural_key(p.name))
    return [Entry(d.name, partial(_load_lasot, d)) for d in seq_dirs]


LASOT = register_layout(
    Layout(
        name="lasot",
        title="LaSOT",
        expected="<class>/<class>-<N>/img/*.jpg with groundtruth.txt next to img/ "
        "(or a class folder, or one <class>-<N> folder)",
        index=_index_lasot,
        order=40,
    )
)
