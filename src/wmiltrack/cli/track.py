"""``wmiltrack track``: one object through a video, an image folder or an OTB sequence.

Long runs lose nothing: each box is written (and flushed) as soon as it is computed, a frame
that cannot be decoded is skipped with the last box held (``--strict`` stops instead), and
SIGINT/SIGTERM stop the run after the current frame with the output and ``--video`` closed.
"""

from __future__ import annotations

import argparse
import math
import signal
import sys
import threading
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from types import FrameType
from typing import IO, Any

from ..timing import timed
from .options import (
    EXIT_CODES_EPILOG,
    EXIT_ERROR,
    EXIT_OK,
    EXIT_SIGINT,
    Subparsers,
    UsageError,
    add_executor_options,
    add_model_options,
    add_tracker_options,
    open_frames,
    parse_box,
    tracker_from_args,
    tracker_overrides,
)
from .outputs import check_outputs

EXIT_SIGTERM = 128 + int(signal.SIGTERM)  # 143, besides the command line's own table

_HELD_COLOR = (0, 0, 255)  # red: the box drawn on a skipped frame is the last one, held


class _StopRequest:
    """SIGINT/SIGTERM handler: the first signal asks the loop to stop after the current frame;
    a second one (the user insisting) raises :class:`KeyboardInterrupt` at once."""

    def __init__(self) -> None:
        self.signum: int | None = None
        self.hurry = True  # set to False once the run is closing: then signals are only noted

    def __call__(self, signum: int, frame: FrameType | None) -> None:
        if self.signum is not None and self.hurry:
            raise KeyboardInterrupt
        if self.signum is None:
            self.signum = signum


@contextmanager
def _stop_signals() -> Iterator[_StopRequest]:
    """Route SIGINT and SIGTERM to a :class:`_StopRequest` while the block runs (main thread
    only: elsewhere Python cannot set handlers, and the defaults stay)."""
    stop = _StopRequest()
    if threading.current_thread() is not threading.main_thread():
        yield stop
        return
    previous = {s: signal.signal(s, stop) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield stop
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)


class _BoxLines:
    """One ``x,y,w,h`` line per frame, written and flushed as soon as it is computed, to a file
    (same format as :func:`wmiltrack.data.boxes.write_boxes`) or to standard output.

    The file is opened in two steps, so that a run that fails before it starts leaves an
    existing file as it was: :meth:`open` opens it without emptying it (a file that cannot be
    written fails here), and the first line empties it, once the first frame, the box and the
    other outputs (``--video``) are known to be good. :meth:`abandon` undoes an :meth:`open`
    whose run did not start (a file it created is removed).
    """

    def __init__(self, path: Path | None, extra: Callable[[Sequence[float], float, bool], str]
                 | None = None) -> None:
        from ..data.boxes import format_box

        self.path = path
        self.count = 0
        self._fh: IO[str] | None = None
        self._created = False
        self._regular = False
        self._started = False
        self._format: Callable[[Sequence[float]], str]
        self._extra = extra
        if path is None:
            self._fh = sys.stdout
            self._started = True
            self._format = lambda box: ",".join(f"{float(v):g}" for v in box)
        else:
            self._format = format_box

    def open(self) -> None:
        """Open the file for writing without changing what it holds (no-op for stdout)."""
        if self._fh is not None or self.path is None:
            return
        self._created = not self.path.exists()
        if self._created:
            self.path.parent.mkdir(parents=True, exist_ok=True)
        # a regular file is emptied at the first line; a device or pipe (/dev/null, a FIFO)
        # holds nothing to keep and cannot be emptied
        self._regular = self.path.is_file()
        self._fh = self.path.open("r+" if self._regular and not self._created else "w",
                                  encoding="utf-8")

    def abandon(self) -> None:
        """Close a file opened by :meth:`open` before any line: an existing file keeps its
        content, a file created by :meth:`open` is removed."""
        if self.path is None or self._fh is None or self._started:
            return
        self._fh.close()
        self._fh = None
        if self._created:
            self.path.unlink(missing_ok=True)

    def write(self, box: Sequence[float], score: float = math.nan, ok: bool = True) -> None:
        """The line of one frame: ``x,y,w,h``, or with ``--scores`` ``x,y,w,h,score,ok``."""
        line = self._format(box)
        if self._extra is not None:
            line += self._extra(box, score, ok)
        self.write_line(line)

    def write_line(self, line: str) -> None:
        """One line (of one frame), flushed at once."""
        self.open()
        assert self._fh is not None
        if not self._started:  # the first line: now the old content goes
            if self._regular:
                self._fh.seek(0)
                self._fh.truncate()
            self._started = True
        self._fh.write(line + "\n")
        self._fh.flush()
        self.count += 1

    def close(self) -> None:
        if self.path is not None and self._fh is not None:
            if not self._started:
                self.abandon()
                return
            self._fh.close()


def _cmd_track(args: argparse.Namespace) -> int:
    if args.list is not None:
        return _track_list(args)
    if args.input is None:
        raise UsageError("give INPUT (a video, image folder or OTB sequence) or --list FILE")
    if args.jobs != 1 or args.executor is not None or args.scheduler is not None:
        raise UsageError("-j, --executor and --scheduler go with --list (many clips)")
    with _stop_signals() as stop:
        return _track(args, stop)


def _check_list_args(args: argparse.Namespace) -> None:
    """The usage errors of ``track --list``: options that go with one INPUT, and -o DIR."""
    if args.input is not None:
        raise UsageError("give either INPUT (one clip) or --list FILE (many), not both")
    mixed = [o for o, v in (("--box", args.box), ("--boxes", args.boxes), ("--video", args.video))
             if v is not None] + (["--strict"] if args.strict else [])
    if mixed:
        raise UsageError(f"--list takes each clip's first box from its line; {', '.join(mixed)} "
                         "goes with one INPUT")
    if args.output is None:
        raise UsageError("--list needs -o DIR, the folder of the clips' box files")
    if args.output.is_file():
        raise UsageError(f"-o {args.output} is a file; --list writes one box file per clip into a folder")


def _track_list(args: argparse.Namespace) -> int:
    """``track --list FILE -o DIR``: every clip of the list on the chosen executor; each box
    file written as its clip finishes; clips whose box file exists are skipped (resume)."""
    from ..parallel.batch import ClipResult, describe_clip, failed_clip, read_clip_list, track_clips
    from ..parallel.executors import make_executor
    from ..progress import progress

    _check_list_args(args)
    tracker_from_args(args)  # an unknown tracker or parameter is a usage error before any clip runs
    clips = read_clip_list(args.list, args.output)
    for clip in clips:  # no box file may be an input (a clip, a file of a clip's folder, the list)
        check_outputs([("--list's box file", Path(clip.output))],
                      [args.list, *(Path(c.path) for c in clips)])
    args.output.mkdir(parents=True, exist_ok=True)
    try:
        executor = make_executor(args.executor, args.jobs, 1, args.scheduler,
                                 log=lambda line: print(f"wmiltrack: {line}", file=sys.stderr),
                                 failed=failed_clip, describe=describe_clip)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    done = sum(Path(c.output).is_file() for c in clips)
    failed: list[ClipResult] = []
    tracked = 0

    def bar(results: Iterator[ClipResult], n: int) -> Iterator[ClipResult]:
        return iter(progress(results, total=n, desc=f"{args.tracker} clips"))

    interrupted = False
    try:
        for result in track_clips(clips, executor, tracker=args.tracker, seed=args.seed,
                                  overrides=tracker_overrides(args), wrap=bar):
            if result.error is None:
                tracked += 1
            else:
                failed.append(result)
                print(f"wmiltrack: error: {result.clip.label}: {result.error}", file=sys.stderr)
    except KeyboardInterrupt:
        interrupted = True
    _list_summary(args, len(clips), done, tracked, len(failed), interrupted)
    if interrupted:
        return EXIT_SIGINT
    return EXIT_ERROR if failed else EXIT_OK


def _list_summary(args: argparse.Namespace, clips: int, done: int, tracked: int, failed: int,
                  interrupted: bool) -> None:
    """Print the one-line summary of a ``track --list`` run."""
    summary = [f"{clips} clips: {tracked} tracked"]
    if done:
        summary.append(f"{done} already done (their box files exist)")
    if failed:
        summary.append(f"{failed} failed")
    left = clips - done - tracked - failed
    if interrupted:
        summary.append(f"interrupted with {left} not done: run the same command again to resume")
    print(f"wmiltrack: {'; '.join(summary)}; boxes in {args.output}", file=sys.stderr)


@dataclass
class _Step:
    """What one frame gave: a box, a score and an ok flag per target, the frame to draw them on
    (the last good one for a skipped frame) and their colour."""

    boxes: list[tuple[float, ...]]
    scores: list[float]
    oks: list[bool]
    shown: Any
    color: tuple[int, int, int] = (0, 255, 0)


class _OneTarget:
    """One target (``--box`` or the sequence's ground truth): a :class:`~wmiltrack.Tracker`
    (or an OpenCV tracker) started on the first box, one ``x,y,w,h`` line per frame (with
    ``--scores``: ``,score,ok``), the score drawn on ``--video``."""

    def __init__(self, tracker: Any, out: _BoxLines, box_given: bool) -> None:
        self.tracker = tracker
        self.out = out
        self.box_given = box_given

    def start(self, frame: Any, starts: Sequence[Sequence[float]]) -> None:
        try:
            self.tracker.init(frame, starts[0])
        except (ValueError, TypeError) as exc:
            if not self.box_given:
                raise  # the sequence's own ground truth: a bad input file, status 1
            raise UsageError(f"--box: {exc}") from None

    def found(self, result: Any) -> list[Any]:
        """The frame's results from what ``tracker.update`` returned."""
        return [result]

    def write(self, index: int, step: _Step, held: bool) -> None:
        self.out.write(step.boxes[0], step.scores[0], step.oks[0])

    def drawn_score(self, step: _Step) -> float:
        return step.scores[0]


class _SeveralTargets:
    """Several targets (``--boxes FILE``): a :class:`~wmiltrack.MultiTracker` with one target
    per line of FILE, one MOTChallenge-style line per target and frame, no score drawn."""

    def __init__(self, tracker: Any, out: _BoxLines, path: Path) -> None:
        self.tracker = tracker
        self.out = out
        self.path = path
        self.ids: list[int] = []

    def start(self, frame: Any, starts: Sequence[Sequence[float]]) -> None:
        try:
            self.ids = [_add_target(self.tracker, frame, b, k, self.path)
                        for k, b in enumerate(starts)]
        except (ValueError, TypeError) as exc:
            raise UsageError(str(exc)) from None

    def found(self, results: Any) -> list[Any]:
        return [results[k] for k in self.ids]

    def write(self, index: int, step: _Step, held: bool) -> None:
        for k, (b, s) in enumerate(zip(step.boxes, step.scores)):
            self.out.write_line(_mot_line(index, k, b, s, held=held))

    def drawn_score(self, step: _Step) -> float:
        return math.nan


class _Run:
    """The frames of one ``track`` run, one at a time: the trackers' boxes, the output lines,
    ``--video``, and what the summary counts."""

    def __init__(self, args: argparse.Namespace, targets: _OneTarget | _SeveralTargets,
                 starts: list[tuple[float, ...]], bar: Any, fps: float | None) -> None:
        self.args = args
        self.targets = targets
        self.starts = starts
        self.bar = bar
        self.fps = fps
        self.video: Any = None  # the cv2.VideoWriter, once the first frame is drawn
        self.last: _Step | None = None
        self.skipped = 0
        self.frames_done = 0
        self.times: list[float] = []
        self.error: str | None = None

    def frame(self, i: int, frame: Any, problem: str | None) -> bool:
        """Track, write and draw one frame; False when the run must stop (``--strict``)."""
        if frame is None:
            step = self._skipped(i, problem)
            if step is None:
                return False
        elif i == 0:
            step = self._first(frame)
        else:
            step = self._next(frame)
        self.targets.write(i, step, held=frame is None)
        self.frames_done += 1
        if self.args.video is not None and i > 0:
            self._draw(step, i + 1, self.targets.drawn_score(step))
        self.last = step
        return True

    def _skipped(self, i: int, problem: str | None) -> _Step | None:
        """A frame that cannot be used: the last boxes held (None with ``--strict``)."""
        if i == 0:
            raise ValueError(f"frame 1 cannot be used ({problem}), and the first box belongs to it")
        if self.args.strict:
            self.error = f"frame {i + 1}: {problem} (--strict)"
            return None
        self.skipped += 1
        self.bar.write(f"wmiltrack: warning: frame {i + 1} skipped, last box held: {problem}",
                       file=sys.stderr)
        last = self.last
        assert last is not None
        n = len(last.boxes)
        return _Step(last.boxes, [math.nan] * n, [False] * n, last.shown, _HELD_COLOR)

    def _first(self, frame: Any) -> _Step:
        """The first frame: the trackers start; their boxes as they use them (rounded to
        whole pixels, clipped to the frame)."""
        from ..engine.frames import clip_box

        self.targets.start(frame, self.starts)
        fw, fh = frame.shape[1], frame.shape[0]
        boxes = [tuple(float(v) for v in clip_box(b, fw, fh)) for b in self.starts]
        _warn_clipped(self.starts, boxes, fw, fh, self.bar)
        step = _Step(boxes, [1.0] * len(boxes), [True] * len(boxes), frame)
        # every output is opened before the first line empties -o: a video that cannot be
        # written leaves an existing box file as it was
        self.targets.out.open()
        if self.args.video is not None:
            self._draw(step, 1, math.nan)
        return step

    def _next(self, frame: Any) -> _Step:
        """A later frame: the trackers' update, timed alone."""
        result, seconds = timed(self.targets.tracker.update, frame)
        self.times.append(seconds)
        found = self.targets.found(result)
        return _Step([tuple(r.box) for r in found], [r.score for r in found],
                     [bool(r.ok) for r in found], frame)

    def _draw(self, step: _Step, number: int, score: float) -> None:
        self.video = _write_video_frame(self.video, self.args.video, step.shown, step.boxes,
                                        number, score, self.fps, step.color)

    def close_video(self) -> None:
        if self.video is not None:
            self.video.release()


def _track(args: argparse.Namespace, stop: _StopRequest) -> int:
    from ..data.sequences import TolerantFrames
    from ..progress import progress

    if args.boxes is not None and args.box is not None:
        raise UsageError("give either --box (one target) or --boxes (several), not both")
    several = args.boxes is not None
    if several and args.scores:
        raise UsageError("--scores goes with one target; --boxes lines already hold a score")
    check_outputs([("-o", args.output), ("--video", args.video)],
                  [p for p in (args.input, args.boxes) if p is not None])
    check_video_name(args.video)
    tracker: Any = tracker_from_args(args, several=several)
    seq = open_frames(args.input, has_box=args.box is not None or several)
    starts = _start_boxes(args, seq)
    reader = TolerantFrames(seq)
    frames = iter(reader)
    # the file is opened (not emptied) at the first frame, emptied at the first box
    out = _BoxLines(args.output, _score_fields if args.scores else None)
    targets = (_SeveralTargets(tracker, out, args.boxes) if several
               else _OneTarget(tracker, out, args.box is not None))
    bar = progress(frames, total=reader.expected, desc=f"{args.tracker} {seq.name}",
                   enabled=False if args.quiet else None)
    run = _Run(args, targets, starts, bar, seq.fps)
    broken_pipe = False
    try:
        for i, frame, problem in bar:
            if stop.signum is not None:  # a signal came before the first frame
                break
            if not run.frame(i, frame, problem) or stop.signum is not None:
                break
    except KeyboardInterrupt:  # a second SIGINT/SIGTERM while a frame was being processed
        if stop.signum is None:  # not from our handler (not installed outside the main thread)
            stop.signum = int(signal.SIGINT)
    except BrokenPipeError:  # the reader of standard output went away (| head): stop quietly
        broken_pipe = True
    except OSError as exc:  # writing the boxes failed (disk full, ...)
        run.error = f"cannot write the boxes: {exc}"
    finally:
        stop.hurry = False  # a signal now must not cut the closing of the output and video
        bar.close()
        frames.close()
        seq.close()
        run.close_video()
        try:
            out.close()
        except OSError as exc:
            run.error = run.error or f"cannot write the boxes: {exc}"

    if broken_pipe:
        raise BrokenPipeError  # the command line's one exit status for a closed pipe
    return _close_run(args, stop, reader, run.error, run.frames_done,
                      len(starts) if several else 0,
                      out.count, run.times, run.skipped)


def _start_boxes(args: argparse.Namespace, seq: Any) -> list[tuple[float, ...]]:
    """The first box of each target: --boxes, --box, or the sequence's ground truth."""
    if args.boxes is not None:
        try:
            return _read_start_boxes(args.boxes)
        except ValueError as exc:  # a bad --boxes file is bad input, as a bad --box is
            raise UsageError(str(exc)) from None
    if args.box is not None:
        return [tuple(args.box)]
    if seq.groundtruth is not None:
        return [tuple(seq.init_box)]
    raise UsageError(f"{args.input} has no ground truth; give the first box with --box x,y,w,h")


def _close_run(args: argparse.Namespace, stop: _StopRequest, reader: Any, error: str | None,
               frames_done: int, targets: int, lines: int, times: list[float],
               skipped: int) -> int:
    """Print the run's one-line summary (and its error); the exit status."""
    if error is None and stop.signum is None and reader.ended_early is not None:
        if args.strict:
            error = f"{reader.ended_early} (--strict)"
        else:
            print(f"wmiltrack: warning: {reader.ended_early}", file=sys.stderr)
    written = error is None or not error.startswith("cannot write")
    where = "" if args.output is None or not written else f", boxes in {args.output}"
    summary = [f"{frames_done} frame{'' if frames_done == 1 else 's'}{where}"]
    if targets:
        summary.append(f"{targets} targets, {lines} lines")
    if times:
        summary.append(f"{len(times) / sum(times):.0f} frames/s (update only)")
    if skipped:
        summary.append(f"{skipped} skipped (could not be used, last box held)")
    if reader.ended_early is not None and stop.signum is None:
        summary.append(reader.ended_early)
    status = EXIT_OK if error is None else EXIT_ERROR
    if error is not None:
        print(f"wmiltrack: error: {error}", file=sys.stderr)
    if stop.signum is not None:  # the interrupt decides the exit status
        status = 128 + stop.signum
        summary.append(f"interrupted by {signal.Signals(stop.signum).name} (exit status {status})")
    if not args.quiet or status != EXIT_OK:
        print(f"wmiltrack: {'; '.join(summary)}", file=sys.stderr)
    return status


def _score_fields(box: Sequence[float], score: float, ok: bool) -> str:
    """The ``,score,ok`` that ``--scores`` adds to a line: the tracker's confidence (1 on the
    first frame, ``nan`` where there is none: OpenCV's trackers, a skipped frame) and 1/0."""
    return f",{score:.4g},{int(bool(ok))}"


def _warn_clipped(given: Sequence[Sequence[float]], used: Sequence[Sequence[float]], fw: int,
                  fh: int, bar: Any) -> None:
    """Warn about each first box that reaches past the frame: the tracker starts from the part
    inside it (rounding to whole pixels alone is not worth a word)."""
    for b, u in zip(given, used):
        x, y, w, h = (float(v) for v in b)
        if x < -0.5 or y < -0.5 or x + w > fw + 0.5 or y + h > fh + 0.5:
            box = ",".join(f"{v:g}" for v in (x, y, w, h))
            kept = ",".join(f"{v:g}" for v in u)
            bar.write(f"wmiltrack: warning: box {box} reaches past the {fw}x{fh} frame; "
                      f"tracking the part inside it, {kept}", file=sys.stderr)


def _read_start_boxes(path: Path) -> list[tuple[float, ...]]:
    """The first boxes of ``--boxes FILE``: one ``x,y,w,h`` line per target (a bad line is
    named as ``FILE:LINE`` by :func:`~wmiltrack.data.boxes.read_boxes`)."""
    from ..data.boxes import read_boxes

    boxes = read_boxes(path)
    if len(boxes) == 0:
        raise ValueError(f"{path} holds no box: write one x,y,w,h line per target")
    return [tuple(float(v) for v in b) for b in boxes]


def _add_target(tracker: Any, frame: Any, box: Sequence[float], k: int, path: Path) -> int:
    """``tracker.add(frame, box)`` for the ``k``-th box of ``--boxes FILE``; a box the tracker
    refuses is named by its line in the file."""
    try:
        return int(tracker.add(frame, box))
    except (ValueError, TypeError) as exc:
        lines = [n for n, text in enumerate(path.read_text(encoding="utf-8-sig").splitlines(), 1)
                 if text.strip()]
        where = f"{path}:{lines[k]}" if k < len(lines) else str(path)
        raise ValueError(f"{where}: {exc}") from None


def _mot_line(index: int, target: int, box: Sequence[float], score: float, held: bool) -> str:
    """A MOTChallenge-style line ``frame,id,x,y,w,h,score,-1,-1,-1``: frame and id count from 1
    (the id is the target's line in ``--boxes``); the score is 1 on the first frame (the given
    box) and -1 on a skipped frame (the last box, held)."""
    from ..data.boxes import format_box

    s = -1.0 if held else (1.0 if index == 0 else score)
    return f"{index + 1},{target + 1},{format_box(box)},{s:.4g},-1,-1,-1"


#: The containers ``--video`` writes, by file extension, with the codec each gets.
VIDEO_CODECS = {".avi": "MJPG", ".mp4": "mp4v"}


def check_video_name(path: Path | None) -> None:
    """A :class:`UsageError` for a ``--video`` name whose extension is not a container the
    writer makes (:data:`VIDEO_CODECS`), said before anything runs; OpenCV's writer would only
    fail to open, without a reason. ``None`` (no ``--video``) passes."""
    if path is not None and path.suffix.lower() not in VIDEO_CODECS:
        kinds = " or ".join(f"{ext} ({codec})" for ext, codec in VIDEO_CODECS.items())
        raise UsageError(f"--video {path}: cannot write a {path.suffix or 'extension-less'} "
                         f"video; name it {kinds}")


def _write_video_frame(writer: Any, path: Path, frame: Any, boxes: Sequence[Sequence[float]],
                       number: int, score: float, fps: float | None,
                       color: tuple[int, int, int] = (0, 255, 0)) -> Any:
    """Add one frame with its boxes to ``--video``; ``number`` counts frames from 1."""
    import cv2
    import numpy as np

    from ..visualize import draw_result

    if writer is None:
        h, w = frame.shape[:2]
        fourcc = cv2.VideoWriter.fourcc(*VIDEO_CODECS[path.suffix.lower()])
        writer = cv2.VideoWriter(str(path), fourcc, float(fps or 25.0), (w, h))
        if not writer.isOpened():
            raise RuntimeError(f"cannot write video {path}: OpenCV's video writer could not open "
                               "it (is its folder there and writable?)")
    img = (frame if frame.ndim == 3 and frame.shape[2] == 3
           else cv2.cvtColor(np.ascontiguousarray(frame), cv2.COLOR_GRAY2BGR))
    for k, box in enumerate(boxes):  # frame number and score written once
        img = draw_result(img, box, index=number if k == 0 else None,
                          score=score if k == 0 else None, color=color)
    writer.write(img)
    return writer


def add_track(sub: Subparsers) -> None:
    """Add the ``track`` subcommand to ``sub``."""
    p = sub.add_parser(
        "track", help="track an object through a video, image folder or OTB sequence",
        description="Track one object. INPUT is a video file, a folder of images, or an OTB "
        "sequence folder (img/ + groundtruth_rect.txt: the first box comes from its ground truth "
        "unless --box is given). Prints or writes one x,y,w,h line per frame, each line as soon "
        "as it is computed, so an interrupted run keeps every box computed; the first line is the "
        "first box as the tracker uses it (rounded to whole pixels, clipped to the frame), and "
        "-o FILE is not touched before it. A frame that cannot "
        "be used (an image file that is truncated or does not decode, an image of another size) "
        "is skipped: its line repeats the last box, a warning names it, and the summary counts "
        "it. A video that stops reading before the frame count its header announces is reported "
        "too.",
        epilog=EXIT_CODES_EPILOG + " For track: skipped frames still give 0; a bad frame "
        "with --strict is 1; SIGTERM gives 143. An interrupt stops after the current frame; the "
        "output then holds one line per frame processed and --video is closed so that it plays. "
        "A second interrupt stops at once (the lines and video already written are still kept). "
        "-o, --video and --list's box files may not be the input or a file of it (its frames, "
        "its ground truth), nor each other (exit status 2, nothing written).")
    p.add_argument("input", type=Path, nargs="?",
                   help="video file, image folder or OTB sequence folder (or give --list)")
    p.add_argument("--box", type=parse_box, help="first box as x,y,w,h (pixels)")
    p.add_argument("--boxes", type=Path, metavar="FILE",
                   help="track several targets: FILE holds one x,y,w,h line per target (on the "
                   "first frame); output lines are MOTChallenge-style frame,id,x,y,w,h,score,-1,-1,-1 "
                   "(frame and id from 1, id = line in FILE), one per target and frame")
    p.add_argument("-o", "--output", type=Path,
                   help="write boxes here (default: print them); with --list, the folder of the "
                   "clips' box files")
    p.add_argument("--list", type=Path, metavar="FILE",
                   help="track many clips: FILE holds one 'PATH x,y,w,h' line per clip (PATH "
                   "relative to FILE's folder); each clip's boxes go to -o DIR/<clip name>.txt "
                   "(clips of one name in different folders: DIR/<folder>_<clip name>.txt) as "
                   "soon as it is finished (written complete, then renamed), and a clip whose box "
                   "file exists is skipped, so running the command again resumes a stopped run")
    p.add_argument("--video", type=Path, help="write a video with the box, frame number and score "
                   "drawn (a skipped frame shows the last good frame with the held box in red)")
    p.add_argument("--scores", action="store_true",
                   help="one target: write x,y,w,h,score,ok lines (score: the tracker's confidence "
                   "in [0, 1], 1 on the first frame, nan where there is none; ok: 1 tracked, 0 "
                   "lost or skipped frame)")
    p.add_argument("-q", "--quiet", action="store_true",
                   help="no progress bar and no summary line (warnings and errors are still shown)")
    p.add_argument("--strict", action="store_true",
                   help="stop with exit status 1 at the first frame that cannot be decoded, or when "
                   "a video ends before the frame count its container announces (default: skip "
                   "the frame, hold the last box, warn)")
    add_tracker_options(p)
    add_model_options(p)
    add_executor_options(p, "the clips")
    p.set_defaults(func=_cmd_track)
