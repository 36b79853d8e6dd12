"""Before/after speed of one tracker on a noisy machine: two interpreters, interleaved.

On a shared or virtual machine the speed of whole runs moves by 10-20 % from minute to minute
(another tenant, the host's clock), more than most changes worth measuring. This script starts
one worker process per Python interpreter (each with its own installed wmiltrack: a venv of the
old code and one of the new), hands them chunks of the same work in turn (``--chunk`` updates of
one sequence, the sequences in rotation, the order within a pair alternated), for ``--seconds``,
and prints the ratio of their times: a burst of noise falls on both alike.

    python benchmarks/interleaved.py OLD_PYTHON NEW_PYTHON --otb ../shared/data/otb \\
        [--sequences Coke,David,Girl,Car4] [--frames 120] [--tracker rcwmil-cf] [--seconds 60]
    python benchmarks/interleaved.py OLD_PYTHON NEW_PYTHON --generated 640x480/64,640x480/128

Each worker decodes the sequences' first ``--frames`` frames beforehand (or generates them:
``--generated WxH/BOX,...``, as ``fps_compare.py --sizes WxH --boxes BOX`` does), times only
``Tracker.update`` (OpenCV on one thread) and starts the tracker again at a sequence's end.

Both workers run on one core (``--cpu``, by default the last one this process may use; ``-1``
lets the system place them): left to the system, each may sit on a core of its own whose
neighbours differ, and one interpreter against itself then measured anywhere from 0.96 to 1.05
in runs of 30 s on our 2-core VM; pinned, from 0.992 to 1.002 (Linux only; elsewhere the
workers are not pinned).
"""

from __future__ import annotations

import argparse
import os
import re
import statistics
import subprocess
import sys
import time

WORKER = r"""
import os, sys, time
import cv2
import wmiltrack
from wmiltrack.data.sequences import load_dataset
from wmiltrack.trackers import parse_spec

cv2.setNumThreads(1)
root, names, frames, spec, chunk = sys.argv[1], sys.argv[2].split(","), int(sys.argv[3]), sys.argv[4], int(sys.argv[5])
cpu = int(sys.argv[6])
if cpu >= 0 and hasattr(os, "sched_setaffinity"):
    os.sched_setaffinity(0, {cpu})
variant, overrides = parse_spec(spec)
if root:
    data = [(s.load()[:frames + 1], s.init_box) for s in (load_dataset(root, [n])[0] for n in names)]
else:  # generated: names are WxH/BOX
    from wmiltrack.data.synthetic import make_sequence
    data = []
    for n in names:
        (w, h), b = (int(v) for v in n.split("/")[0].split("x")), int(n.split("/")[1])
        s = make_sequence(frames + 1, size=(h, w), target_size=(b, b), seed=1)
        data.append((s.load(), s.init_box))

def start(k):
    fr, box = data[k]
    t = wmiltrack.Tracker(variant, seed=0, **overrides)
    t.init(fr[0], box)
    return [t, 1]

state = [start(k) for k in range(len(data))]
print("ready", flush=True)
for line in sys.stdin:
    k = int(line)
    fr = data[k][0]
    t0 = time.perf_counter()
    for _ in range(chunk):
        if state[k][1] >= len(fr):
            t1 = time.perf_counter()
            state[k] = start(k)
            t0 += time.perf_counter() - t1  # a restart is not timed
        state[k][0].update(fr[state[k][1]])
        state[k][1] += 1
    print(time.perf_counter() - t0, flush=True)
"""


def _start(pythons: tuple[str, str], argv: list[str]) -> list[subprocess.Popen[str]]:
    """One worker per interpreter, each ready (its sequences decoded, its trackers started)."""
    procs: list[subprocess.Popen[str]] = []
    for py in pythons:
        try:
            procs.append(subprocess.Popen([py, "-c", WORKER, *argv], stdin=subprocess.PIPE,
                                          stdout=subprocess.PIPE, text=True))
        except OSError as e:
            for p in procs:
                p.kill()
            raise SystemExit(f"cannot run {py}: {e.strerror}") from None
    for py, p in zip(pythons, procs):
        assert p.stdout is not None
        if p.stdout.readline().strip() != "ready":
            for q in procs:
                q.kill()
            raise SystemExit(f"{py}: the worker did not start (its error is above)")
    return procs


def _turns(procs: list[subprocess.Popen[str]], pythons: tuple[str, str], sequences: int,
           seconds: float) -> list[list[float]]:
    """Each worker's chunk times, the workers taking turns (the order within a pair
    alternated) over the sequences in rotation, for ``seconds``."""
    times: list[list[float]] = [[], []]
    end, turn = time.monotonic() + seconds, 0
    while time.monotonic() < end:
        for j in ((0, 1) if turn % 2 == 0 else (1, 0)):
            p = procs[j]
            assert p.stdin is not None and p.stdout is not None
            p.stdin.write(f"{turn % sequences}\n")
            p.stdin.flush()
            answer = p.stdout.readline()
            if not answer:
                raise SystemExit(f"{pythons[j]}: the worker stopped (its error is above)")
            times[j].append(float(answer))
        turn += 1
    return times


def _last_cpu() -> int:
    """The last core this process may run on (-1 where the system cannot say)."""
    if not hasattr(os, "sched_getaffinity"):
        return -1
    return max(os.sched_getaffinity(0))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("old", help="the Python interpreter of the old code")
    ap.add_argument("new", help="the Python interpreter of the new code")
    ap.add_argument("--otb", default=os.environ.get("WMILTRACK_OTB"),
                    help="OTB-layout folder (default: $WMILTRACK_OTB)")
    ap.add_argument("--generated", default=None,
                    help="generated frames instead: comma-separated WxH/BOX (e.g. 640x480/64)")
    ap.add_argument("--sequences", default="Coke,David,Girl,Car4")
    ap.add_argument("--frames", type=int, default=120)
    ap.add_argument("--tracker", default="rcwmil-cf", help="a spec, as wmiltrack eval takes it")
    ap.add_argument("--chunk", type=int, default=30, help="updates per turn")
    ap.add_argument("--seconds", type=float, default=60.0)
    ap.add_argument("--cpu", type=int, default=_last_cpu(),
                    help="the core both workers run on (-1: not pinned; default: the last one "
                         "this process may use)")
    args = ap.parse_args(argv)
    if args.generated:
        args.otb, args.sequences = "", args.generated
        if not all(re.fullmatch(r"\d+x\d+/\d+", g) for g in args.generated.split(",")):
            ap.error(f"--generated takes WxH/BOX items, got {args.generated!r}")
    elif not args.otb:
        ap.error("give --otb (or set WMILTRACK_OTB) or --generated")
    if args.frames < 1 or args.chunk < 1 or args.seconds <= 0:
        ap.error("--frames and --chunk must be >= 1 and --seconds > 0")
    names = args.sequences.split(",")
    pythons = (args.old, args.new)
    if args.cpu >= 0 and hasattr(os, "sched_getaffinity") and args.cpu not in os.sched_getaffinity(0):
        ap.error(f"--cpu {args.cpu}: not a core this process may use "
                 f"({sorted(os.sched_getaffinity(0))})")
    procs = _start(pythons, [args.otb, args.sequences, str(args.frames), args.tracker,
                             str(args.chunk), str(args.cpu)])
    try:
        times = _turns(procs, pythons, len(names), args.seconds)
    finally:
        for p in procs:
            if p.stdin is not None:
                p.stdin.close()
            p.wait()
    old, new = (sum(t) for t in times)
    updates = len(times[0]) * args.chunk
    pairs = [b / a for a, b in zip(*times)]
    where = f"core {args.cpu}" if args.cpu >= 0 and hasattr(os, "sched_setaffinity") else "not pinned"
    print(f"{args.tracker} on {args.sequences} ({args.frames} frames each; {where}), {len(pairs)} turns "
          f"of {args.chunk} updates each: old {updates / old:.0f} updates/s, new "
          f"{updates / new:.0f} updates/s; new / old time: {new / old:.3f} in all, "
          f"{statistics.median(pairs):.3f} as the median of the turns")
    return 0


if __name__ == "__main__":
    sys.exit(main())
