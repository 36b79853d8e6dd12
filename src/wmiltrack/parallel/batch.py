"""Tracking many clips, each from its own first box: ``wmiltrack track --list FILE``.

The list file has one line per clip, ``PATH x,y,w,h`` (the box's numbers separated by commas,
semicolons or spaces; ``PATH`` a video or image folder, relative to the list file's folder;
blank lines and lines starting with ``#`` are skipped). Every clip becomes one job
(:func:`track_clip`) on one of :mod:`wmiltrack.parallel.executors` (this process, worker processes,
Dask), and its box file, ``<output folder>/<clip name>.txt`` (for clips of one name in
different folders ``<output folder>/<folders>_<clip name>.txt``, the folders from the list
file's), is written as soon as that clip is finished. A box file is written under a
temporary name and renamed when complete, so a run that is stopped leaves either a complete
file or none; the next run skips every clip whose file exists (resume) and tracks the others.

A clip's frames are read as ``wmiltrack track`` reads them: a frame that cannot be used is
skipped with the last box held, and the first line is the first box as the tracker uses it
(rounded to whole pixels, clipped to the frame).
"""

from __future__ import annotations

import os
import re
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

__all__ = ["Clip", "ClipJob", "ClipResult", "read_clip_list", "track_clip", "track_clips"]

_NUMBER = re.compile(r"^[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$")
PARTIAL_SUFFIX = ".partial"


@dataclass(frozen=True)
class Clip:
    """One line of the list file.

    Attributes
    ----------
    path:
        The video or image folder (absolute).
    box:
        The first box ``(x, y, w, h)`` as written.
    line:
        Its line in the list file (from 1), to name it in messages.
    output:
        Its box file (absolute).
    """

    path: str
    box: tuple[float, float, float, float]
    line: int
    output: str

    @property
    def label(self) -> str:
        """``name (line N)``, as messages name the clip."""
        return f"{Path(self.path).name} (line {self.line})"


@dataclass(frozen=True)
class ClipJob:
    """One clip with the tracker to run on it (picklable, for worker processes and Dask)."""

    clip: Clip
    tracker: str = "rcwmil"
    seed: int = 0
    overrides: tuple[tuple[str, Any], ...] = ()


@dataclass(frozen=True)
class ClipResult:
    """What a :class:`ClipJob` gave: one box per frame, or the error that stopped it."""

    clip: Clip
    boxes: npt.NDArray[np.float64] = field(repr=False)
    skipped: int = 0
    error: str | None = None


def _parse_line(text: str) -> tuple[str, tuple[float, float, float, float]] | None:
    """``(path, box)`` of a list line, or ``None`` when its end is not a box."""
    fields = text.split()
    if len(fields) >= 5 and all(_NUMBER.match(f.strip(",;")) for f in fields[-4:]):
        path, numbers = fields[:-4], [f.strip(",;") for f in fields[-4:]]
    elif len(fields) >= 2:
        path, numbers = fields[:-1], [f for f in re.split(r"[,;]", fields[-1]) if f]
    else:
        return None
    if len(numbers) != 4 or not all(_NUMBER.match(n) for n in numbers):
        return None
    x, y, w, h = (float(n) for n in numbers)
    return " ".join(path), (x, y, w, h)


def read_clip_list(list_file: str | os.PathLike[str], out_dir: str | os.PathLike[str]) -> list[Clip]:
    """Read a list file.

    Parameters
    ----------
    list_file:
        One ``PATH x,y,w,h`` line per clip (see the module's description).
    out_dir:
        Folder of the box files: clip ``a/b.mp4`` gets ``out_dir/b.txt``; clips of one name in
        different folders get their folders in the name (``a/b.mp4``: ``out_dir/a_b.txt``).

    Returns
    -------
    list of Clip

    Raises
    ------
    FileNotFoundError
        The list file is missing.
    ValueError
        A line that is not ``PATH x,y,w,h``, a clip that does not exist, one clip listed twice
        (their box files would collide), or no clip at all; the message names the line.
    """
    lf = Path(list_file)
    if not lf.is_file():
        raise FileNotFoundError(f"list file not found: {lf}")
    base, out = lf.resolve().parent, Path(out_dir).resolve()
    found: list[tuple[int, Path, tuple[float, float, float, float]]] = []
    for lineno, raw in enumerate(lf.read_text(encoding="utf-8-sig").splitlines(), start=1):
        text = raw.strip()
        if not text or text.startswith("#"):
            continue
        parsed = _parse_line(text)
        if parsed is None:
            raise ValueError(f"{lf}:{lineno}: expected 'PATH x,y,w,h', got {text!r}")
        name, box = parsed
        path = (base / Path(name).expanduser()).resolve()
        if not path.exists():
            raise ValueError(f"{lf}:{lineno}: {path} does not exist")
        found.append((lineno, path, box))
    if not found:
        raise ValueError(f"{lf} lists no clip: write one 'PATH x,y,w,h' line per clip")
    names = [_clip_name(path) for _, path, _ in found]
    clips: list[Clip] = []
    by_output: dict[str, int] = {}
    for (lineno, path, box), name in zip(found, names):
        if names.count(name) > 1:  # clips of one name in different folders: name the folders too
            name = _clip_name(path, base)
        output = str(out / f"{name}.txt")
        if output in by_output:
            raise ValueError(f"{lf}:{lineno}: its box file {output} is also line "
                             f"{by_output[output]}'s (the same clip twice?)")
        by_output[output] = lineno
        clips.append(Clip(str(path), box, lineno, output))
    return clips


def _clip_name(path: Path, base: Path | None = None) -> str:
    """The name of a clip's box file (without ``.txt``): the video's stem or the folder's name;
    with ``base``, its path from ``base`` (or its full path), folders joined by ``_``, so that
    ``cam1/clip.mp4`` and ``cam2/clip.mp4`` get ``cam1_clip`` and ``cam2_clip``."""
    stem = path.stem if path.is_file() else path.name
    if base is None:
        return stem
    parent = path.parent
    folders = parent.relative_to(base).parts if parent.is_relative_to(base) else parent.parts[1:]
    return "_".join([*folders, stem])


def track_clip(job: ClipJob) -> ClipResult:
    """Track one clip from its first box; an error (unreadable clip, bad box, unknown tracker)
    is the result's ``error``, not an exception."""
    from ..data.sequences import TolerantFrames, open_input
    from ..engine.frames import clip_box
    from ..trackers import make_tracker

    boxes: list[tuple[float, ...]] = []
    skipped = 0
    try:
        tracker = make_tracker(job.tracker, seed=job.seed, **dict(job.overrides))
        seq = open_input(job.clip.path, groundtruth=False)
        frames = iter(TolerantFrames(seq))
        try:
            for i, frame, problem in frames:
                if frame is None:
                    if i == 0:
                        raise ValueError(f"frame 1 cannot be used ({problem}), and the first box "
                                         "belongs to it")
                    boxes.append(boxes[-1])
                    skipped += 1
                elif i == 0:
                    tracker.init(frame, job.clip.box)
                    fh, fw = frame.shape[:2]
                    boxes.append(tuple(float(v) for v in clip_box(job.clip.box, fw, fh)))
                else:
                    boxes.append(tuple(tracker.update(frame).box))
        finally:
            frames.close()
            seq.close()
    except Exception as exc:  # noqa: BLE001 - reported for this clip, the others go on
        return ClipResult(job.clip, np.zeros((0, 4)), skipped, f"{type(exc).__name__}: {exc}")
    return ClipResult(job.clip, np.asarray(boxes, dtype=np.float64).reshape(-1, 4), skipped)


def failed_clip(job: ClipJob, error: str) -> ClipResult:
    """The result of a job that gave none (a Dask worker died under it, for instance)."""
    return ClipResult(job.clip, np.zeros((0, 4)), 0, error)


def describe_clip(job: ClipJob) -> str:
    """A job as the Dask executor's retry line names it."""
    return job.clip.label


def _write_complete(path: Path, boxes: npt.NDArray[np.float64]) -> None:
    """Write the box file under a temporary name, then rename it: a file under the final name
    is always complete."""
    from ..data.boxes import write_boxes

    partial = path.with_name(path.name + PARTIAL_SUFFIX)
    write_boxes(partial, boxes)
    os.replace(partial, path)


def track_clips(
    clips: Sequence[Clip],
    executor: Any,
    *,
    tracker: str = "rcwmil",
    seed: int = 0,
    overrides: dict[str, Any] | None = None,
    wrap: Callable[[Iterator[ClipResult], int], Iterator[ClipResult]] | None = None,
) -> Iterator[ClipResult]:
    """Track every clip whose box file does not exist yet; write each box file as its clip is
    finished and yield the clip's result (a failed clip gets no file).

    Parameters
    ----------
    clips:
        From :func:`read_clip_list`.
    executor:
        An executor of :mod:`wmiltrack.parallel.executors` (anything with their ``map``).
    tracker, seed, overrides:
        The tracker spec, its seed and parameter overrides, the same for every clip.
    wrap:
        ``wrap(results, n_jobs)`` wraps the stream of results (a progress bar).
    """
    todo = [c for c in clips if not Path(c.output).is_file()]
    jobs = [ClipJob(c, tracker, seed, tuple(sorted((overrides or {}).items()))) for c in todo]
    results: Iterator[ClipResult] = executor.map(track_clip, jobs)
    if wrap is not None:
        results = wrap(results, len(jobs))
    for result in results:
        if result.error is None:
            _write_complete(Path(result.clip.output), result.boxes)
        yield result
