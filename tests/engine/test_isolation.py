"""Determinism and isolation: same seed, same boxes -- across runs, processes and threads.
(Which compiled calls release the GIL: tests/core/test_gil.py.)
"""

from __future__ import annotations

import json
import subprocess
import sys
import threading
from typing import Any

import numpy as np
import pytest

import wmiltrack
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
