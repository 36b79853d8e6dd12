"""**TrackingNet** ``<root>/TRAIN_<k>/frames/<seq>/0.jpg ...`` and ``TRAIN_<k>/anno/<seq>.txt``;
``TEST/`` holds first-frame-only annotations (got10k-toolkit ``got10k/datasets/trackingnet.py``,
pytracking ``pytracking/evaluation/trackingnetdataset.py``: frames sorted by their integer name).
The root loads every ``TRAIN_<k>`` chunk present (or ``TEST`` when there is none); point at one
chunk folder to load only that one.
"""

from __future__ import annotations

import re
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

from ..sequences import Sequence, natural_key
from .files import absent_rows, first_frame_only, images_in, make_sequence, read_box_file, subdirs
from .registry import Entry, Layout, LayoutError, register_layout

_TN_CHUNK = re.compile(r"^(TRAIN_\d+|TEST)$")


def _is_tn_chunk(d: Path) -> bool:
    return (d / "anno").is_dir() and (d / "frames").is_dir()


def _load_trackingnet(chunk: Path, name: str) -> Sequence:
    what = f"TrackingNet sequence {chunk.name}/{name}"
    gt_file = chunk / "anno" / f"{name}.txt"
    img_dir = chunk / "frames" / name
    gt = read_box_file(gt_file)
    images = images_in(img_dir)
    if not images:
        raise LayoutError(f"{what}: no images in {img_dir}")
    padded = first_frame_only(what, images, img_dir, gt, gt_file)
    meta: dict[str, Any] = {"layout": "trackingnet", "absent_policy": "exclude", "chunk": chunk.name}
    if padded is not None:
        meta["first_frame_only"] = True
        return make_sequence(name, images, padded, np.zeros(len(images), dtype=bool), meta)
    return make_sequence(name, images, gt, absent_rows(gt), meta)


def _index_trackingnet(root: Path) -> list[Entry] | None:
    if _is_tn_chunk(root) and _TN_CHUNK.match(root.name):
        chunks = [root]
    else:
        found = [d for d in subdirs(root) if _TN_CHUNK.match(d.name) and _is_tn_chunk(d)]
        train = [d for d in found if d.name != "TEST"]
        chunks = train or found
        if not chunks and _is_tn_chunk(root):
            chunks = [root]  # a chunk folder under another name
    entries: list[Entry] = []
    seen: dict[str, str] = {}
    for chunk in chunks:
        for p in sorted((chunk / "anno").glob("*.txt"), key=lambda p: natural_key(p.name)):
            if p.stem in seen:
                raise LayoutError(
                    f"TrackingNet sequence {p.stem} is in both {seen[p.stem]} and {chunk.name}"
                )
            seen[p.stem] = chunk.name
            entries.append(Entry(p.stem, partial(_load_trackingnet, chunk, p.stem)))
    return entries or None


TRACKINGNET = register_layout(
    Layout(
        name="trackingnet",
        title="TrackingNet",
        expected="TRAIN_<k>/ or TEST/ chunk folders holding frames/<seq>/*.jpg and anno/<seq>.txt, "
        "or one such chunk folder",
        index=_index_trackingnet,
        aliases=("tracking-net",),
        order=20,
    )
)
