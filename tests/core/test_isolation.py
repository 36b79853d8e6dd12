"""Determinism and isolation: same seed, same boxes -- across runs, processes and threads.

Also checks which compiled calls release the GIL: while a long core call runs, a Python
thread must be able to make progress (it cannot while the GIL is held).
"""

from __future__ import annotations

import json
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

import wmiltrack
from wmiltrack import _core, _learn
from wmiltrack.data.synthetic import make_sequence

VARIANTS = sorted(wmiltrack.variants())


def _sequence(n: int = 12, seed: int = 0) -> tuple[list[np.ndarray], tuple[float, ...]]:
    seq = make_sequence(n, size=(120, 160), target_size=(32, 28), seed=seed)
    return seq.load(), tuple(float(v) for v in seq.groundtruth[0])


def _run(variant: str, frames: list[np.ndarray], box: tuple[float, ...], seed: int = 0) -> list[list[float]]:
    t = wmiltrack.Tracker(variant, seed=seed)
    t.init(frames[0], box)
    out = [list(t.box)]
    for f in frames[1:]:
        r = t.update(f)
        out.append([*r.box, r.score])
    return out


@pytest.mark.usefixtures("nano_in_environment")  # (every preset, rcwmil-nano included)
def test_same_seed_same_boxes_in_process() -> None:
    frames, box = _sequence()
    for v in VARIANTS:
        assert _run(v, frames, box) == _run(v, frames, box), v


def test_different_seeds_differ_somewhere() -> None:
    frames, box = _sequence()
    assert any(_run(v, frames, box, seed=0) != _run(v, frames, box, seed=1) for v in VARIANTS)


@pytest.mark.usefixtures("nano_in_environment")
def test_same_seed_same_boxes_across_processes() -> None:
    """A fresh interpreter (new hash seed, new allocations) gives bit-identical boxes and scores."""
    frames, box = _sequence()
    here = {v: _run(v, frames, box) for v in VARIANTS}
    code = (
        "import json, sys; sys.path.insert(0, %r); import test_isolation as m; "
        "frames, box = m._sequence(); "
        "print(json.dumps({v: m._run(v, frames, box) for v in m.VARIANTS}))"
    ) % str(__import__("pathlib").Path(__file__).resolve().parent)
    outs = []
    for hashseed in ("1", "2"):
        proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300,
                              env={**__import__("os").environ, "PYTHONHASHSEED": hashseed})
        assert proc.returncode == 0, proc.stderr[-2000:]
        outs.append(json.loads(proc.stdout.strip().splitlines()[-1]))
    # JSON round-trips doubles exactly (repr is shortest round-trip)
    assert outs[0] == here and outs[1] == here


@pytest.mark.usefixtures("nano_in_environment")
@pytest.mark.parametrize("variant", VARIANTS)
def test_two_threads_match_sequential(variant: str) -> None:
    """Two trackers on two sequences in two threads: the boxes of running them one by one."""
    a = _sequence(10, seed=1)
    b = _sequence(10, seed=2)
    want = [_run(variant, *a), _run(variant, *b)]
    got: list[Any] = [None, None]
    errors: list[BaseException] = []
    barrier = threading.Barrier(2)

    def work(i: int, seq: tuple[list[np.ndarray], tuple[float, ...]]) -> None:
        try:
            barrier.wait()
            got[i] = _run(variant, *seq)
        except BaseException as exc:  # noqa: BLE001 - reported below
            errors.append(exc)

    threads = [threading.Thread(target=work, args=(i, s)) for i, s in enumerate((a, b))]
    for th in threads:
        th.start()
    for th in threads:
        th.join()
    assert not errors, errors
    assert got == want


def test_many_threads_shared_frames() -> None:
    """Four trackers reading the same (read-only) frames concurrently agree with a lone run."""
    frames, box = _sequence(10)
    for f in frames:
        f.setflags(write=False)
    want = _run("rcwmil", frames, box)
    results: list[Any] = []
    lock = threading.Lock()

    def work() -> None:
        r = _run("rcwmil", frames, box)
        with lock:
            results.append(r)

    threads = [threading.Thread(target=work) for _ in range(4)]
    for th in threads:
        th.start()
    for th in threads:
        th.join()
    assert results == [want] * 4


# ------------------------------------------------------------------ which calls release the GIL
def _progress_during(call: Callable[[], object]) -> tuple[int, float]:
    """How far a pure-Python counter thread gets while ``call()`` runs in this thread.

    The counter is read just before and just after the call, with this thread holding the
    GIL both times, so a call that keeps the GIL lets the counter make exactly no progress.
    """
    count = [0]
    stop = threading.Event()
    started = threading.Event()

    def spin() -> None:
        started.set()
        while not stop.is_set():
            count[0] += 1

    old = sys.getswitchinterval()
    sys.setswitchinterval(1e-3)
    th = threading.Thread(target=spin)
    th.start()
    started.wait()
    try:
        before = count[0]
        t0 = time.perf_counter()
        call()
        elapsed = time.perf_counter() - t0
        after = count[0]
    finally:
        stop.set()
        th.join()
        sys.setswitchinterval(old)
    return after - before, elapsed


def _heavy_calls() -> dict[str, Callable[[], object]]:
    rng = np.random.default_rng(0)
    big = rng.integers(0, 256, size=(3000, 3000, 3), dtype=np.uint8)
    ii = _core.IntegralImage()
    ii.compute(big[:600, :600], (0, 0, 600, 600))
    m = 200
    starts = np.arange(0, 3 * m + 1, 3, dtype=np.int32)
    rects = np.tile(np.array([[0, 0, 8, 8], [8, 8, 10, 6], [2, 12, 14, 4]], np.int32), (m, 1))
    bank = _core.FeatureBank(starts, rects, rng.uniform(-1, 1, 3 * m))
    xs, ys = (rng.integers(0, 500, 40000).astype(np.int32) for _ in range(2))
    values = rng.normal(size=(m, 20000)) + 60.0  # far from both means: the exp/log path
    mu, sig = np.zeros(m), np.ones(m)
    sel = np.arange(m, dtype=np.int32)
    h_pos, h_neg = rng.normal(size=(400, 300)), rng.normal(size=(400, 300))
    # WMIL selection is fast (vectorised): a larger problem so that the call lasts > 10 ms.
    w_pos, w_neg = rng.normal(size=(600, 500)), rng.normal(size=(600, 500))
    return {
        # A 3000 x 3000 table now takes ~6 ms (its buffer is reused): four in a row, each of
        # which must release the GIL for the counter to keep up.
        "IntegralImage.compute": lambda: [ii.compute(big, (0, 0, 3000, 3000)) for _ in range(4)],
        "project": lambda: _core.project(ii, bank, xs, ys),
        "log_ratio": lambda: _core.log_ratio(values, mu, sig, mu + 1, sig, 1e-30),
        "score_grid": lambda: [_core.score_grid(ii, bank, sel, mu, sig, mu + 1, sig, 1e-30,
                                                (250, 250, 20, 20), 100, 1, (600, 600))
                               for _ in range(4)],
        "wmil_select": lambda: _learn.wmil_select(w_pos, w_neg, np.full(500, 1 / 500), 600, False),
        "milboost_select": lambda: _learn.milboost_select(h_pos, h_neg, 300, 1e-5),
    }


def _relative_progress(call: Callable[[], object]) -> tuple[float, float]:
    """Counter progress during ``call()`` relative to progress during a sleep of equal length.

    A call that releases the GIL lets the counter thread run about as freely as a sleep
    does (ratio near 1 when a core is free); a call that holds it lets the counter run only
    in the switch windows just before and after it (ratio near 0).
    """
    call()  # warm-up (first touch of the buffers)
    best = 0.0
    elapsed = 0.0
    for _ in range(3):
        progress, elapsed = _progress_during(call)
        free, slept = _progress_during(lambda: time.sleep(elapsed))
        best = max(best, (progress / elapsed) / max(free / slept, 1.0))
    return best, elapsed


@pytest.mark.parametrize("name", ["IntegralImage.compute", "project", "log_ratio", "score_grid", "wmil_select",
                                  "milboost_select"])
def test_core_call_releases_the_gil(name: str) -> None:
    ratio, elapsed = _relative_progress(_heavy_calls()[name])
    assert elapsed > 0.01, f"{name} took {elapsed * 1e3:.2f} ms: too short to tell"
    assert ratio > 0.25, f"{name} ({elapsed * 1e3:.1f} ms) let a Python thread run only {ratio:.0%} as much as a sleep"


def test_gil_probe_sees_a_call_that_holds_the_gil() -> None:
    """Control: one C call that keeps the GIL (builtin ``sum`` over a range) scores near 0.
    The probe keeps the best of three tries (what a releasing call needs); on a loaded machine
    the sleep it is compared with runs slower too, so one try of the control can score high by
    chance: the control keeps the lowest of three probes, which a call that released the GIL
    would still fail."""
    runs = [_relative_progress(lambda: sum(range(3_000_000))) for _ in range(3)]
    assert all(elapsed > 0.01 for _, elapsed in runs)
    assert min(ratio for ratio, _ in runs) < 0.25
