"""Two trackers in two threads vs. one after the other: the speed-up of the GIL-free core.

    python benchmarks/threads.py [--frames 150] [--repeats 5] [--variants rcwmil,ct,mil]

Each variant tracks two generated sequences (different seeds) once sequentially and once
in two threads; both runs must give identical boxes. Prints the median wall time of
``--repeats`` runs of each and the ratio. The compiled calls (integral image, projection,
log ratios, grid scoring, feature selection) release the GIL; the numpy glue between them
does not, which bounds the speed-up below 2.
"""

from __future__ import annotations

import argparse
import statistics
import threading

import numpy as np

import wmiltrack
from wmiltrack.data.synthetic import make_sequence
from wmiltrack.timing import gc_paused, timed

Seq = tuple[list[np.ndarray], tuple[float, ...]]


def track(variant: str, seq: Seq) -> list[tuple[float, float, float, float]]:
    """Boxes of one run of ``variant`` over ``seq``."""
    frames, box = seq
    t = wmiltrack.Tracker(variant, seed=0)
    t.init(frames[0], box)
    return [t.box] + [t.update(f).box for f in frames[1:]]


def sequential(variant: str, seqs: list[Seq]) -> tuple[float, list[object]]:
    with gc_paused():
        out, dt = timed(lambda: [track(variant, s) for s in seqs])
    return dt, out


def threaded(variant: str, seqs: list[Seq]) -> tuple[float, list[object]]:
    out: list[object] = [None] * len(seqs)
    barrier = threading.Barrier(len(seqs) + 1)

    def work(i: int) -> None:
        barrier.wait()
        out[i] = track(variant, seqs[i])

    threads = [threading.Thread(target=work, args=(i,)) for i in range(len(seqs))]

    def join_all() -> None:
        for th in threads:
            th.join()

    with gc_paused():
        for th in threads:
            th.start()
        barrier.wait()
        _, dt = timed(join_all)
    return dt, out


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=150)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--variants", default=",".join(sorted(wmiltrack.variants())))
    ap.add_argument("--size", default="240x320", help="frame HxW")
    args = ap.parse_args(argv)
    h, w = (int(v) for v in args.size.split("x"))
    seqs: list[Seq] = []
    for seed in (1, 2):
        s = make_sequence(args.frames, size=(h, w), seed=seed)
        seqs.append((s.load(), tuple(float(v) for v in s.groundtruth[0])))
    print(f"2 trackers x {args.frames} frames of {w}x{h}, median of {args.repeats} runs")
    print(f"{'variant':8s} {'sequential s':>13s} {'2 threads s':>12s} {'speed-up':>9s}")
    for variant in args.variants.split(","):
        seq_t, thr_t = [], []
        want = sequential(variant, seqs)[1]
        for _ in range(args.repeats):
            t, out = sequential(variant, seqs)
            seq_t.append(t)
            t, got = threaded(variant, seqs)
            thr_t.append(t)
            assert got == want == out, f"{variant}: threaded boxes differ from sequential ones"
        s, p = statistics.median(seq_t), statistics.median(thr_t)
        print(f"{variant:8s} {s:13.3f} {p:12.3f} {s / p:8.2f}x", flush=True)


if __name__ == "__main__":
    main()
