"""**OTB** ``<root>/<Seq>/img/`` + ``groundtruth_rect.txt``, loaded by
:func:`wmiltrack.data.sequences.load_otb_sequence` (which decodes each sequence's first image to
fail early, the one layout that opens an image while loading). Detected last: DTB70 shares its
structure, and every other layout's is more specific."""

from __future__ import annotations

from functools import partial
from pathlib import Path

import numpy as np

from ..sequences import GT_FILE, Sequence, list_otb_sequences, load_otb_sequence
from .registry import Entry, Layout, register_layout


def _load_otb(path: Path) -> Sequence:
    seq = load_otb_sequence(path)
    assert seq.groundtruth is not None
    seq.meta.setdefault("layout", "otb")
    seq.meta.setdefault("absent", np.asarray(~np.all(np.isfinite(seq.groundtruth), axis=1)))
    seq.meta.setdefault("absent_policy", "exclude")
    seq.meta.setdefault("first_frame_only", False)
    return seq


def _index_otb(root: Path) -> list[Entry] | None:
    if (root / "img").is_dir() and (root / GT_FILE).is_file():
        return [Entry(root.name, partial(_load_otb, root))]
    if not root.is_dir():
        return None
    dirs = list_otb_sequences(root)
    if not dirs:
        return None
    return [Entry(d.name, partial(_load_otb, d)) for d in dirs]


OTB = register_layout(
    Layout(
        name="otb",
        title="OTB",
        expected="sequence folders <Seq>/img/*.jpg with <Seq>/groundtruth_rect.txt, or one such folder",
        index=_index_otb,
        aliases=("otb100", "otb2015"),
        order=90,
    )
)
