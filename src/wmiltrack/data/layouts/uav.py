"""**UAV123, UAV123_10fps, UAV20L** ``<root>/data_seq/<frames>/<folder>/000001.jpg`` and
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
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from functools import lru_cache, partial
from pathlib import Path

from ..sequences import Sequence, natural_key
from .files import absent_rows, check_count, frame_numbers, images_in, make_sequence, read_box_file
from .registry import Entry, Layout, LayoutError, register_layout

__all__ = ["UAV20L", "UAV123", "UAV123_10FPS", "UAV123_10FPS_SPLITS", "UAV123_SPLITS", "parse_config_seqs"]

# Annotation files covering a frame range of a shared image folder:
# name -> (folder under data_seq/<subset>, first frame, last frame), 1-based and inclusive.
# UAV123 (30 fps): got10k-toolkit got10k/datasets/uav123.json (agrees with pytracking's
# uavdataset.py and with the seqUAV123 table of the release's configSeqs.m).
UAV123_SPLITS: dict[str, tuple[str, int, int]] = {
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
UAV123_10FPS_SPLITS: dict[str, tuple[str, int, int]] = {
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
    gt = read_box_file(gt_file)
    if len(gt) == 0:
        raise LayoutError(f"{what}: {gt_file} holds no box")
    span, source = _uav_span(root, subset, name)
    folder_name = span[0] if span is not None else name
    img_dir = root / "data_seq" / subset.data / folder_name
    images = images_in(img_dir)
    if not images:
        raise LayoutError(f"{what}: no images in {img_dir}")
    if span is None:
        check_count(what, len(images), img_dir, len(gt), gt_file)
        frames, start, end = images, 1, len(gt)
    else:
        _, start, end = span
        if end - start + 1 != len(gt):
            raise LayoutError(
                f"{what}: {gt_file} has {len(gt)} boxes but the sequence is frames {start}-{end} "
                f"of {folder_name} ({end - start + 1} frames, from {source})"
            )
        by_number = frame_numbers(images)
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
    return make_sequence(name, frames, gt, absent_rows(gt), meta)


def _index_uav(subset: _UavSubset, root: Path) -> list[Entry] | None:
    r = _uav_root(root, subset)
    if r is None:
        return None
    names = sorted((p.stem for p in (r / "anno" / subset.anno).glob("*.txt")), key=natural_key)
    if not names:
        return None
    return [Entry(n, partial(_load_uav, r, subset, n)) for n in names]


def _uav_layout(subset: _UavSubset, title: str, expected: str, aliases: tuple[str, ...]) -> Layout:
    return register_layout(
        Layout(
            name=subset.layout,
            title=title,
            expected=expected,
            index=partial(_index_uav, subset),
            aliases=aliases,
            order=10,  # the most specific structure: asked first, in this order
        )
    )


UAV123 = _uav_layout(
    _UavSubset("uav123", "UAV123", "UAV123", UAV123_SPLITS),
    "UAV123",
    "data_seq/UAV123/<folder>/000001.jpg and anno/UAV123/<seq>.txt",
    ("uav",),
)
UAV123_10FPS = _uav_layout(
    _UavSubset("uav123_10fps", "UAV123_10fps", "UAV123_10fps", UAV123_10FPS_SPLITS),
    "UAV123_10fps",
    "data_seq/UAV123_10fps/<folder>/000001.jpg and anno/UAV123_10fps/<seq>.txt "
    "(configSeqs.m beside them gives each sequence's folder and frames)",
    ("uav123-10fps", "uav123_10", "uav10fps"),
)
# UAV20L annotates whole folders of the 30 fps release (configSeqs.m: startFrame 1). Detected
# when the release has no anno/UAV123 (a folder with both is UAV123).
UAV20L = _uav_layout(
    _UavSubset("uav20l", "UAV20L", "UAV123", {}),
    "UAV20L",
    "data_seq/UAV123/<seq>/000001.jpg and anno/UAV20L/<seq>.txt",
    ("uav-20l",),
)
