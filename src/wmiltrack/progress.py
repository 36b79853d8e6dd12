"""A tiny dependency-free progress bar for long runs.

Example
-------
>>> for frame in progress(frames, desc="David"):  # doctest: +SKIP
...     tracker.update(frame)
David  37/150 [#####---------------]  24.5 it/s ETA 4s
"""

from __future__ import annotations

import math
import os
import sys
import time
from collections.abc import Iterable, Iterator
from typing import TextIO, TypeVar

__all__ = ["NO_PROGRESS_ENV", "format_duration", "progress"]

T = TypeVar("T")

NO_PROGRESS_ENV = "WMILTRACK_NO_PROGRESS"
"""Setting this environment variable (to anything but ``""``, ``0``, ``false``, ``no``, ``off``)
turns the progress display off by default."""

BAR_WIDTH = 20
TTY_INTERVAL = 0.1  # seconds between redraws on a terminal
PLAIN_STEP = 0.1  # fraction of the total between plain lines
PLAIN_INTERVAL = 10.0  # seconds between plain lines when the total is unknown

_now = time.monotonic  # replaced in tests


def format_duration(seconds: float) -> str:
    """Format a duration compactly: ``4s``, ``2m05s``, ``1h02m03s`` (``?`` if unknown).

    Parameters
    ----------
    seconds:
        Duration; negative, infinite or NaN values give ``"?"``.

    Returns
    -------
    str
    """
    if not math.isfinite(seconds) or seconds < 0:
        return "?"
    s = round(seconds)
    if s < 60:
        return f"{s}s"
    m, s = divmod(s, 60)
    if m < 60:
        return f"{m}m{s:02d}s"
    h, m = divmod(m, 60)
    return f"{h}h{m:02d}m{s:02d}s"


def _env_disabled() -> bool:
    value = os.environ.get(NO_PROGRESS_ENV)
    if value is None:
        return False
    return value.strip().lower() not in ("", "0", "false", "no", "off")


def _is_tty(file: TextIO) -> bool:
    try:
        return bool(file.isatty())
    except (AttributeError, ValueError, OSError):
        return False


def _line(desc: str, n: int, total: int | None, elapsed: float, done: bool) -> str:
    rate = n / elapsed if elapsed > 0 else 0.0
    head = f"{desc}  " if desc else ""
    rate_txt = f"{rate:.1f} it/s" if elapsed > 0 else "? it/s"
    if total is None or total <= 0:
        tail = f"in {format_duration(elapsed)}" if done else f"{format_duration(elapsed)}"
        return f"{head}{n} [{rate_txt}] {tail}"
    filled = min(BAR_WIDTH, int(BAR_WIDTH * n / total))
    bar = "#" * filled + "-" * (BAR_WIDTH - filled)
    width = len(str(total))
    if done:
        tail = f"in {format_duration(elapsed)}"
    else:
        eta = (total - n) / rate if rate > 0 else math.inf
        tail = f"ETA {format_duration(eta)}"
    return f"{head}{n:>{width}}/{total} [{bar}] {rate_txt} {tail}"


def progress(
    iterable: Iterable[T],
    total: int | None = None,
    desc: str = "",
    *,
    enabled: bool | None = None,
    file: TextIO | None = None,
) -> Iterator[T]:
    """Yield the items of ``iterable`` while showing progress on ``file``.

    The display reads ``desc  37/150 [#####---------------] 24.5 it/s ETA 4s`` and ends with
    ``in <elapsed>`` once the iteration finishes (or stops early).

    Parameters
    ----------
    iterable:
        Items to pass through unchanged.
    total:
        Expected number of items; taken from ``len(iterable)`` when omitted and available.
        Without it, only the count, rate and elapsed time are shown.
    desc:
        Label printed first.
    enabled:
        ``True``/``False`` to force the display on/off; ``None`` (default) shows it unless the
        environment variable ``WMILTRACK_NO_PROGRESS`` is set (see :data:`NO_PROGRESS_ENV`).
    file:
        Text stream to write to; ``None`` means ``sys.stderr`` at call time. On a terminal
        (``file.isatty()``) one line is redrawn in place (carriage return) at most ~10 times per
        second; otherwise plain lines are printed, at most one per 10 % of ``total`` (or one
        per 10 s when the total is unknown), plus a final line.

    Yields
    ------
    object
        The items of ``iterable``.
    """
    on = (not _env_disabled()) if enabled is None else enabled
    if not on:
        yield from iterable
        return
    out = sys.stderr if file is None else file
    if total is None:
        try:
            total = len(iterable)  # type: ignore[arg-type]
        except TypeError:
            total = None
    tty = _is_tty(out)
    start = _now()
    n = 0
    last_draw = start
    last_width = 0
    next_mark = 1  # plain mode: index of the next 10 % milestone to report

    def draw(done: bool) -> None:
        nonlocal last_draw, last_width
        now = _now()
        text = _line(desc, n, total, now - start, done)
        if tty:
            pad = " " * max(0, last_width - len(text))
            out.write("\r" + text + pad + ("\n" if done else ""))
            last_width = len(text)
        else:
            out.write(text + "\n")
        out.flush()
        last_draw = now

    try:
        if tty:
            draw(False)
        for item in iterable:
            yield item
            n += 1
            now = _now()
            if tty:
                if now - last_draw >= TTY_INTERVAL:
                    draw(False)
            elif total is not None and total > 0:
                if n < total and n >= math.ceil(total * PLAIN_STEP * next_mark - 1e-9):
                    while n >= math.ceil(total * PLAIN_STEP * next_mark - 1e-9):
                        next_mark += 1
                    draw(False)
            elif now - last_draw >= PLAIN_INTERVAL:
                draw(False)
    finally:
        draw(True)
