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

Each benchmark family has its own module here, which gives its folder conventions and the
public sources each was checked against (real datasets were not available where the layouts
were written; they were rebuilt from these sources and tested on generated data):
:mod:`~wmiltrack.data.layouts.otb`, :mod:`~wmiltrack.data.layouts.lasot`,
:mod:`~wmiltrack.data.layouts.got10k`, :mod:`~wmiltrack.data.layouts.uav` (UAV123,
UAV123_10fps, UAV20L), :mod:`~wmiltrack.data.layouts.dtb70`,
:mod:`~wmiltrack.data.layouts.trackingnet` and :mod:`~wmiltrack.data.layouts.vot`. Each builds a
:class:`Layout` (how a folder is detected, indexed and loaded) and registers it with
:func:`register_layout` in the one registry that the entry points read: a new benchmark is a
new module and its import line below.

A dataset whose image count and annotation count differ is refused with both counts in the error.
"""

from __future__ import annotations

# Each family registers its layouts when imported, in this order (that of LAYOUTS, and of the
# layouts' names in messages); detection has its own order (Layout.order). One line a benchmark.
# isort: off
from . import otb as otb
from . import lasot as lasot
from . import got10k as got10k
from . import uav as uav
from . import trackingnet as trackingnet
from . import vot as vot
from . import dtb70 as dtb70

# isort: on
from .registry import (
    LAYOUT_REGISTRY,
    Entry,
    Layout,
    LayoutError,
    detect_layout,
    iter_layout,
    list_layout,
    load_layout,
    register_layout,
)
from .uav import parse_config_seqs
from .vot import parse_vot_region, polygon_to_box

__all__ = [
    "LAYOUTS",
    "Entry",
    "Layout",
    "LayoutError",
    "detect_layout",
    "iter_layout",
    "list_layout",
    "load_layout",
    "parse_config_seqs",
    "parse_vot_region",
    "polygon_to_box",
    "register_layout",
]

LAYOUTS = tuple(LAYOUT_REGISTRY)
"""The built-in layout names, accepted by :func:`load_layout` (``layout=``) and returned by
:func:`detect_layout` (with any layout registered later)."""
