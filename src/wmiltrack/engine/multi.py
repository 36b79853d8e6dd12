"""Several targets in one video: one :class:`~wmiltrack.Tracker` per target, updated together.

Target ``i`` (the ``i``-th successful :meth:`MultiTracker.add`) runs exactly the tracker
``Tracker(variant, seed=seed + i)`` would, so its boxes are those of a single tracker started on
the same frame with the same box. What the targets share is the per-frame work that does not
depend on the target: the frame is checked and converted once; one integral image is built over
the union of the targets' search regions when that takes less time than their separate tables,
which the threads build in parallel (many or close targets: up to the whole frame), and every
target reads it, with the same result as its own table; and the targets' calls into the
compiled core are made together (for a paper preset one call a frame for all targets, else one
per step of the frame), which spreads them over ``threads`` threads with the GIL released
(:func:`wmiltrack.engine.tracker.update_many`): the Python part of each target's step runs in
the calling thread, the core's part in parallel.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np

from .. import _core
from .frames import as_frame, frame_size
from .params import Params
from .result import TrackResult
from .tracker import Tracker, update_many

__all__ = ["MultiTracker"]


class MultiTracker:
    """Track several objects in the same frames.

    Parameters
    ----------
    variant : str
        Preset of every target, as for :class:`~wmiltrack.Tracker` (``"rcwmil"``, ...).
    seed : int
        Target ``i`` uses seed ``seed + i``.
    threads : int, optional
        Threads for the targets' core work in :meth:`update`; ``None`` = one per core
        (``os.cpu_count()``), ``1`` = all in the calling thread.
    share : {"auto", "always", "never"}
        One integral image for all targets: when that takes less time than the targets'
        separate ones (``"auto"``: the union covers fewer pixels than the separate regions
        divided among the threads that build them), always, or never. Boxes are the same
        either way.
    params : Params, optional
        Start from these parameters instead of the preset's defaults.
    **overrides
        Any :class:`~wmiltrack.Params` field, applied to every target.

    Examples
    --------
    >>> mt = MultiTracker("rcwmil", seed=0)           # doctest: +SKIP
    >>> a = mt.add(frame0, (10, 20, 40, 40))           # doctest: +SKIP
    >>> b = mt.add(frame0, (200, 80, 32, 64))          # doctest: +SKIP
    >>> results = mt.update(frame1)                    # {0: TrackResult, 1: TrackResult}
    >>> mt.remove(a)                                   # doctest: +SKIP

    One ``MultiTracker`` must not be used from two threads at once (``RuntimeError``).
    """

    def __init__(self, variant: str = "rcwmil", *, seed: int = 0, threads: int | None = None,
                 share: str = "auto", params: Params | None = None, **overrides: Any) -> None:
        if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
            raise ValueError(f"seed must be a non-negative int, got {seed!r}")
        if threads is not None and (isinstance(threads, bool) or not isinstance(threads, int)
                                    or threads < 1):
            raise ValueError(f"threads must be None or an int >= 1, got {threads!r}")
        if share not in ("auto", "always", "never"):
            raise ValueError(f"share must be 'auto', 'always' or 'never', got {share!r}")
        self._share = share
        self._shared = _core.IntegralImage()
        self.last_shared = False
        """Whether the last :meth:`update` built one integral image for all targets."""
        # Validate the preset and overrides now, not at the first add().
        self._params = (Params.for_variant(variant, **overrides) if params is None
                        else params.replace(**overrides) if overrides else params)
        self._seed = int(seed)
        self._threads = threads if threads is not None else (os.cpu_count() or 1)
        self._targets: dict[int, Tracker] = {}
        self._next_id = 0
        self._frame_wh: tuple[int, int] | None = None  # the live targets' frame size

    # -- public API ------------------------------------------------------------------------
    @property
    def params(self) -> Params:
        """The parameters every target uses (frozen)."""
        return self._params

    @property
    def ids(self) -> list[int]:
        """Ids of the live targets, in the order they were added."""
        return list(self._targets)

    def __len__(self) -> int:
        return len(self._targets)

    def __contains__(self, target_id: object) -> bool:
        return target_id in self._targets

    def add(self, frame: np.ndarray, box: Any) -> int:
        """Start tracking the object in ``box = (x, y, w, h)`` of ``frame``; returns its id.

        Ids are 0, 1, 2, ... in the order of successful calls. A bad box or frame raises the
        same ``ValueError``/``TypeError`` as :meth:`Tracker.init` and uses up no id; the other
        targets are not affected. All targets follow one video, so a frame of another size than
        the live targets' is a ``ValueError`` (every later :meth:`update` would fail for one
        side or the other).
        """
        img = as_frame(frame)
        wh = frame_size(img)
        if self._targets and self._frame_wh is not None and wh != self._frame_wh:
            raise ValueError(
                f"frame is {wh[0]}x{wh[1]} but the live targets were started on "
                f"{self._frame_wh[0]}x{self._frame_wh[1]} frames: all targets of a MultiTracker "
                "follow one video (use a MultiTracker per video)")
        tracker = Tracker(params=self._params, seed=self._seed + self._next_id)
        tracker.init(img, box)
        target_id = self._next_id
        self._targets[target_id] = tracker
        self._frame_wh = wh
        self._next_id += 1
        return target_id

    def remove(self, target_id: int) -> None:
        """Stop tracking one target; an unknown id is a ``KeyError``."""
        if target_id not in self._targets:
            raise KeyError(f"no live target with id {target_id!r}; live ids: {self.ids}")
        del self._targets[target_id]

    def update(self, frame: np.ndarray) -> dict[int, TrackResult]:
        """Locate every live target in the next frame; ``{id: TrackResult}``.

        The frame is checked once, before any target moves: a bad frame, or one of another size
        than the targets started on, raises as :meth:`Tracker.update` does and changes no
        target. A target whose update still fails does not stop the others: its error is
        raised after all targets have been updated, as a ``ValueError`` naming the target.
        """
        img = as_frame(frame)
        items = list(self._targets.items())
        if not items:
            return {}
        wh = frame_size(img)
        if wh != self._frame_wh:
            assert self._frame_wh is not None
            raise ValueError(
                f"frame size changed from {self._frame_wh[0]}x{self._frame_wh[1]} to "
                f"{wh[0]}x{wh[1]}; no target was moved (remove the targets and add them again "
                "on frames of the new size)")
        trackers = [t for _, t in items]
        shared = self._prepare(img, trackers)
        # Each target runs its own frame step; their calls into the core go together, on up
        # to `threads` threads with the GIL released once per step.
        outcomes = update_many(trackers, img, integral=shared, threads=self._threads)
        for outcome in outcomes:
            if isinstance(outcome, RuntimeError):
                raise outcome
        results: dict[int, TrackResult] = {}
        failed: list[str] = []
        for (target_id, _), outcome in zip(items, outcomes):
            if isinstance(outcome, Exception):
                failed.append(f"target {target_id}: {outcome}")
            else:
                results[target_id] = outcome
        if failed:
            raise ValueError("; ".join(failed))
        return results

    def close(self) -> None:
        """Release what the tracker holds between frames: nothing of its own. The core's
        worker threads belong to the process (every MultiTracker and ``update_many`` call
        shares them): after each call they watch for the next one for up to 0.2 ms, on their
        own cores, then sleep. Kept so that ``with MultiTracker(...)`` and ``close()`` still
        work."""

    def __enter__(self) -> MultiTracker:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __repr__(self) -> str:
        return (f"MultiTracker({self._params.variant!r}, seed={self._seed}, "
                f"targets={self.ids}, threads={self._threads})")

    # -- internals -------------------------------------------------------------------------
    def _prepare(self, img: np.ndarray, trackers: list[Tracker]) -> _core.IntegralImage | None:
        """One luma integral image over the union of the targets' regions, or None when the
        targets are better served by their own (their regions, divided among the threads,
        cover fewer pixels than the union; or other channels)."""
        self.last_shared = False
        if self._share == "never" or len(trackers) < 2 or any(t.uses_channels for t in trackers):
            return None
        fh, fw = img.shape[:2]
        rects = []
        for t in trackers:
            x, y, w, h = t.search_region()
            x0, y0, x1, y1 = max(x, 0), max(y, 0), min(x + w, fw), min(y + h, fh)
            if x1 > x0 and y1 > y0:
                rects.append((x0, y0, x1, y1))
        if len(rects) < 2:
            return None
        ux0, uy0 = min(r[0] for r in rects), min(r[1] for r in rects)
        ux1, uy1 = max(r[2] for r in rects), max(r[3] for r in rects)
        # The shared table is built in this thread alone; separate ones are built by each
        # target's own core call, spread over the threads: compare what each costs in time.
        separate = sum((r[2] - r[0]) * (r[3] - r[1]) for r in rects)
        workers = min(self._threads, len(rects))
        if self._share == "auto" and (ux1 - ux0) * (uy1 - uy0) * workers > separate:
            return None
        self._shared.compute(img, (ux0, uy0, ux1 - ux0, uy1 - uy0))
        self.last_shared = True
        return self._shared
