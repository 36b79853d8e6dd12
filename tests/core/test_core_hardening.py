"""Issue 12: the compiled core on its own, under threads, hostile arguments and other CPUs.

``wmiltrack._core`` is public, so these tests drive it directly (not through ``Tracker``).
The thread tests run in a subprocess: on a core that is not safe they may crash the
interpreter (a read of freed or out-of-bounds memory), which must fail the test rather than
the whole test session.
"""
from __future__ import annotations

import platform
import re
import shutil
import subprocess
import sys
import textwrap
import threading
import tracemalloc
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import wmiltrack
from wmiltrack import _core
from wmiltrack.data.synthetic import make_preset

BANK = dict(starts=np.array([0, 1, 3], np.int32),
            rects=np.array([[1, 2, 5, 4], [0, 0, 3, 3], [4, 4, 6, 2]], np.int32),
            weights=np.array([1.0, 0.5, -2.0]))
WEAK = dict(mu1=np.array([100.0, 20.0]), sigma1=np.array([50.0, 30.0]),
            mu0=np.array([-50.0, 0.0]), sigma0=np.array([60.0, 20.0]))


def bank() -> _core.FeatureBank:
    return _core.FeatureBank(BANK["starts"], BANK["rects"], BANK["weights"])


def computed(frame: np.ndarray | None = None) -> _core.IntegralImage:
    if frame is None:
        frame = np.random.default_rng(0).integers(0, 256, (60, 80, 3), dtype=np.uint8)
    ii = _core.IntegralImage()
    ii.compute(frame, (0, 0, frame.shape[1], frame.shape[0]))
    return ii


def run_script(code: str, timeout: float = 240.0) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True,
                          text=True, timeout=timeout)


# ---------------------------------------------------------------- 3. never computed
def test_uncomputed_integral_image_refuses_every_member() -> None:
    ii = _core.IntegralImage()
    assert ii.computed is False
    frame = np.zeros((20, 20), np.uint8)
    calls = {
        "rect_sum": lambda: ii.rect_sum(0, 0, 0, 0),
        "table": lambda: ii.table(),
        "table(1)": lambda: ii.table(1),
        "x0": lambda: ii.x0, "y0": lambda: ii.y0, "width": lambda: ii.width,
        "height": lambda: ii.height, "num_channels": lambda: ii.num_channels,
        "channels": lambda: ii.channels,
        "project": lambda: _core.project(ii, bank(), np.zeros(1, np.int32), np.zeros(1, np.int32)),
        "score_grid": lambda: _core.score_grid(ii, bank(), np.array([0, 1], np.int32), *WEAK.values(),
                                               1e-30, (0, 0, 4, 4), 3, 1, (20, 20)),
    }
    for name, call in calls.items():
        with pytest.raises(ValueError, match="not been computed"):
            call()
        assert name  # each call raised
    # A failed first compute leaves it uncomputed; a good one makes it usable.
    with pytest.raises(ValueError):
        ii.compute(frame, (100, 100, 5, 5))
    assert ii.computed is False
    ii.compute(frame, (0, 0, 20, 20))
    assert ii.computed and ii.rect_sum(0, 0, 0, 0) == 0.0 and ii.table().shape == (21, 21)


# ---------------------------------------------------------------- 8. exceptions
def test_failed_compute_leaves_the_object_unchanged() -> None:
    frame = np.random.default_rng(1).integers(0, 256, (1000, 1000, 3), dtype=np.uint8)
    ii = _core.IntegralImage()
    ii.compute_channels(frame, (10, 20, 30, 40), [_core.CH_LUMA, _core.CH_GRAD])
    state = (ii.x0, ii.y0, ii.width, ii.height, ii.channels)
    tables = [ii.table(0), ii.table(1)]
    # 1001 * 1001 * 8 bytes * 200000 planes = 1.6 TB: the allocation fails.
    with pytest.raises(MemoryError):
        ii.compute_channels(frame, (0, 0, 1000, 1000), [_core.CH_LUMA] * 200_000)
    # Bad arguments after the size is known: a colour channel of a gray frame, a missed ROI.
    with pytest.raises(ValueError):
        ii.compute_channels(frame[..., 0], (0, 0, 1000, 1000), [_core.CH_LUMA, _core.CH_OPP_RG])
    with pytest.raises(ValueError):
        ii.compute(frame, (5000, 0, 10, 10))
    assert (ii.x0, ii.y0, ii.width, ii.height, ii.channels) == state
    for k, t in enumerate(tables):
        np.testing.assert_array_equal(ii.table(k), t)
    assert ii.rect_sum(10, 20, 30, 40, 1) == tables[1][-1, -1]


# ---------------------------------------------------------------- 4. validate first
def test_score_grid_validates_radius_before_allocating() -> None:
    ii, fb, sel = computed(), bank(), np.array([0, 1], np.int32)
    args = (*WEAK.values(), 1e-30, (10, 10, 8, 8))
    tracemalloc.start()
    try:
        for radius in (5000, 50_000, 2**31 - 1):  # today: 0.8 GB, 80 GB, an overflowing side
            with pytest.raises(ValueError, match=r"radius must be in 1 \.\. 4096"):
                _core.score_grid(ii, fb, sel, *args, radius, 1, (80, 60), True)
        with pytest.raises(ValueError, match="step must be >= 1"):
            _core.score_grid(ii, fb, sel, *args, 5, 0, (80, 60), True)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < 1 << 20, f"{peak} bytes allocated before the radius was refused"
    # The largest radius is accepted (the grid is (2 * 4095 + 1)^2 with step 1; step 64 here).
    assert _core.score_grid(ii, fb, sel, *args, 4096, 64, (80, 60), True)[4].shape == (127, 127)


# ---------------------------------------------------------------- 5. no silent conversion
def test_coordinates_are_never_wrapped_or_truncated() -> None:
    ii, fb = computed(), bank()
    xs, ys = np.array([0, 10, 30], np.int32), np.array([0, 20, 40], np.int32)
    want = _core.project(ii, fb, xs, ys)
    # Exact conversions are accepted: wider ints in range, integral floats, lists.
    for cx, cy in [(xs.astype(np.int64), ys.astype(np.int64)), (xs.astype(np.uint16), ys),
                   (xs.astype(np.float64), ys.astype(np.float32)), (xs.tolist(), ys.tolist())]:
        np.testing.assert_array_equal(_core.project(ii, fb, cx, cy), want)
    np.testing.assert_array_equal(_core.project(ii, fb, xs, ys, np.array([1.0])), want[1:])
    # 2**32 would wrap to 0 (inside the table) and 0.5 truncate to 0: both refused.
    bad = [np.array([2**32, 0, 0], np.int64), np.array([2**31, 0, 0], np.int64),
           np.array([-(2**31) - 1, 0, 0], np.int64), np.array([2**63, 0, 0], np.uint64),
           np.array([0.5, 0, 0]), np.array([np.nan, 0, 0]), np.array([np.inf, 0, 0]),
           np.array([2.0**32, 0, 0])]
    for b in bad:
        with pytest.raises(ValueError, match="int32 range|not an integer"):
            _core.project(ii, fb, b, ys)
        with pytest.raises(ValueError, match="int32 range|not an integer"):
            _core.project(ii, fb, xs, b)
    for b in (np.array([True, False, True]), np.array(["0", "1", "2"]), np.array([1j, 0, 0])):
        with pytest.raises(TypeError, match="must hold integers"):
            _core.project(ii, fb, b, ys)
    with pytest.raises(ValueError, match="not an integer"):
        _core.project(ii, fb, xs, ys, np.array([0.5]))
    with pytest.raises(ValueError, match="int32 range"):
        _core.project(ii, fb, xs, ys, np.array([2**32], np.int64))  # would wrap to feature 0
    with pytest.raises(ValueError, match="int32 range"):
        _core.score_grid(ii, fb, np.array([2**32, 1], np.int64), *WEAK.values(), 1e-30,
                         (10, 10, 8, 8), 5, 1, (80, 60))
    # The bank's own integer arrays too.
    with pytest.raises(ValueError, match="int32 range"):
        _core.FeatureBank(BANK["starts"], BANK["rects"] + np.int64(2**32), BANK["weights"])
    with pytest.raises(ValueError, match="not an integer"):
        _core.FeatureBank(BANK["starts"], BANK["rects"] + 0.25, BANK["weights"])
    with pytest.raises(ValueError, match="int32 range"):
        _core.FeatureBank(BANK["starts"], BANK["rects"], BANK["weights"],
                          channels=np.array([0, 2**32, 0], np.int64))


# ---------------------------------------------------------------- 6. per-value log ratio
def test_log_ratio_value_depends_on_its_inputs_only() -> None:
    rng = np.random.default_rng(2)
    mu1, s1, mu0, s0 = (np.array([v]) for v in (10.0, 3.0, -4.0, 5.0))
    xs = rng.uniform(-20, 30, 41)
    for guard in (1e-30, 1e-5):
        alone = np.array([_core.log_ratio(np.array([[x]]), mu1, s1, mu0, s0, guard)[0, 0] for x in xs])
        # The same values in one batch, in batches that also hold a far outlier (which takes
        # the guarded formula), and at every offset (alignment, tails of vector packets).
        batches = [xs, np.concatenate([xs, [1e6]]), np.concatenate([[-1e6], xs])]
        for off in range(1, 9):
            batches.append(np.concatenate([np.full(off, 0.25), xs]))
        for b in batches:
            got = _core.log_ratio(b[None, :], mu1, s1, mu0, s0, guard)[0]
            start = len(b) - len(xs) if b[0] != xs[0] else 0
            got = got[start:start + len(xs)]
            np.testing.assert_array_equal(got, alone)  # bit for bit


def test_score_grid_and_log_ratio_agree_bit_for_bit() -> None:
    frame = np.random.default_rng(3).integers(0, 256, (60, 80), dtype=np.uint8)
    ii, fb = computed(frame), bank()
    sel = np.array([1, 0], np.int32)
    box, radius = (30, 25, 10, 8), 9
    for guard in (1e-30, 1e-5):
        weak = [np.array([300.0, 2000.0]), np.array([400.0, 700.0]),
                np.array([-200.0, 1500.0]), np.array([300.0, 600.0])]
        dx, dy, best, n, scores = _core.score_grid(ii, fb, sel, *weak, guard, box, radius, 1,
                                                   (80, 60), True)
        offs = [(i, j) for j in range(-8, 9) for i in range(-8, 9) if i * i + j * j < radius**2]
        xs = np.array([box[0] + i for i, _ in offs], np.int32)
        ys = np.array([box[1] + j for _, j in offs], np.int32)
        # The candidates in reverse order, and the first 20 one by one: other batches than
        # score_grid's, which must not matter.
        v = _core.project(ii, fb, xs, ys, sel)
        h = _core.log_ratio(v[:, ::-1], *weak, guard)[:, ::-1]
        for q in range(20):
            np.testing.assert_array_equal(_core.log_ratio(v[:, q:q + 1], *weak, guard)[:, 0], h[:, q])
        total = np.zeros(len(offs))
        for row in h:  # the core adds the features in order
            total += row
        grid = np.array([scores[j + 8, i + 8] for i, j in offs])
        if guard >= 1e-15:
            np.testing.assert_array_equal(grid, total)
            assert n == len(offs) and best == total.max()
            continue
        # Under CT's guard the search sums the exact-path log ratios in float (issue 28): the
        # same values up to float rounding, and still each candidate's own (another grid that
        # holds the same candidates in other runs and batches gives the same bits).
        np.testing.assert_allclose(grid, total, rtol=1e-6, atol=1e-5)
        assert n == len(offs) and best == grid.max()
        *_, wide = _core.score_grid(ii, fb, sel, *weak, guard, box, radius + 3, 1, (80, 60), True)
        np.testing.assert_array_equal(np.array([wide[j + 11, i + 11] for i, j in offs]), grid)


# ---------------------------------------------------------------- 1. shared objects
SHARED_SCRIPT = """
import sys, threading
import numpy as np
from wmiltrack import _core
rng = np.random.default_rng(0)
fa = rng.integers(0, 256, (900, 1200), dtype=np.uint8)
fb_ = rng.integers(0, 256, (900, 1200, 3), dtype=np.uint8)
roi_a, roi_b = (0, 0, 1200, 900), (100, 50, 700, 600)
bank = _core.FeatureBank(np.array([0, 1, 3], np.int32),
                         np.array([[1, 2, 5, 4], [0, 0, 3, 3], [4, 4, 6, 2]], np.int32),
                         np.array([1.0, 0.5, -2.0]))
xs = np.arange(120, 700, 3, dtype=np.int32); ys = (xs // 2 + 60).astype(np.int32)
weak = (np.array([100.0, 20.0]), np.array([50.0, 30.0]), np.array([-50.0, 0.0]), np.array([60.0, 20.0]))
sel = np.array([0, 1], np.int32)
def results(ii):
    return (_core.project(ii, bank, xs, ys).tobytes(), ii.rect_sum(120, 60, 500, 500),
            _core.score_grid(ii, bank, sel, *weak, 1e-30, (300, 300, 10, 8), 40, 1, (1200, 900))[:3])
ii = _core.IntegralImage()
ii.compute(fa, roi_a); want_a = results(ii)
ii.compute_channels(fb_, roi_b, [_core.CH_LUMA, _core.CH_GRAD]); want_b = results(ii)
assert want_a != want_b
stop = False; bad = []; reads = [0]
def writer():
    global stop
    for i in range(60):
        if i % 2: ii.compute(fa, roi_a)
        else: ii.compute_channels(fb_, roi_b, [_core.CH_LUMA, _core.CH_GRAD])
    stop = True
def reader():
    while not stop:
        r = results(ii)  # three calls: each sees one table, not necessarily the same one
        reads[0] += 1
        if any(x != a and x != b for x, a, b in zip(r, want_a, want_b)):
            bad.append(r)
threads = [threading.Thread(target=writer), threading.Thread(target=reader),
           threading.Thread(target=reader)]
for t in threads: t.start()
for t in threads: t.join()
print("reads", reads[0], "inconsistent", len(bad))
sys.exit(1 if bad or reads[0] == 0 else 0)
"""


def test_integral_image_shared_between_threads() -> None:
    r = run_script(SHARED_SCRIPT)
    assert r.returncode == 0, f"rc={r.returncode}\n{r.stdout}\n{r.stderr[-2000:]}"
    assert "inconsistent 0" in r.stdout


# ---------------------------------------------------------------- 2. arguments read once
MUTATE_SCRIPT = """
import sys, threading
import numpy as np
from wmiltrack import _core
frame = np.random.default_rng(0).integers(0, 256, (200, 200), dtype=np.uint8)
ii = _core.IntegralImage(); ii.compute(frame, (0, 0, 200, 200))
bank = _core.FeatureBank(np.array([0, 1], np.int32), np.array([[0, 0, 4, 4]], np.int32), np.ones(1))
n = 400_000
xs = np.zeros(n, np.int32); ys = np.zeros(n, np.int32)
want = _core.project(ii, bank, xs, ys)
stop = False
def flip():
    # -2**31 + 1: the box corner sits 16 GB before the table.
    while not stop:
        xs[-1] = -2**31 + 1
        xs[-1] = 0
t = threading.Thread(target=flip); t.start()
ok = refused = wrong = 0
for _ in range(150):
    try:
        got = _core.project(ii, bank, xs, ys)
    except IndexError:
        refused += 1
        continue
    if np.array_equal(got, want): ok += 1
    else: wrong += 1
stop = True; t.join()
print("ok", ok, "refused", refused, "wrong", wrong)
sys.exit(1 if wrong else 0)
"""


def test_project_reads_each_coordinate_once() -> None:
    r = run_script(MUTATE_SCRIPT)
    assert r.returncode == 0, f"rc={r.returncode}\n{r.stdout}\n{r.stderr[-2000:]}"
    assert "wrong 0" in r.stdout


# ---------------------------------------------------------------- many targets on two threads
# Run by scripts/sanitize.sh under ThreadSanitizer too: the targets' frame steps (search, draws
# from each target's generator, learning) run on two threads in one core call.
MULTI_SCRIPT = """
import sys
import numpy as np
import wmiltrack
rng = np.random.default_rng(1)
frames = [rng.integers(0, 256, (240, 320, 3), dtype=np.uint8) for _ in range(6)]
boxes = [(20, 20, 30, 30), (150, 100, 30, 30), (260, 180, 30, 30), (100, 150, 24, 40)]
singles = []
for i, b in enumerate(boxes):
    t = wmiltrack.Tracker("rcwmil", seed=3 + i)
    t.init(frames[0], b)
    singles.append([t.update(f) for f in frames[1:]])
for share in ("never", "always"):
    mt = wmiltrack.MultiTracker("rcwmil", seed=3, threads=2, share=share)
    for b in boxes:
        mt.add(frames[0], b)
    for k, f in enumerate(frames[1:]):
        found = mt.update(f)
        if [found[i] for i in range(len(boxes))] != [s[k] for s in singles]:
            sys.exit(f"share={share}: frame {k + 1} differs from the single trackers")
print("multi: same boxes")
"""


def test_multi_tracker_on_two_threads_matches_single_trackers() -> None:
    r = run_script(MULTI_SCRIPT)
    assert r.returncode == 0, f"rc={r.returncode}\n{r.stdout}\n{r.stderr[-2000:]}"
    assert "same boxes" in r.stdout


# ---------------------------------------------------------------- Tracker across threads
def test_tracker_refuses_concurrent_use() -> None:
    seq = make_preset("easy", seed=0, n_frames=3)
    frames, gt = seq.load(), seq.groundtruth
    t = wmiltrack.Tracker("ct", seed=0)
    t.init(frames[0], tuple(gt[0]))
    inside, release = threading.Event(), threading.Event()

    def slow_stage(tracker: object, state: Any) -> Any:  # a first stage that waits
        inside.set()
        release.wait(10)
        return state

    t.stages = (slow_stage, *wmiltrack.Tracker.stages)
    errors: list[BaseException] = []
    th = threading.Thread(target=lambda: t.update(frames[1]))
    th.start()
    try:
        assert inside.wait(10)
        with pytest.raises(RuntimeError, match="another thread"):
            t.update(frames[2])
        with pytest.raises(RuntimeError, match="another thread"):
            t.init(frames[0], tuple(gt[0]))
    except BaseException as e:  # pragma: no cover - reported below
        errors.append(e)
    finally:
        release.set()
        th.join()
    assert not errors, errors
    del t.stages  # (the class's stages again)
    t.update(frames[2])  # usable again once the other call returned


# ---------------------------------------------------------------- 7. portable build
def _disassembly(mod: Any) -> str:
    """The compiled module's machine code as objdump prints it (skips without binutils)."""
    objdump = shutil.which("objdump")
    if objdump is None:
        pytest.skip("objdump (binutils) not installed")
    return subprocess.run([objdump, "-d", "--no-show-raw-insn", str(Path(mod.__file__ or ""))],
                          capture_output=True, text=True, check=True).stdout


def test_default_build_is_portable() -> None:
    assert _core.BUILD_NATIVE is False, "built with WMILTRACK_NATIVE=ON: not a portable build"
    for mod in (_core, wmiltrack._learn):
        path = Path(mod.__file__ or "")
        asm = _disassembly(mod)
        # AVX/AVX-512 register operands (instructions an x86-64 baseline CPU lacks) are allowed
        # only inside the vmath kernels compiled for AVX2 (named *_avx2), which run only on a
        # CPU that has AVX2 (chosen at run time; the C++ tests check they give the same bits
        # as the baseline kernels).
        wide, dispatched, function = [], 0, ""
        for ln in asm.splitlines():
            label = re.match(r"^[0-9a-f]+ <(.*)>:$", ln)
            if label:
                function = label.group(1)
            elif "%ymm" in ln or "%zmm" in ln:
                if "avx2" in function and "%zmm" not in ln:
                    dispatched += 1
                else:
                    wide.append(f"{function}: {ln.strip()}")
        assert not wide, f"{path.name}: {len(wide)} AVX instructions, e.g. {wide[:3]}"
        if mod is _core:
            assert dispatched > 0, "no AVX2 vmath kernels found: were they renamed?"


@pytest.mark.skipif(platform.machine() not in ("x86_64", "AMD64"), reason="x86-64 instruction")
def test_frame_rows_are_prefetched() -> None:
    # The integral image asks for the frame rows ahead of its scan (a cold frame's region costs
    # about twice as much without). A compiler once deleted that loop as dead code, silently.
    assert "prefetcht1" in _disassembly(_core), "the integral image's row prefetch was compiled out"


def test_simd_copies_give_the_same_boxes_and_scores() -> None:
    """The AVX2 copies of the vectorised kernels (vmath, MILBoost selection) and the baseline
    copies compute the same bits: whole tracker runs agree exactly, boxes and scores."""
    if _core.simd_path() != "avx2":
        pytest.skip(f"this CPU runs the {_core.simd_path()} copy only: nothing to compare")
    seq = make_preset("all", seed=3, n_frames=40)
    frames = seq.load()
    assert seq.groundtruth is not None
    first = tuple(float(v) for v in seq.groundtruth[0])
    for variant in ("rcwmil", "ct", "mil", "wmil", "rcwmil-plus"):
        runs = []
        for portable in (False, True):
            _core.set_simd_portable(portable)
            try:
                assert _core.simd_path() == ("sse2" if portable else "avx2")
                tracker = wmiltrack.Tracker(variant, seed=0)
                tracker.init(frames[0], first)
                runs.append([tracker.update(f) for f in frames[1:]])
            finally:
                _core.set_simd_portable(False)
        fast, portable_run = runs
        assert [r.box for r in fast] == [r.box for r in portable_run], variant
        assert [r.score for r in fast] == [r.score for r in portable_run], variant
