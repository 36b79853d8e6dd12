"""NanoTrack alone, as a peer tracker with wmiltrack's ``init``/``update`` interface
(``nanotrack:v2`` / ``nanotrack:v3`` of ``wmiltrack eval``): the network's published step
(:mod:`wmiltrack.networks.nanotrack`) on every frame, nothing else."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ..engine.frames import as_frame, clip_box
from ..engine.result import TrackResult
from ..networks.nanotrack import nanotrack_step
from ..networks.siamese import as_bgr

__all__ = ["NanoTracker"]


class NanoTracker:
    """NanoTrack alone, by its published tracking step: a box on every frame, its score the
    network's softmax at the chosen point; it never reports a lost target (``ok`` is always
    True).

    ``backbone``, ``head``: the model files (else found by
    :func:`wmiltrack.networks.files.nanotrack_files`); ``runtime``, ``threads``: as
    :func:`wmiltrack.networks.backends.load_backend`.
    """

    def __init__(self, version: str = "v3", *, backbone: str | Path | None = None,
                 head: str | Path | None = None, runtime: str = "auto", threads: int = 1) -> None:
        self.version = version
        self._step = nanotrack_step(version, backbone=backbone, head=head, runtime=runtime,
                                    threads=threads)

    @property
    def runtime(self) -> str:
        """The runtime that runs the network: ``"onnxruntime"`` or ``"opencv"``."""
        return self._step.network.runtime

    def init(self, frame: np.ndarray, box: Any) -> None:
        """Take the template from ``frame`` at ``box = (x, y, w, h)``."""
        img = as_bgr(as_frame(frame))
        x, y, w, h = clip_box(box, img.shape[1], img.shape[0])
        self._step.start(img, (float(x), float(y), float(w), float(h)))

    def update(self, frame: np.ndarray) -> TrackResult:
        """One tracking step: the new box and the network's score."""
        found = self._step.locate(as_bgr(as_frame(frame)))
        return TrackResult(found.box, found.score, True)
