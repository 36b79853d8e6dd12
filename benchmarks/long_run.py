"""A long unattended run: 20 000 frames generated on the fly, peak memory at 1 000 and at the end.

    python benchmarks/long_run.py [--frames 20000] [--variant rcwmil] [--reinits 2000]

Frames are rendered into a reused buffer (a textured target on a slow periodic path over a
fixed background, with noise drawn from a cyclic bank), so the memory measured is the
tracker's, not the data's. Reports peak RSS (``VmHWM`` from ``/proc/self/status``, else
``ru_maxrss``) and current RSS at 1 000 frames and at the end, checks every box lies in
the frame, then re-initialises one tracker ``--reinits`` times and reports RSS growth.
"""

from __future__ import annotations

import argparse
import math
import resource
import time
from collections.abc import Iterator

import numpy as np

import wmiltrack


def _status_kib(field: str) -> int:
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith(field + ":"):
                    return int(line.split()[1])
    except OSError:
        pass
    if field == "VmHWM":
        return int(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)  # KiB on Linux
    return -1


def frames_on_the_fly(n: int, size: tuple[int, int] = (240, 320), target: tuple[int, int] = (40, 36),
                      seed: int = 0) -> Iterator[tuple[np.ndarray, tuple[float, float, float, float]]]:
    """Yield ``(frame, true box)``; the frame is the same buffer each time, overwritten."""
    rng = np.random.default_rng(seed)
    h, w = size
    tw, th = target
    background = np.repeat(np.repeat(rng.integers(0, 256, (h // 8 + 1, w // 8 + 1, 3)), 8, 0), 8, 1)[:h, :w]
    background = background.astype(np.uint8)
    patch = np.repeat(np.repeat(rng.integers(0, 256, (th // 4 + 1, tw // 4 + 1, 3)), 4, 0), 4, 1)[:th, :tw]
    patch = patch.astype(np.uint8)
    patch[th // 3: th // 3 + 6] = 240
    noise = [rng.integers(-6, 7, size=(h, w, 3)).astype(np.int16) for _ in range(16)]
    buf = np.empty((h, w, 3), np.uint8)
    tmp = np.empty((h, w, 3), np.int16)
    cx, cy = (w - tw) / 2, (h - th) / 2
    for i in range(n):
        x = int(round(cx + 0.8 * cx * math.sin(2 * math.pi * i / 997)))
        y = int(round(cy + 0.8 * cy * math.sin(2 * math.pi * i / 1499)))
        np.add(background, noise[i % len(noise)], out=tmp, casting="unsafe")
        tmp[y:y + th, x:x + tw] = patch
        np.clip(tmp, 0, 255, out=tmp)
        buf[...] = tmp
        yield buf, (float(x), float(y), float(tw), float(th))


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=20000)
    ap.add_argument("--variant", default="rcwmil")
    ap.add_argument("--reinits", type=int, default=2000)
    ap.add_argument("--checkpoint", type=int, default=1000)
    args = ap.parse_args(argv)
    print(f"{args.variant}: {args.frames} frames of 320x240 generated on the fly")
    print(f"start: peak RSS {_status_kib('VmHWM') / 1024:.1f} MiB")
    t = wmiltrack.Tracker(args.variant, seed=0)
    lost = 0
    t0 = time.perf_counter()
    for i, (frame, gt) in enumerate(frames_on_the_fly(args.frames)):
        if i == 0:
            t.init(frame, gt)
        else:
            r = t.update(frame)
            x, y, w, h = r.box
            assert 0 <= x and x + w <= 320 and 0 <= y and y + h <= 240, (i, r.box)
            assert math.isfinite(r.score)
            if abs(x - gt[0]) > w / 2 or abs(y - gt[1]) > h / 2:
                lost += 1
        if i + 1 in (args.checkpoint, args.frames):
            print(f"after {i + 1:6d} frames: peak RSS {_status_kib('VmHWM') / 1024:7.1f} MiB, "
                  f"current RSS {_status_kib('VmRSS') / 1024:7.1f} MiB, "
                  f"{(i + 1) / (time.perf_counter() - t0):6.0f} frames/s, "
                  f"{lost} frames with centre error > half the box", flush=True)
    frames = [f.copy() for f, _ in frames_on_the_fly(2)]
    rss0 = _status_kib("VmRSS")
    for k in range(args.reinits):
        t.init(frames[k % 2], (100, 80, 40, 36))
        t.update(frames[1 - k % 2])
    rss1 = _status_kib("VmRSS")
    print(f"{args.reinits} re-inits (+1 update each) of one tracker: RSS {rss0 / 1024:.1f} -> {rss1 / 1024:.1f} MiB "
          f"({(rss1 - rss0):+d} KiB)")


if __name__ == "__main__":
    main()
