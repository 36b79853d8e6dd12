"""Frames per second of every wmiltrack variant and OpenCV tracker on the same frames.

Usage::

    python benchmarks/fps_compare.py                 # 3 frame sizes x 3 box sizes, ~2-4 min
    python benchmarks/fps_compare.py --quick         # 2 x 2, fewer frames, < 1 min
    python benchmarks/fps_compare.py --cv-python PATH/TO/contrib-venv/bin/python

For each frame size (320x240, 640x480, 1280x720) and target size (32, 64, 128 px) a synthetic
sequence is generated (``wmiltrack.data.synthetic.make_sequence``) and decoded into memory; then
every tracker runs over the same frames ``--repeats`` times (trackers interleaved within each
round), timing ``update`` alone.  The table gives the median update-only FPS over the runs,
and a second table divides it by OpenCV's TrackerMIL's on the same frames.  Trackers the
installed ``cv2`` lacks are skipped with a note.

``--cv-python PY`` times the OpenCV trackers in another interpreter (for instance a venv with
``opencv-contrib-python-headless``, which has KCF, CSRT, MOSSE, MedianFlow, TLD and Boosting);
the frames are handed over in a temporary ``.npy`` file and that interpreter only needs
numpy and cv2.  The wmiltrack variants are timed in this process either way, one after the
other on the same machine, so the ratios compare like with like.
"""

from __future__ import annotations

import argparse
import gc
import json
import math
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

OPENCV = ("MIL", "KCF", "CSRT", "MOSSE", "MedianFlow", "TLD", "Boosting")
VARIANTS = ("rcwmil", "ct", "fct", "mil", "wmil", "osil", "rcwmil-plus")
Frame = npt.NDArray[np.uint8]


# --------------------------------------------------------------------- OpenCV (numpy + cv2 only)
def _cv_factory(name: str) -> Any:
    import cv2

    for mod in (cv2, getattr(cv2, "legacy", None)):
        f = getattr(mod, f"Tracker{name}_create", None) if mod is not None else None
        if f is not None:
            return f
    return None


def time_opencv(name: str, frames: Sequence[Frame], box: Sequence[float]) -> float:
    """Update-only FPS of OpenCV's tracker ``name`` (NaN if it is not in this cv2)."""
    import cv2

    create = _cv_factory(name)
    if create is None:
        return math.nan
    cv2.setRNGSeed(0)
    tracker = create()
    tracker.init(frames[0], tuple(round(v) for v in box))
    total = 0.0
    gc.collect()
    gc.disable()
    try:
        for frame in frames[1:]:
            t0 = time.perf_counter()
            tracker.update(frame)
            total += time.perf_counter() - t0
    finally:
        gc.enable()
    return (len(frames) - 1) / total if total > 0 else math.nan


def _worker(path: str, names: str, box: str) -> int:
    frames = list(np.load(path))
    b = [float(v) for v in box.split(",")]
    out = {n: time_opencv(n, frames, b) for n in names.split(",") if n}
    print(json.dumps({k: (None if math.isnan(v) else v) for k, v in out.items()}))
    return 0


def _cv_available_here() -> list[str]:
    try:
        return [n for n in OPENCV if _cv_factory(n) is not None]
    except ImportError:
        return []


def _cv_available_in(python: str) -> list[str]:
    code = (
        f"import cv2;print(','.join(n for n in {OPENCV!r} if any(getattr(m,'Tracker'+n+'_create',"
        "None) for m in (cv2,getattr(cv2,'legacy',None)) if m is not None)))"
    )
    res = subprocess.run([python, "-c", code], capture_output=True, text=True, check=True)
    return [n for n in res.stdout.strip().split(",") if n]


# --------------------------------------------------------------------- main
def _time_variant(name: str, frames: Sequence[Frame], box: Sequence[float]) -> float:
    from wmiltrack.eval.runner import run_sequence

    run = run_sequence(name, frames, box, seed=0, raise_errors=True)
    return run.fps


def _fmt(v: float, spec: str = ".0f") -> str:
    return "-" if v is None or math.isnan(v) else format(v, spec)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the comparison; return the exit status."""
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
        help="comma-separated subset (default: all variants and OpenCV trackers)",
    )
    ap.add_argument(
        "--cv-python",
        default=None,
        help="time the OpenCV trackers with this Python (e.g. a contrib venv)",
    )
    ap.add_argument("--json", type=Path, default=None, help="also write the figures here")
    ap.add_argument("--worker", nargs=3, metavar=("NPY", "NAMES", "BOX"), help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.worker:
        return _worker(*args.worker)

    try:
        import wmiltrack  # noqa: F401
    except ImportError:  # a checkout that was not installed
        sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))
    import cv2

    from wmiltrack.data.synthetic import make_sequence
    from wmiltrack.eval.runner import cpu_model

    n_frames = args.frames or (30 if args.quick else 60)
    repeats = args.repeats or (2 if args.quick else 3)
    sizes_txt = args.sizes or ("320x240,640x480" if args.quick else "320x240,640x480,1280x720")
    boxes_txt = args.boxes or ("32,64" if args.quick else "32,64,128")
    sizes = [tuple(int(v) for v in s.lower().split("x")) for s in sizes_txt.split(",")]
    box_sizes = [int(b) for b in boxes_txt.split(",")]

    cv_names = _cv_available_in(args.cv_python) if args.cv_python else _cv_available_here()
    where = f"{args.cv_python}" if args.cv_python else "this Python"
    for n in OPENCV:
        if n not in cv_names:
            print(f"note: opencv:{n} skipped (not in the cv2 of {where})", file=sys.stderr)
    trackers = list(VARIANTS) + [f"opencv:{n}" for n in cv_names]
    if args.trackers:
        wanted = [t.strip() for t in args.trackers.split(",") if t.strip()]
        trackers = [t for t in trackers if t in wanted]
        if "opencv:MIL" in [f"opencv:{n}" for n in cv_names] and "opencv:MIL" not in trackers:
            trackers.append("opencv:MIL")  # the reference of the ratios
    cv_trackers = [t.split(":", 1)[1] for t in trackers if t.startswith("opencv:")]
    wm_trackers = [t for t in trackers if not t.startswith("opencv:")]

    opencv_ver = cv2.__version__
    if args.cv_python:
        opencv_ver += (
            " (OpenCV trackers: "
            + subprocess.run(
                [args.cv_python, "-c", "import cv2;print(cv2.__version__)"],
                capture_output=True,
                text=True,
                check=True,
            ).stdout.strip()
            + ", contrib)"
        )
    print(
        f"# {cpu_model()}, {os.cpu_count()} cores; Python {platform.python_version()}, numpy "
        f"{np.__version__}, OpenCV {opencv_ver}; {n_frames} frames per run, median of "
        f"{repeats} runs, update-only FPS"
    )

    combos = [(w, h, b) for (w, h) in sizes for b in box_sizes]
    fps: dict[str, dict[str, float]] = {t: {} for t in trackers}
    runs: dict[str, dict[str, list[float]]] = {t: {} for t in trackers}
    t_start = time.perf_counter()
    for w, h, b in combos:
        key = f"{w}x{h}/{b}"
        seq = make_sequence(
            n_frames, size=(h, w), target_size=(b, b), seed=1, name=f"synthetic-{key}"
        )
        frames = seq.load()
        assert seq.groundtruth is not None
        box = [float(v) for v in seq.groundtruth[0]]
        per: dict[str, list[float]] = {t: [] for t in trackers}
        tmp: str | None = None
        if args.cv_python and cv_trackers:
            fd, tmp = tempfile.mkstemp(suffix=".npy")
            os.close(fd)
            np.save(tmp, np.stack(frames))
        try:
            for _ in range(repeats):
                for t in wm_trackers:
                    per[t].append(_time_variant(t, frames, box))
                if not cv_trackers:
                    continue
                if tmp is not None:
                    assert args.cv_python is not None
                    res = subprocess.run(
                        [
                            args.cv_python,
                            __file__,
                            "--worker",
                            tmp,
                            ",".join(cv_trackers),
                            ",".join(repr(v) for v in box),
                        ],
                        capture_output=True,
                        text=True,
                        check=True,
                    )
                    got = json.loads(res.stdout.strip().splitlines()[-1])
                    for n in cv_trackers:
                        v = got.get(n)
                        per[f"opencv:{n}"].append(math.nan if v is None else float(v))
                else:
                    for n in cv_trackers:
                        per[f"opencv:{n}"].append(time_opencv(n, frames, box))
        finally:
            if tmp is not None:
                os.unlink(tmp)
        for t in trackers:
            vals = [v for v in per[t] if not math.isnan(v)]
            fps[t][key] = statistics.median(vals) if vals else math.nan
            runs[t][key] = per[t]
        print(f"  {key}: done ({time.perf_counter() - t_start:.0f} s)", file=sys.stderr)

    keys = [f"{w}x{h}/{b}" for w, h, b in combos]
    head = "| Tracker | " + " | ".join(keys) + " |"
    rule = "|---|" + "---:|" * len(keys)
    print("\nUpdate-only FPS (median of runs), by frame size / box size:\n")
    print(head)
    print(rule)
    for t in trackers:
        print(f"| {t} | " + " | ".join(_fmt(fps[t][k]) for k in keys) + " |")
    ref = "opencv:MIL"
    if ref in fps:
        print("\nRatio to OpenCV TrackerMIL on the same frames:\n")
        print(head)
        print(rule)
        for t in trackers:
            ratios = [fps[t][k] / fps[ref][k] if fps[ref][k] > 0 else math.nan for k in keys]
            print(f"| {t} | " + " | ".join(_fmt(r, ".1f") for r in ratios) + " |")
    else:
        print("\n(no ratios: opencv:MIL is not available)")
    print(f"\n(wall time {time.perf_counter() - t_start:.0f} s)")
    if args.json is not None:
        doc = {
            "cpu": cpu_model(),
            "cores": os.cpu_count(),
            "python": platform.python_version(),
            "numpy": np.__version__,
            "opencv": opencv_ver,
            "frames": n_frames,
            "repeats": repeats,
            "fps_median": fps,
            "fps_runs": runs,
        }
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(
            json.dumps(doc, indent=1, default=lambda o: None).replace("NaN", "null")
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
