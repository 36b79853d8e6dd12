"""**VOT** ``<root>/list.txt`` and ``<seq>/color/00000001.jpg`` (VOT2017+) or ``<seq>/00000001.jpg``
(older editions), ``groundtruth.txt`` with one region per line (got10k-toolkit
``got10k/datasets/vot.py``; a VOT toolkit workspace's ``sequences/`` folder is found too).  Region
lines follow the VOT toolkit's parser (``votchallenge/toolkit``, ``vot/region/io.py``): 4 values a
rectangle, an even number > 4 a polygon, ``m<x0>,<y0>,<w>,<h>,<RLE...>`` a mask, a single value
a special code.  Polygons become the axis-aligned min/max box (pytracking
``pytracking/evaluation/votdataset.py``; got10k-toolkit's ``VOT._corner2rect`` uses an
area-preserving box instead, available as ``polygon_to_box(..., mode="area")``), masks the box of
their pixels.  Special codes, ``nan`` values and empty regions (``0,0,0,0``, empty masks) are
absent frames (``absent_policy = "exclude"``: VOT's own measures are not OPE figures).
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable
from functools import partial
from pathlib import Path
from typing import Literal

import numpy as np

from ..sequences import GT_FILE, Sequence
from .files import absent_rows, check_count, has_images, images_in, make_sequence, read_list, subdirs
from .got10k import SEQUENCE_MARKERS
from .registry import Entry, Layout, LayoutError, register_layout

__all__ = ["VOT", "parse_vot_region", "polygon_to_box"]

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
        and not any((d / m).is_file() for m in SEQUENCE_MARKERS)
        and has_images(_vot_image_dir(d))
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
    images = images_in(img_dir)
    if not lines:
        raise LayoutError(f"{what}: {gt_file} holds no region")
    check_count(what, len(images), img_dir, len(lines), gt_file)
    meta = {
        "layout": "vot",
        "absent_policy": "exclude",
        "region_kinds": tuple(sorted(kinds - {"special"})),
        "polygon_to_box": polygon,
    }
    return make_sequence(name, images, boxes, absent_rows(boxes), meta)


def _index_vot(root: Path) -> list[Entry] | None:
    if _is_vot_seq(root):
        return [Entry(root.name, partial(_load_vot, root))]
    base = root / "sequences" if (root / "sequences" / "list.txt").is_file() else root
    list_file = base / "list.txt"
    if list_file.is_file():
        names = read_list(list_file)
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
        dirs = [d for d in subdirs(base) if _is_vot_seq(d)]
    if not dirs:
        return None
    return [Entry(d.name, partial(_load_vot, d)) for d in dirs]


VOT = register_layout(
    Layout(
        name="vot",
        title="VOT",
        expected="list.txt and <seq>/color/*.jpg (or <seq>/*.jpg) with a region groundtruth.txt "
        "per sequence, or one such sequence folder",
        index=_index_vot,
        order=50,
    )
)
