"""**DTB70** ``<root>/<seq>/img/00001.jpg`` and ``<seq>/groundtruth_rect.txt`` (comma-separated
``x,y,w,h``, one line per image: got10k-toolkit ``got10k/datasets/dtb70.py``).  The structure is
OTB's, so detection calls a folder DTB70 only when every sequence's first frame is
``img/00001.jpg`` (five digits; OTB uses four but for ``Board``) and the folder (or its parent)
is named ``*DTB70*`` or at least half the sequences bear DTB70's names; ``layout="dtb70"``
loads any such folder.  ``absent_policy = "exclude"``.
"""

from __future__ import annotations

from functools import partial
from pathlib import Path

from ..sequences import GT_FILE, Sequence
from .files import absent_rows, check_count, images_in, make_sequence, read_box_file, subdirs
from .registry import Entry, Layout, LayoutError, register_layout

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
    return [d for d in subdirs(root) if _is_dtb70_seq(d)]


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
    gt = read_box_file(gt_file)
    images = images_in(img_dir)
    if len(gt) == 0:
        raise LayoutError(f"{what}: {gt_file} holds no box")
    check_count(what, len(images), img_dir, len(gt), gt_file)
    meta = {"layout": "dtb70", "absent_policy": "exclude"}
    return make_sequence(name, images, gt, absent_rows(gt), meta)


def _index_dtb70(root: Path, detecting: bool = False) -> list[Entry] | None:
    dirs = _dtb70_dirs(root)
    if not dirs or (detecting and not _looks_dtb70(root, dirs)):
        return None
    return [Entry(d.name, partial(_load_dtb70, d)) for d in dirs]


DTB70 = register_layout(
    Layout(
        name="dtb70",
        title="DTB70",
        expected="sequence folders <seq>/img/00001.jpg with <seq>/groundtruth_rect.txt, or one such "
        "folder (detected as DTB70 rather than OTB when the folder is named DTB70 or most "
        "sequences bear DTB70's names)",
        index=_index_dtb70,
        # Detection asks for more than the (OTB-like) structure; see _looks_dtb70.
        detect=partial(_index_dtb70, detecting=True),
        aliases=("dtb", "dtb-70"),
        order=60,
    )
)
