"""Run stage of the evaluation: run trackers on sequences and time them honestly.

The unit of work is a :class:`Task`, one (tracker spec, sequence, seed) with the protocol's
settings; :func:`run_task` turns it into a :class:`RunOutcome` (boxes as the tracker gave
them, its "found" flags, timing, any error).  An executor maps tasks to outcomes and hands
each one back as soon as it is finished (:mod:`wmiltrack.parallel.executors`: in this process, in
worker processes or on Dask), so the caller can write each result at once and a failure or an
interruption loses only the tasks not yet finished.

Timing rules
------------
* Frames are decoded before any clock starts; the trackers get the same in-memory arrays.
* The clock is read right before and after each ``update`` call, and nothing else is inside
  the interval (:func:`wmiltrack.timing.timed`, the one timing helper of every timed loop).
  ``init`` is timed separately (``init_time``), and creating the tracker object is not timed.
* Python's garbage collector is run before every run and disabled during it, for every
  tracker alike (as :mod:`timeit` does, :func:`wmiltrack.timing.gc_paused`), so a
  collection does not land on one tracker's update.
* ``fps`` is *update-only* throughput: ``updates / sum(update times)``.  The median
  per-update time is kept too (``median_update_time``), being robust to a slow outlier.
* OpenCV's own thread pool is set to ``cv_threads`` (1 by default: one thread per tracker, as
  wmiltrack uses) in every process that runs trackers.
* If a tracker raises, the exception is recorded (type, message and frame index) and the
  remaining frames have no box; nothing is swallowed silently.
"""

from __future__ import annotations

import math
import traceback
import warnings
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal, TypeVar

import numpy as np
import numpy.typing as npt

from ..engine.result import TrackerLike, TrackResult
from ..parallel import executors
from ..timing import gc_paused, timed
from ..trackers import make_tracker
from .metrics import valid_mask

__all__ = [
    "RunOutcome",
    "RunResult",
    "SerialExecutor",
    "Task",
    "run_sequence",
    "run_task",
]

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]
Frame = npt.NDArray[np.uint8]
TrackerSpec = str | Callable[[], TrackerLike]
T = TypeVar("T")
R = TypeVar("R")


@dataclass(frozen=True)
class RunResult:
    """One tracker run over one sequence.

    Attributes
    ----------
    tracker:
        The tracker's name (its spec).
    boxes:
        ``(n, 4)`` boxes; row 0 is the initialisation box; NaN rows after an error.
    scores:
        ``(n,)`` confidence per frame; NaN on frame 0 and where the tracker gives none.
    oks:
        ``(n,)`` the tracker's own "found" flag (True on frame 0).
    init_time:
        Seconds spent in ``init`` (NaN if it raised).
    update_times:
        ``(n,)`` seconds spent in each ``update``; NaN on frame 0 and on frames not run.
    n_updates:
        Updates that completed.
    error:
        ``None``, or ``"<ExceptionType>: <message>"`` if the tracker raised.
    error_frame:
        Frame index where it raised (0 for ``init``), else ``None``.
    traceback:
        Formatted traceback of the error, else ``None``.
    """

    tracker: str
    boxes: FloatArray = field(repr=False)
    scores: FloatArray = field(repr=False)
    oks: BoolArray = field(repr=False)
    init_time: float
    update_times: FloatArray = field(repr=False)
    n_updates: int
    error: str | None = None
    error_frame: int | None = None
    traceback: str | None = field(default=None, repr=False)

    @property
    def total_update_time(self) -> float:
        """Sum of the update times in seconds."""
        return float(np.nansum(self.update_times))

    @property
    def fps(self) -> float:
        """Update-only frames per second: ``n_updates / total_update_time`` (NaN if none)."""
        t = self.total_update_time
        return self.n_updates / t if self.n_updates > 0 and t > 0 else float("nan")

    @property
    def median_update_time(self) -> float:
        """Median seconds per update (NaN if none)."""
        t = self.update_times[~np.isnan(self.update_times)]
        return float(np.median(t)) if t.size else float("nan")

    @property
    def completed(self) -> bool:
        """True when the tracker ran to the last frame without raising."""
        return self.error is None

    def to_dict(self, per_frame: bool = False) -> dict[str, Any]:
        """JSON-serialisable summary (optionally with boxes and times per frame)."""
        d: dict[str, Any] = {
            "tracker": self.tracker,
            "n_frames": int(self.boxes.shape[0]),
            "n_updates": self.n_updates,
            "fps": _num(self.fps),
            "median_update_time": _num(self.median_update_time),
            "total_update_time": self.total_update_time,
            "init_time": _num(self.init_time),
            "error": self.error,
            "error_frame": self.error_frame,
        }
        if per_frame:
            d["boxes"] = [[_num(v) for v in row] for row in self.boxes]
            d["scores"] = [_num(v) for v in self.scores]
            d["update_times"] = [_num(v) for v in self.update_times]
        return d


def _num(v: float | np.floating[Any]) -> float | None:
    f = float(v)
    return None if math.isnan(f) else f


def _spec_name(spec: TrackerSpec) -> str:
    if isinstance(spec, str):
        return spec.strip()
    return str(getattr(spec, "name", None) or getattr(spec, "__name__", None) or repr(spec))


def _factory(
    spec: TrackerSpec, seed: int, params: Mapping[str, Any] | None
) -> Callable[[], TrackerLike]:
    if isinstance(spec, str):
        kw = dict(params or {})
        return lambda: make_tracker(spec, seed=seed, **kw)
    if params:
        raise ValueError("params can only be given with a tracker name, not a factory")
    return spec


def run_sequence(
    spec: TrackerSpec,
    frames: Sequence[Frame | None],
    init_box: Sequence[float] | npt.NDArray[Any],
    *,
    seed: int = 0,
    params: Mapping[str, Any] | None = None,
    raise_errors: bool = False,
) -> RunResult:
    """Run one tracker over pre-decoded frames, timing each ``update``.

    Parameters
    ----------
    spec:
        A tracker name for :func:`wmiltrack.trackers.make_tracker` (``"rcwmil"``,
        ``"opencv:MIL"``...) or a callable returning a new tracker.
    frames:
        The decoded frames (decode before calling: decoding is not timed). ``None`` marks a
        frame that could not be decoded: the tracker is not updated there and the frame gets
        the last box, with ``ok`` False and no score (as ``wmiltrack track`` skips it).
    init_box:
        ``(x, y, w, h)`` of the target in ``frames[0]``.
    seed:
        Tracker seed (ignored for a callable spec).
    params:
        Extra tracker parameters (only with a name).
    raise_errors:
        Re-raise an exception from the tracker instead of recording it.

    Returns
    -------
    RunResult

    Raises
    ------
    ValueError
        If ``frames`` is empty, its first frame is ``None``, or ``init_box`` is not 4 numbers.
    Exception
        Whatever creating the tracker raises (unknown name, :class:`TrackerUnavailable`...),
        and, with ``raise_errors``, whatever ``init``/``update`` raise.
    """
    n = len(frames)
    if n == 0:
        raise ValueError("no frames to track")
    first = frames[0]
    if first is None:
        raise ValueError("the first frame could not be decoded, and the first box belongs to it")
    box0 = np.asarray(init_box, dtype=np.float64).reshape(-1)
    if box0.shape != (4,):
        raise ValueError(f"init_box must be 4 numbers x, y, w, h; got {init_box!r}")
    name = _spec_name(spec)
    tracker = _factory(spec, seed, params)()
    run = _Recording(name, n)
    frame_list = list(frames)
    i = 0
    with gc_paused():
        try:
            box_tuple = (float(box0[0]), float(box0[1]), float(box0[2]), float(box0[3]))
            _, run.init_time = timed(tracker.init, first, box_tuple)
            run.boxes[0] = box0
            run.oks[0] = True
            for i in range(1, n):
                frame = frame_list[i]
                if frame is None:  # not decodable: skipped, the last box held
                    run.boxes[i] = run.boxes[i - 1]
                    continue
                r, run.times[i] = timed(tracker.update, frame)
                run.boxes[i] = r.box
                run.scores[i] = r.score
                run.oks[i] = r.ok
                run.n_updates += 1
        except Exception as exc:
            if raise_errors:
                raise
            run.failed(exc, i)
            warnings.warn(
                f"tracker {name!r} raised at frame {i + 1}: {run.error}", RuntimeWarning,
                stacklevel=2
            )
    return run.result()


class _Recording:
    """What :func:`run_sequence` records while it runs, frame by frame."""

    def __init__(self, name: str, n: int) -> None:
        self.name = name
        self.boxes = np.full((n, 4), np.nan)
        self.scores = np.full(n, np.nan)
        self.oks = np.zeros(n, dtype=bool)
        self.times = np.full(n, np.nan)
        self.init_time = math.nan
        self.n_updates = 0
        self.error: str | None = None
        self.error_frame: int | None = None
        self.traceback: str | None = None

    def failed(self, exc: Exception, i: int) -> None:
        """The tracker raised ``exc`` at frame ``i``: recorded, and no box from there on."""
        self.error = f"{type(exc).__name__}: {exc}"
        self.error_frame = i
        self.traceback = traceback.format_exc()
        self.boxes[i:] = np.nan
        self.scores[i:] = np.nan
        self.oks[i:] = False
        self.times[i:] = np.nan

    def result(self) -> RunResult:
        return RunResult(
            tracker=self.name,
            boxes=self.boxes,
            scores=self.scores,
            oks=self.oks,
            init_time=self.init_time,
            update_times=self.times,
            n_updates=self.n_updates,
            error=self.error,
            error_frame=self.error_frame,
            traceback=self.traceback,
        )


# ----------------------------------------------------------------------------- tasks
@dataclass(frozen=True)
class Task:
    """One unit of work: a tracker on a sequence with one seed.

    Attributes
    ----------
    tracker:
        Tracker spec for :func:`wmiltrack.trackers.make_tracker`.
    sequence:
        Path of the OTB sequence (:func:`wmiltrack.data.sequences.load_otb_sequence`), or for
        another layout the sequence's name in ``dataset``.
    seed:
        Tracker seed.
    repeat:
        Index of the repeat this seed belongs to (``seed = first seed + repeat``).
    protocol:
        ``"ope"`` (one pass from the first frame with ground truth) or ``"vot"`` (supervised,
        re-initialised ``skip`` frames after each failure; ``burnin`` frames left out).
    skip, burnin:
        VOT settings.
    layout:
        Dataset layout (:data:`wmiltrack.data.layouts.LAYOUTS`); ``"otb"`` reads ``sequence``
        as a folder.
    dataset:
        For the other layouts: the dataset folder :func:`wmiltrack.data.layouts.load_layout`
        finds ``sequence`` in.
    """

    tracker: str
    sequence: str
    seed: int
    repeat: int = 0
    protocol: Literal["ope", "vot"] = "ope"
    skip: int = 5
    burnin: int = 10
    layout: str = "otb"
    dataset: str | None = None


@dataclass(frozen=True)
class RunOutcome:
    """What one :class:`Task` gave (or, untimed, one box file read back).

    Attributes
    ----------
    tracker, sequence:
        Names (the sequence's name, not its path).
    repeat, seed:
        Repeat index and the tracker seed it used.
    boxes:
        ``(n, 4)`` boxes, one per ground-truth frame, as the tracker gave them: NaN where it
        gave none (an OpenCV tracker saying "not found"), before the first frame with ground
        truth, and from the frame where it raised on.  With the VOT protocol, NaN on frames
        not tracked.
    oks:
        ``(n,)`` the tracker's own "found" flag (False where it did not run).
    fps:
        Update-only frames per second (NaN when not timed, e.g. ``--results``).
    init_time:
        Seconds in ``init`` (mean over the initialisations for VOT).
    median_update_time:
        Median seconds per ``update``.
    n_updates:
        Number of timed updates.
    n_lost:
        Frames where the tracker reported the target lost (``ok`` False) after ``init``.
    error:
        ``"<Exception>: <message> (frame i)"`` if the task failed, else ``None``.
    error_frame:
        Frame where it failed (the first frame not tracked), else ``None``.
    vot:
        :meth:`wmiltrack.eval.vot_style.SupervisedResult.to_dict` for the VOT protocol.
    scores:
        ``(n,)`` the tracker's confidence per frame (``TrackResult.score``); NaN where it gave
        none (frame 0 of a run, frames not tracked). Empty when not known (box files read
        back).
    skipped_frames:
        One line per frame of the sequence that could not be decoded (``frame 120:
        0120.jpg: truncated JPEG ...``): not given to the tracker, which kept its last box.
    """

    tracker: str
    sequence: str
    repeat: int
    seed: int
    boxes: FloatArray = field(repr=False)
    oks: BoolArray = field(repr=False)
    fps: float = math.nan
    init_time: float = math.nan
    median_update_time: float = math.nan
    n_updates: int = 0
    n_lost: int = 0
    error: str | None = None
    error_frame: int | None = None
    vot: dict[str, Any] | None = field(default=None, repr=False)
    scores: FloatArray = field(default_factory=lambda: np.zeros(0), repr=False)
    skipped_frames: tuple[str, ...] = ()

    @property
    def frames_run(self) -> int:
        """Frames up to (not including) the one where the task failed, else all of them."""
        return int(self.boxes.shape[0]) if self.error_frame is None else self.error_frame


# one decoded sequence per process: tasks come sequence by sequence, so each is decoded once
_decoded: dict[tuple[str, str | None, str], _Decoded] = {}


@dataclass(frozen=True)
class _Decoded:
    """A sequence decoded for its tasks: frames (``None`` where one could not be decoded) and
    one line per such frame."""

    name: str
    gt: FloatArray
    frames: list[Frame | None]
    problems: tuple[str, ...]


def _load(task: Task) -> _Decoded:
    key = (task.layout, task.dataset, task.sequence)
    if key not in _decoded:
        _decoded.clear()
        if task.layout == "otb":
            from ..data.sequences import load_otb_sequence

            seq = load_otb_sequence(task.sequence)
        else:
            from ..data.layouts import load_layout

            if task.dataset is None:
                raise ValueError(f"a {task.layout} task needs the dataset folder")
            seq = load_layout(task.dataset, task.layout, [task.sequence])[0]
        if seq.groundtruth is None:  # pragma: no cover - every loader reads it
            raise ValueError(f"{task.sequence}: no ground truth")
        gt = np.asarray(seq.groundtruth, dtype=np.float64)
        frames, problems = _decode_all(seq)  # decoded before any clock starts
        if len(frames) != len(gt):
            raise ValueError(f"{seq.name}: decoded {len(frames)} frames but have {len(gt)} "
                             "ground-truth boxes")
        _decoded[key] = _Decoded(seq.name, gt, frames, problems)
    return _decoded[key]


def _decode_all(seq: Any) -> tuple[list[Frame | None], tuple[str, ...]]:
    """Every frame of ``seq`` as :class:`wmiltrack.data.sequences.TolerantFrames` reads them
    (the reader of ``wmiltrack track``): one frame that cannot be decoded (a truncated JPEG)
    is ``None`` with a line saying why, instead of failing the whole sequence."""
    from ..data.sequences import TolerantFrames

    frames: list[Frame | None] = []
    problems: list[str] = []
    try:
        for i, frame, problem in TolerantFrames(seq):
            frames.append(frame)
            if frame is None:
                problems.append(f"frame {i + 1}: {problem}")
    finally:
        seq.close()
    return frames, tuple(problems)


class _TimedTracker:
    """Wraps a tracker and records the time spent in ``init`` and ``update``."""

    def __init__(self, inner: TrackerLike, init_times: list[float], update_times: list[float]):
        self.inner = inner
        self.init_times = init_times
        self.update_times = update_times

    def init(self, frame: Frame, box: tuple[float, float, float, float]) -> object:
        out, seconds = timed(self.inner.init, frame, box)
        self.init_times.append(seconds)
        return out

    def update(self, frame: Frame) -> TrackResult:
        r, seconds = timed(self.inner.update, frame)
        self.update_times.append(seconds)
        return r


def _run_ope(task: Task, data: _Decoded) -> RunOutcome:
    name, frames, gt = data.name, data.frames, data.gt
    n = len(frames)
    idx = np.flatnonzero(valid_mask(gt))
    if idx.size == 0:
        raise ValueError(f"{name}: no frame has a valid ground-truth box")
    start = int(idx[0])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # the error is recorded instead
        run = run_sequence(task.tracker, frames[start:], gt[start], seed=task.seed)
    boxes = np.full((n, 4), np.nan)
    oks = np.zeros(n, dtype=bool)
    scores = np.full(n, np.nan)
    boxes[start:] = run.boxes
    oks[start:] = run.oks
    scores[start:] = run.scores
    error_frame = None if run.error_frame is None else start + run.error_frame
    end = n if error_frame is None else error_frame
    return RunOutcome(
        tracker=task.tracker,
        sequence=name,
        repeat=task.repeat,
        seed=task.seed,
        boxes=boxes,
        oks=oks,
        fps=run.fps,
        init_time=run.init_time,
        median_update_time=run.median_update_time,
        n_updates=run.n_updates,
        n_lost=int(np.sum(~oks[start + 1 : end])),
        error=None if run.error is None else (
            run.error if error_frame is None else f"{run.error} (frame {error_frame + 1})"),
        error_frame=error_frame,
        scores=scores,
        skipped_frames=data.problems,
    )


def _run_vot(task: Task, data: _Decoded) -> RunOutcome:
    from .vot_style import run_supervised

    name, gt = data.name, data.gt
    if data.problems:  # the supervised protocol re-initialises on frames: it needs them all
        raise ValueError(f"the VOT protocol needs every frame; {'; '.join(data.problems)}")
    frames = [f for f in data.frames if f is not None]

    init_times: list[float] = []
    update_times: list[float] = []

    def factory() -> TrackerLike:
        return _TimedTracker(make_tracker(task.tracker, seed=task.seed), init_times, update_times)

    with gc_paused():
        res = run_supervised(factory, frames, gt, skip=task.skip, burnin=task.burnin)
    total = float(sum(update_times))
    n = len(update_times)
    boxes = np.asarray(res.boxes, dtype=np.float64)
    return RunOutcome(
        tracker=task.tracker,
        sequence=name,
        repeat=task.repeat,
        seed=task.seed,
        boxes=boxes,
        oks=np.all(np.isfinite(boxes), axis=1),
        fps=n / total if n and total > 0 else math.nan,
        init_time=float(np.mean(init_times)) if init_times else math.nan,
        median_update_time=float(np.median(update_times)) if update_times else math.nan,
        n_updates=n,
        vot=res.to_dict(),
    )


def run_task(task: Task) -> RunOutcome:
    """Run one task; a failure (of the tracker, or of loading) becomes the outcome's ``error``.

    Parameters
    ----------
    task:
        What to run.

    Returns
    -------
    RunOutcome
        With ``error`` set and NaN boxes from the failing frame on if anything raised; the
        exception does not propagate (``KeyboardInterrupt`` does).
    """
    name = Path(task.sequence).name
    n = 0
    try:
        data = _load(task)
        name, n = data.name, len(data.frames)
        if task.protocol == "vot":
            return _run_vot(task, data)
        return _run_ope(task, data)
    except Exception as exc:  # noqa: BLE001 - recorded in the outcome, reported in the table
        return RunOutcome(
            tracker=task.tracker,
            sequence=name,
            repeat=task.repeat,
            seed=task.seed,
            boxes=np.full((n, 4), np.nan),
            oks=np.zeros(n, dtype=bool),
            error=f"{type(exc).__name__}: {exc}",
            error_frame=0,
        )


# ----------------------------------------------------------------------------- executors
class SerialExecutor(executors.SerialExecutor):
    """:class:`wmiltrack.parallel.executors.SerialExecutor` that also lets go of the decoded sequence
    it kept between tasks (one per process, see :func:`run_task`) once the tasks are done.

    Parameters
    ----------
    cv_threads:
        ``cv2.setNumThreads`` while the tasks run (restored afterwards); ``None`` leaves it.
    """

    def map(self, fn: Callable[[T], R], tasks: Sequence[T]) -> Iterator[R]:
        """Run ``fn`` on every task in order, yielding each outcome at once."""
        try:
            yield from super().map(fn, tasks)
        finally:
            _decoded.clear()
