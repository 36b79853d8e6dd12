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
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from types import FrameType
from typing import IO, Any

from .options import (
    Subparsers,
    UsageError,
    add_executor_options,
    add_tracker_options,
    open_frames,
    parse_box,
    parse_overrides,
    tracker_from_args,
)

EXIT_OK = 0
EXIT_ERROR = 1
EXIT_USAGE = 2
EXIT_SIGINT = 128 + int(signal.SIGINT)    # 130
EXIT_SIGTERM = 128 + int(signal.SIGTERM)  # 143

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

    The file is opened (and an existing one emptied) at the first line, once the first frame
    and box are known to be good: a run that fails before it starts leaves the file as it was.
    """

    def __init__(self, path: Path | None) -> None:
        from ..data.boxes import format_box

        self.path = path
        self.count = 0
        self._fh: IO[str] | None = None
        self._format: Callable[[Sequence[float]], str]
        if path is None:
            self._fh = sys.stdout
            self._format = lambda box: ",".join(f"{float(v):g}" for v in box)
        else:
            self._format = format_box

    def write(self, box: Sequence[float]) -> None:
        self.write_line(self._format(box))

    def write_line(self, line: str) -> None:
        """One line (of one frame), flushed at once."""
        if self._fh is None:
            assert self.path is not None
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self._fh = self.path.open("w", encoding="utf-8")
        self._fh.write(line + "\n")
        self._fh.flush()
        self.count += 1

    def close(self) -> None:
        if self.path is not None and self._fh is not None:
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


def _track_list(args: argparse.Namespace) -> int:
    """``track --list FILE -o DIR``: every clip of the list on the chosen executor; each box
    file written as its clip finishes; clips whose box file exists are skipped (resume)."""
    from ..batch import ClipResult, describe_clip, failed_clip, read_clip_list, track_clips
    from ..executors import make_executor
    from ..progress import progress

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
    tracker_from_args(args)  # an unknown tracker or parameter is a usage error before any clip runs
    clips = read_clip_list(args.list, args.output)
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
                                  overrides=parse_overrides(args.set), wrap=bar):
            if result.error is None:
                tracked += 1
            else:
                failed.append(result)
                print(f"wmiltrack: error: {result.clip.label}: {result.error}", file=sys.stderr)
    except KeyboardInterrupt:
        interrupted = True
    summary = [f"{len(clips)} clips: {tracked} tracked"]
    if done:
        summary.append(f"{done} already done (their box files exist)")
    if failed:
        summary.append(f"{len(failed)} failed")
    left = len(clips) - done - tracked - len(failed)
    if interrupted:
        summary.append(f"interrupted with {left} not done: run the same command again to resume")
    print(f"wmiltrack: {'; '.join(summary)}; boxes in {args.output}", file=sys.stderr)
    if interrupted:
        return EXIT_SIGINT
    return EXIT_ERROR if failed else EXIT_OK


def _track(args: argparse.Namespace, stop: _StopRequest) -> int:
    from ..data.sequences import TolerantFrames
    from ..engine.frames import clip_box
    from ..progress import progress

    if args.boxes is not None and args.box is not None:
        raise UsageError("give either --box (one target) or --boxes (several), not both")
    several = args.boxes is not None
    tracker: Any = tracker_from_args(args, several=several)
    seq = open_frames(args.input, has_box=args.box is not None or several)
    starts = _start_boxes(args, seq)
    box = starts[0]
    ids: list[int] = []
    reader = TolerantFrames(seq)
    frames = iter(reader)
    out = _BoxLines(args.output)  # the file is opened at the first box, not before
    bar = progress(frames, total=reader.expected, desc=f"{args.tracker} {seq.name}")
    writer = None
    skipped = 0
    times: list[float] = []
    error: str | None = None
    last_boxes: list[tuple[float, ...]] = []
    last_frame: Any = None
    frames_done = 0
    try:
        for i, frame, problem in bar:
            if stop.signum is not None:  # a signal came before the first frame
                break
            color = (0, 255, 0)
            if frame is None:
                if i == 0:
                    raise ValueError(f"frame 1 cannot be used ({problem}), and the first box "
                                     "belongs to it")
                if args.strict:
                    error = f"frame {i + 1}: {problem} (--strict)"
                    break
                skipped += 1
                bar.write(f"wmiltrack: warning: frame {i + 1} skipped, last box held: {problem}",
                          file=sys.stderr)
                shown, color = last_frame, _HELD_COLOR
                boxes, scores = last_boxes, [math.nan] * len(last_boxes)
            elif i == 0:
                if several:
                    ids = [_add_target(tracker, frame, b, k, args.boxes) for k, b in enumerate(starts)]
                else:
                    tracker.init(frame, box)
                # the boxes the trackers start from: rounded to whole pixels, clipped to the frame
                fw, fh = frame.shape[1], frame.shape[0]
                boxes = [tuple(float(v) for v in clip_box(b, fw, fh)) for b in starts]
                scores, shown = [math.nan] * len(boxes), frame
            else:
                t0 = time.perf_counter()
                if several:
                    results = tracker.update(frame)
                    found = [results[k] for k in ids]
                else:
                    found = [tracker.update(frame)]
                times.append(time.perf_counter() - t0)
                boxes = [tuple(r.box) for r in found]
                scores, shown = [r.score for r in found], frame
            if several:
                for k, (b, s) in enumerate(zip(boxes, scores)):
                    out.write_line(_mot_line(i, k, b, s, held=frame is None))
            else:
                out.write(boxes[0])
            frames_done += 1
            if args.video is not None:
                writer = _write_video_frame(writer, args.video, shown, boxes, i + 1,
                                            scores[0] if not several else math.nan, seq.fps, color)
            last_boxes, last_frame = boxes, shown
            if stop.signum is not None:
                break
    except KeyboardInterrupt:  # a second SIGINT/SIGTERM while a frame was being processed
        if stop.signum is None:  # not from our handler (not installed outside the main thread)
            stop.signum = int(signal.SIGINT)
    except OSError as exc:  # writing the boxes failed (disk full, closed pipe, ...)
        error = f"cannot write the boxes: {exc}"
    finally:
        stop.hurry = False  # a signal now must not cut the closing of the output and video
        bar.close()
        frames.close()
        seq.close()
        if writer is not None:
            writer.release()
        try:
            out.close()
        except OSError as exc:
            error = error or f"cannot write the boxes: {exc}"

    return _close_run(args, stop, reader, error, frames_done, len(starts) if several else 0,
                      out.count, times, skipped)


def _start_boxes(args: argparse.Namespace, seq: Any) -> list[tuple[float, ...]]:
    """The first box of each target: --boxes, --box, or the sequence's ground truth."""
    if args.boxes is not None:
        return _read_start_boxes(args.boxes)
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
    where = "" if args.output is None else f", boxes in {args.output}"
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
    print(f"wmiltrack: {'; '.join(summary)}", file=sys.stderr)
    return status


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


def _write_video_frame(writer: Any, path: Path, frame: Any, boxes: Sequence[Sequence[float]],
                       number: int, score: float, fps: float | None,
                       color: tuple[int, int, int] = (0, 255, 0)) -> Any:
    """Add one frame with its boxes to ``--video``; ``number`` counts frames from 1."""
    import cv2
    import numpy as np

    from ..visualize import draw_result

    if writer is None:
        h, w = frame.shape[:2]
        fourcc = cv2.VideoWriter.fourcc(*("mp4v" if str(path).lower().endswith(".mp4") else "MJPG"))
        writer = cv2.VideoWriter(str(path), fourcc, float(fps or 25.0), (w, h))
        if not writer.isOpened():
            raise RuntimeError(f"cannot write video {path}")
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
        epilog="Exit status: 0 done (skipped frames included); 1 error, including a bad frame "
        "with --strict or an output that cannot be written; 2 bad command line (also an unknown "
        "tracker or parameter, or a bad --set value); 130 interrupted "
        "by SIGINT (Ctrl-C), 143 by SIGTERM. An interrupt stops after the current frame; the "
        "output then holds one line per frame processed and --video is closed so that it plays. "
        "A second interrupt stops at once (the lines and video already written are still kept).")
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
                   "relative to FILE's folder); each clip's boxes go to -o DIR/<clip name>.txt as "
                   "soon as it is finished (written complete, then renamed), and a clip whose box "
                   "file exists is skipped, so running the command again resumes a stopped run")
    p.add_argument("--video", type=Path, help="write a video with the box, frame number and score "
                   "drawn (a skipped frame shows the last good frame with the held box in red)")
    p.add_argument("--strict", action="store_true",
                   help="stop with exit status 1 at the first frame that cannot be decoded, or when "
                   "a video ends before the frame count its container announces (default: skip "
                   "the frame, hold the last box, warn)")
    add_tracker_options(p)
    add_executor_options(p, "the clips")
    p.set_defaults(func=_cmd_track)
