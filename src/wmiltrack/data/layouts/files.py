"""What every layout reads the same way: folder listings (names only, no image is decoded),
box and flag files, count checks, and the :class:`~wmiltrack.data.sequences.Sequence` a layout
builds (``nan`` ground-truth rows on absent frames, the common ``meta`` keys).

A layout module uses these so that each benchmark's module holds only what is its own: where its
files are, and how its annotations mark absent frames.
"""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..boxes import read_boxes
from ..sequences import IMAGE_EXTENSIONS, Sequence, natural_key
from .registry import LayoutError

__all__ = [
    "BoolArray",
    "Boxes",
    "absent_rows",
    "check_count",
    "check_flags",
    "first_frame_only",
    "frame_numbers",
    "has_images",
    "images_in",
    "make_sequence",
    "read_box_file",
    "read_flags",
    "read_list",
    "subdirs",
]

Boxes = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


def images_in(folder: Path) -> list[Path]:
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


def has_images(folder: Path) -> bool:
    """Whether ``folder`` holds at least one image file (stops at the first)."""
    if not folder.is_dir():
        return False
    with os.scandir(folder) as it:
        return any(
            e.is_file() and os.path.splitext(e.name)[1].lower() in IMAGE_EXTENSIONS for e in it
        )


def subdirs(folder: Path) -> list[Path]:
    """The folders in ``folder`` (hidden ones left out) in natural name order."""
    if not folder.is_dir():
        return []
    with os.scandir(folder) as it:
        dirs = [Path(e.path) for e in it if e.is_dir() and not e.name.startswith(".")]
    dirs.sort(key=lambda p: natural_key(p.name))
    return dirs


def read_box_file(path: Path) -> Boxes:
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


def read_flags(path: Path) -> NDArray[np.float64]:
    """Per-frame numbers written one per line or comma-separated on one line."""
    text = path.read_text(encoding="utf-8-sig")
    fields = [f for f in _FLAG_SPLIT.split(text) if f]
    try:
        return np.asarray([float(f) for f in fields], dtype=np.float64)
    except ValueError:
        raise LayoutError(f"{path}: expected one number per frame, found {text[:60]!r}") from None


def read_list(list_file: Path) -> list[str]:
    """The non-empty lines of a ``list.txt`` (sequence names), stripped, in file order."""
    return [line.strip() for line in list_file.read_text(encoding="utf-8-sig").splitlines() if line.strip()]


def check_count(what: str, n_images: int, img_dir: Path, n_boxes: int, gt_file: Path) -> None:
    """Refuse a sequence whose image and annotation counts differ, naming both."""
    if n_images != n_boxes:
        raise LayoutError(
            f"{what}: {n_images} images in {img_dir} but {n_boxes} boxes in {gt_file}; the "
            "annotation must have one line per frame (refusing to guess which frames it covers)"
        )


def check_flags(what: str, flags: NDArray[Any], path: Path, n: int) -> None:
    """Refuse a per-frame flag file with a value count other than the frame count."""
    if len(flags) != n:
        raise LayoutError(f"{what}: {path} has {len(flags)} values for {n} frames")


def absent_rows(gt: Boxes) -> BoolArray:
    """Rows that cannot be a target box: a ``nan`` or a non-positive width or height."""
    with np.errstate(invalid="ignore"):
        ok = np.all(np.isfinite(gt), axis=1) & (gt[:, 2] > 0) & (gt[:, 3] > 0)
    return np.asarray(~ok)


def make_sequence(
    name: str,
    images: list[Path],
    gt: Boxes,
    absent: BoolArray,
    meta: dict[str, Any],
) -> Sequence:
    """The image-backed sequence a layout returns: ``gt`` with ``nan`` on the ``absent`` rows,
    ``meta`` over the defaults ``absent`` and ``first_frame_only=False``."""
    gt = np.array(gt, dtype=np.float64, copy=True)
    gt[absent] = np.nan
    info = {"absent": np.asarray(absent, dtype=bool), "first_frame_only": False}
    info.update(meta)
    return Sequence(name=name, groundtruth=gt, paths=tuple(images), meta=info)


def first_frame_only(
    what: str, images: list[Path], img_dir: Path, gt: Boxes, gt_file: Path
) -> Boxes | None:
    """Pad a one-line (first frame only) annotation with ``nan`` rows; ``None`` if not that case."""
    if len(gt) == 1 and len(images) > 1:
        full = np.full((len(images), 4), np.nan)
        full[0] = gt[0]
        return full
    if len(gt) == 0:
        raise LayoutError(f"{what}: {gt_file} holds no box")
    check_count(what, len(images), img_dir, len(gt), gt_file)
    return None


def frame_numbers(images: list[Path]) -> dict[int, Path]:
    """Frame number (the last run of digits in the file name) -> image; the first wins."""
    out: dict[int, Path] = {}
    for p in images:
        digits = re.findall(r"\d+", p.stem)
        if digits:
            out.setdefault(int(digits[-1]), p)
    return out
