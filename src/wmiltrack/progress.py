"""Progress bars for long runs (tqdm on standard error), switched off by an environment variable."""

from __future__ import annotations

import os
from collections.abc import Iterable
from typing import TypeVar

from tqdm import tqdm

__all__ = ["NO_PROGRESS_ENV", "progress"]

T = TypeVar("T")

NO_PROGRESS_ENV = "WMILTRACK_NO_PROGRESS"
"""Set to anything but ``""``, ``0``, ``false``, ``no`` or ``off`` to turn progress bars off
(CI logs, scripts that parse standard error)."""


def progress(iterable: Iterable[T], total: int | None = None, desc: str = "", *,
             enabled: bool | None = None, delay: float = 0.5) -> tqdm[T]:
    """``tqdm(iterable)`` with wmiltrack's defaults: off when :data:`NO_PROGRESS_ENV` is set
    (unless ``enabled`` forces it), slow redraws so that logs stay short, and nothing drawn in
    the first ``delay`` seconds, so that a run that stops at once (a bad input) shows its error
    alone, without a bar before it."""
    if enabled is None:
        enabled = os.environ.get(NO_PROGRESS_ENV, "").strip().lower() in ("", "0", "false", "no", "off")
    return tqdm(iterable, total=total, desc=desc, disable=not enabled, mininterval=0.5,
                dynamic_ncols=True, leave=True, delay=delay)
