"""Frames per second, with mean IoU beside it, of every wmiltrack variant and OpenCV tracker.

Usage::

    python benchmarks/fps_compare.py                 # 3 frame sizes x 3 box sizes, ~2-4 min
    python benchmarks/fps_compare.py --quick         # 2 x 2, fewer frames, < 1 min
    python benchmarks/fps_compare.py --gray          # the same on one-channel gray frames
    PATH/TO/contrib-venv/bin/python benchmarks/fps_compare.py   # all 7 OpenCV trackers
    python benchmarks/fps_compare.py --otb           # real sequences: 4 x their first 120 frames

For each frame size (320x240, 640x480, 1280x720) and target size (32, 64, 128 px) a synthetic
sequence is generated (``wmiltrack.data.synthetic.make_sequence``) and decoded into memory; then
every tracker runs over the same frames ``--repeats`` times (trackers interleaved within each
round).  Every tracker, TrackerMIL (the divisor of the ratios) included, runs in this process
with this ``cv2``, through the same code (:func:`wmiltrack.eval.runner.run_sequence`): the
clock is read around each ``update`` only (after ``init``), and the garbage collector is
handled the same way for every tracker.  OpenCV's thread pool is set to ``--cv-threads``
(default 1, as wmiltrack runs on one core).

Each cell gives the median update-only FPS over the runs and, in brackets, the tracker's mean
IoU with the ground truth on those frames (frames without a box hold the last box, as in
``wmiltrack eval``), so a tracker that loses the target and then returns early does not just
look fast.  A second table divides the FPS by TrackerMIL's on the same frames.  Trackers the
installed ``cv2`` lacks are skipped with a note (run the script with the Python of a venv that
has ``opencv-contrib-python-headless`` and wmiltrack installed to get all seven).

``--otb [ROOT]`` runs on real sequences instead (ROOT: the shared OTB-layout folder, default
``$WMILTRACK_OTB`` or ``../shared/data/otb``): the first ``--frames`` frames (default 120) of each
of ``--sequences`` (default Coke, David, MotorRolling, Skiing: 640x480, 320x240 and two 640x360
clips, boxes from 26 to 125 px), decoded in advance, the same way; the last column, "all",
is the frames of every sequence over the update time of every sequence (each at its median).
"""

from __future__ import annotations

import argparse
import itertools
import json
import math
import os
import platform
import statistics
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

try:
    import wmiltrack  # noqa: F401
except ImportError:  # a checkout that was not installed
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))

from wmiltrack.integrations.opencv_wheels import (
    OPENCV_TRACKERS,
    available_opencv_trackers,
    installed_opencv,
)
from wmiltrack.trackers import parse_spec, split_specs

VARIANTS = ("rcwmil", "ct", "fct", "mil", "wmil", "osil", "rcwmil-plus", "rcwmil-cf", "rcwmil-nano")
REFERENCE = "opencv:MIL"


def simd_path() -> str:
    """The copy of wmiltrack's vectorised kernels that runs here (older versions had none)."""
    from wmiltrack import _core

    path = getattr(_core, "simd_path", None)
    return str(path()) if path is not None else "none (this version predates them)"


def _fmt(v: float, spec: str = ".0f") -> str:
    return "-" if v is None or math.isnan(v) else format(v, spec)


def _parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0] if __doc__ else None)
    ap.add_argument(
        "--quick",
        action="store_true",
        help="320x240 and 640x480, boxes 32 and 64, 30 frames, 2 repeats",
    )
    ap.add_argument("--frames", type=int, default=None, help="frames per run (default 60)")
    ap.add_argument("--repeats", type=int, default=None, help="runs per tracker (default 3)")
    ap.add_argument(
        "--sizes", default=None, help="frame sizes WxH,... (default 320x240,640x480,1280x720)"
    )
    ap.add_argument("--boxes", default=None, help="target sizes in px (default 32,64,128)")
    ap.add_argument(
        "--trackers",
        default=None,
        help="comma-separated subset (default: all variants and OpenCV trackers); "
        "opencv:MIL is always added, being the reference of the ratios",
    )
    ap.add_argument(
        "--cv-threads", type=int, default=1, help="cv2.setNumThreads for OpenCV (default 1)"
    )
    ap.add_argument(
        "--gray",
        action="store_true",
        help="convert the frames to one-channel gray first (every tracker gets the same frames)",
    )
    ap.add_argument(
        "--portable",
        action="store_true",
        help="run wmiltrack's vectorised kernels in their baseline (SSE2) copy even where the CPU "
        "has AVX2 (the boxes are the same; this measures what AVX2 buys)",
    )
    ap.add_argument(
        "--otb", nargs="?", const="", default=None, metavar="ROOT",
        help="real OTB-layout sequences instead of generated ones (ROOT: default "
        "$WMILTRACK_OTB or ../shared/data/otb)",
    )
    ap.add_argument(
        "--sequences", default="Coke,David,MotorRolling,Skiing",
        help="with --otb: comma-separated sequence names (default %(default)s)",
    )
    ap.add_argument("--json", type=Path, default=None, help="also write the figures here")
    return ap


def _can_make(spec: str) -> bool:
    """Whether the tracker can be made here; if not (TrackerNano, NanoTrack or rcwmil-nano
    without their model files, a tracker missing from cv2), a note with the reason."""
    from wmiltrack.integrations.opencv_wheels import TrackerUnavailable
    from wmiltrack.trackers import make_tracker

    try:
        make_tracker(spec)  # a preset's model files are checked as it is made
    except TrackerUnavailable as exc:
        print(f"note: {spec} skipped ({' '.join(str(exc).split())})", file=sys.stderr)
        return False
    return True


def _trackers(ap: argparse.ArgumentParser, chosen: str | None) -> list[str]:
    """The trackers to run: every variant and available OpenCV tracker, or the --trackers
    subset (checked) plus the reference."""
    cv_names = [n for n in available_opencv_trackers() if _can_make(f"opencv:{n}")]
    for n in OPENCV_TRACKERS:
        if n not in available_opencv_trackers():
            print(f"note: opencv:{n} skipped (not in this cv2)", file=sys.stderr)
    trackers = list(VARIANTS) + [f"opencv:{n}" for n in cv_names]
    if not chosen:
        return [t for t in trackers if t.startswith("opencv:") or _can_make(t)]
    wanted = split_specs(chosen)
    known = list(VARIANTS) + [f"opencv:{n}" for n in OPENCV_TRACKERS]

    def valid(spec: str) -> bool:
        if spec in known or spec.startswith("opencv:"):
            return spec in known
        try:  # a variant with settings, e.g. rcwmil-plus:template_weight=0.2
            name, _ = parse_spec(spec)
        except ValueError:
            return False
        return name in VARIANTS or name in ("nanotrack:v2", "nanotrack:v3")

    unknown = [t for t in wanted if not valid(t)]  # unavailable OpenCV ones: noted above
    if unknown:
        ap.error(f"unknown tracker(s): {', '.join(unknown)}; choose from {', '.join(known)}, "
                 "nanotrack:v2, nanotrack:v3 (a variant may carry settings: "
                 "variant:name=value:...)")
    specs = [t for t in wanted if not t.startswith("opencv:") and _can_make(t)]
    return specs + [t for t in trackers if t.startswith("opencv:") and (t in wanted or t == REFERENCE)]


def _clips(ap: argparse.ArgumentParser, args: argparse.Namespace, n_frames: int) -> list[tuple[str, Any]]:
    """(column name, sequence) pairs: the --otb sequences, or generated ones per size."""
    from wmiltrack.data.synthetic import make_sequence

    if args.otb is not None:
        from wmiltrack.data.sequences import default_otb_root, load_otb_sequence

        root = Path(args.otb) if args.otb else default_otb_root()
        names = [n.strip() for n in args.sequences.split(",") if n.strip()]
        missing = [n for n in names if not (root / n).is_dir()]
        if missing:
            ap.error(f"--otb: no sequence {', '.join(missing)} under {root}")
        return [(n, load_otb_sequence(root / n)) for n in names]
    sizes_txt = args.sizes or ("320x240,640x480" if args.quick else "320x240,640x480,1280x720")
    boxes_txt = args.boxes or ("32,64" if args.quick else "32,64,128")
    sizes = [tuple(int(v) for v in s.lower().split("x")) for s in sizes_txt.split(",")]
    box_sizes = [int(b) for b in boxes_txt.split(",")]
    return [
        (f"{w}x{h}/{b}",
         make_sequence(n_frames, size=(h, w), target_size=(b, b), seed=1,
                       name=f"synthetic-{w}x{h}/{b}"))
        for (w, h) in sizes for b in box_sizes
    ]


@dataclass
class _Figures:
    """Per tracker and column: median FPS, mean IoU of the first round, every round's FPS."""

    fps: dict[str, dict[str, float]]
    ious: dict[str, dict[str, float]]
    runs: dict[str, dict[str, list[float]]]
    lengths: dict[str, int]


def _measure(clips: list[tuple[str, Any]], trackers: list[str], n_frames: int, repeats: int,
             gray: bool, t_start: float) -> _Figures:
    """Every tracker over every clip's first n_frames, repeats rounds, trackers interleaved."""
    import cv2

    from wmiltrack.eval.metrics import ope_metrics
    from wmiltrack.eval.runner import run_sequence
    from wmiltrack.eval.scoring import scored_boxes

    out = _Figures({t: {} for t in trackers}, {t: {} for t in trackers}, {t: {} for t in trackers}, {})
    for key, seq in clips:
        frames = list(itertools.islice(seq, n_frames))  # a real sequence: only these decoded
        out.lengths[key] = len(frames)
        if gray:
            frames = [cv2.cvtColor(f, cv2.COLOR_BGR2GRAY) for f in frames]
        assert seq.groundtruth is not None
        gt = np.asarray(seq.groundtruth, dtype=np.float64)[: len(frames)]
        per: dict[str, list[float]] = {t: [] for t in trackers}
        for r in range(repeats):
            for t in trackers:
                run = run_sequence(t, frames, gt[0], seed=0, raise_errors=True)
                per[t].append(run.fps)
                if r == 0:  # same seed every round: the rounds repeat the timing only
                    boxes = scored_boxes(run.boxes, run.oks, missing="hold")
                    out.ious[t][key] = ope_metrics(boxes[1:], gt[1:]).mean_iou
        for t in trackers:
            vals = [v for v in per[t] if not math.isnan(v)]
            out.fps[t][key] = statistics.median(vals) if vals else math.nan
            out.runs[t][key] = per[t]
        print(f"  {key}: done ({time.perf_counter() - t_start:.0f} s)", file=sys.stderr)
    return out


def _add_all_column(fig: _Figures, trackers: list[str], keys: list[str]) -> None:
    """Every sequence's frames over every sequence's update time (each at its median)."""
    frames_total = sum(fig.lengths[k] - 1 for k in keys)
    for t in trackers:
        secs = [(fig.lengths[k] - 1) / fig.fps[t][k] for k in keys]
        fig.fps[t]["all"] = frames_total / sum(secs) if all(x > 0 for x in secs) else math.nan
        fig.ious[t]["all"] = float(np.mean([fig.ious[t][k] for k in keys]))


def _print_tables(fig: _Figures, trackers: list[str], keys: list[str], by_sequence: bool) -> None:
    head = "| Tracker | " + " | ".join(keys) + " |"
    rule = "|---|" + "---:|" * len(keys)
    print("\nUpdate-only FPS (median of runs) and, in brackets, mean IoU on the same frames,")
    print("by sequence:\n" if by_sequence else "by frame size / box size:\n")
    print(head)
    print(rule)
    for t in trackers:
        cells = [f"{_fmt(fig.fps[t][k])} ({_fmt(fig.ious[t][k], '.2f')})" for k in keys]
        print(f"| {t} | " + " | ".join(cells) + " |")
    if REFERENCE in fig.fps:
        print("\nRatio to OpenCV TrackerMIL on the same frames, same process, same run:\n")
        print(head)
        print(rule)
        for t in trackers:
            ref = fig.fps[REFERENCE]
            ratios = [fig.fps[t][k] / ref[k] if ref[k] > 0 else math.nan for k in keys]
            print(f"| {t} | " + " | ".join(_fmt(x, ".1f") for x in ratios) + " |")
    else:
        print(f"\n(no ratios: {REFERENCE} is not available)")


def main(argv: Sequence[str] | None = None) -> int:
    """Run the comparison; return the exit status."""
    ap = _parser()
    args = ap.parse_args(argv)
    if args.portable:
        from wmiltrack import _core

        if not hasattr(_core, "set_simd_portable"):
            ap.error("--portable: this version of wmiltrack has no vectorised kernels")
        _core.set_simd_portable(True)

    import cv2

    from wmiltrack.eval.report import cpu_model
    from wmiltrack.parallel.executors import set_cv_threads

    set_cv_threads(args.cv_threads)
    n_frames = args.frames or (120 if args.otb is not None else 30 if args.quick else 60)
    repeats = args.repeats or (2 if args.quick else 3)
    trackers = _trackers(ap, args.trackers)

    dist, ver = installed_opencv()
    simd = simd_path()
    print(
        f"# {cpu_model()}, {os.cpu_count()} cores; wmiltrack kernels: {simd}; Python "
        f"{platform.python_version()}, numpy "
        f"{np.__version__}, OpenCV {cv2.__version__} ({dist} {ver}), OpenCV threads "
        f"{cv2.getNumThreads()}; {n_frames} {'gray ' if args.gray else ''}frames per run, "
        f"median of {repeats} runs, "
        "update-only FPS; every tracker timed in this process"
    )

    clips = _clips(ap, args, n_frames)
    t_start = time.perf_counter()
    fig = _measure(clips, trackers, n_frames, repeats, args.gray, t_start)
    keys = [key for key, _ in clips]
    if args.otb is not None:
        _add_all_column(fig, trackers, keys)
        keys.append("all")
    _print_tables(fig, trackers, keys, by_sequence=args.otb is not None)
    print(f"\n(wall time {time.perf_counter() - t_start:.0f} s)")
    if args.json is not None:
        doc = {
            "cpu": cpu_model(),
            "cores": os.cpu_count(),
            "simd": simd,
            "python": platform.python_version(),
            "numpy": np.__version__,
            "opencv": f"{cv2.__version__} ({dist} {ver})",
            "opencv_threads": cv2.getNumThreads(),
            "frames": n_frames,
            "gray": args.gray,
            "repeats": repeats,
            "fps_median": fig.fps,
            "mean_iou": fig.ious,
            "fps_runs": fig.runs,
        }
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(
            json.dumps(doc, indent=1, default=lambda o: None).replace("NaN", "null")
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
