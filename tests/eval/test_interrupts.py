"""Ctrl-C and SIGTERM end ``wmiltrack eval -j 2`` at once: the command exits within 2 s with
status 130, no process of its group is left running (workers terminated and reaped, not waited
for), and every task finished before the signal keeps its box file, complete.

The run is a real ``wmiltrack eval`` in its own process group on a small generated dataset:
``rcwmil`` finishes a sequence in well under a second while ``opencv:MIL`` takes several, so
when the signal comes both workers are busy with a MIL task. A signal is sent to the whole
group, as a terminal's Ctrl-C is.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from conftest import write_generated_otb

pytestmark = pytest.mark.skipif(not Path("/proc/self/stat").exists() or os.name != "posix",
                                reason="reads the process table from /proc (Linux)")

N_FRAMES = 160
LIMIT = 2.0  # seconds from the (last) signal to the command's end


def group_processes(pgid: int) -> dict[int, str]:
    """``{pid: state}`` of every process in the process group ``pgid`` (``Z``: ended, waiting
    to be reaped by its parent)."""
    out: dict[int, str] = {}
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
        except OSError:  # ended meanwhile
            continue
        fields = stat[stat.rindex(")") + 2:].split()  # after "pid (comm) "
        if int(fields[2]) == pgid:
            out[int(entry.name)] = fields[0]
    return out


@pytest.fixture(scope="module")
def dataset(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("interrupts") / "data"
    for i in range(4):
        write_generated_otb(root, f"S{i}", seed=i, n=N_FRAMES)
    return root


@pytest.fixture(autouse=True)
def sigint_default() -> Iterator[None]:
    """The command must start with SIGINT's default disposition: an ignored signal is inherited
    through exec, and a test before this one may have left it ignored in this process (the
    command line ignores SIGINT while it reports an interrupt)."""
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, before)


def start_eval(dataset: Path, out: Path) -> subprocess.Popen[bytes]:
    return subprocess.Popen(
        [sys.executable, "-m", "wmiltrack", "eval", str(dataset), "--trackers", "rcwmil,opencv:MIL",
         "--out", str(out), "-j", "2", "--no-progress", "--no-plots"],
        start_new_session=True, stdout=subprocess.PIPE, stderr=subprocess.PIPE)


def wait_for_first_results(proc: subprocess.Popen[bytes], out: Path) -> None:
    """Wait until rcwmil finished two sequences (so there is something to keep) and both
    workers are up."""
    deadline = time.monotonic() + 120
    want = [out / "boxes" / "rcwmil" / f"S{i}.run.json" for i in (0, 1)]
    while not all(p.exists() for p in want):
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() < deadline, "the run made no progress"
        time.sleep(0.05)
    assert len(group_processes(proc.pid)) >= 3  # the command and its two workers at least


def assert_ends_cleanly(proc: subprocess.Popen[bytes], sent: float, status: int) -> str:
    """The command ends within LIMIT s of ``sent`` with ``status``, and by then nothing of its
    group is still running (a process already ended and not yet reaped by init is not running).
    Returns its standard error."""
    try:
        _, err = proc.communicate(timeout=LIMIT + 5)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.communicate()
        pytest.fail("the command did not end after the signal")
    took = time.monotonic() - sent
    running: dict[int, str] = {}
    while time.monotonic() - sent < LIMIT:
        running = {p: s for p, s in group_processes(proc.pid).items() if s != "Z"}
        if not running:
            break
        time.sleep(0.05)
    leftover = {p: s for p, s in group_processes(proc.pid).items() if s != "Z"}
    if leftover:
        os.killpg(proc.pid, signal.SIGKILL)
    assert took < LIMIT, f"ended {took:.1f} s after the signal"
    assert not leftover, f"still running {LIMIT} s after the signal: {leftover}"
    assert proc.returncode == status, err.decode()
    return err.decode()


def assert_finished_tasks_kept(out: Path) -> None:
    for i in (0, 1):
        lines = (out / "boxes" / "rcwmil" / f"S{i}.txt").read_text().splitlines()
        assert len(lines) == N_FRAMES and all(line.count(",") == 3 for line in lines)


@pytest.mark.parametrize("signals", [1, 2], ids=["one-ctrl-c", "two-ctrl-c"])
def test_ctrl_c_ends_a_parallel_eval_at_once_and_keeps_what_was_finished(
        dataset: Path, tmp_path: Path, signals: int) -> None:
    out = tmp_path / "out"
    proc = start_eval(dataset, out)
    wait_for_first_results(proc, out)
    for k in range(signals):
        if k:
            time.sleep(0.05)
        os.killpg(proc.pid, signal.SIGINT)
    err = assert_ends_cleanly(proc, time.monotonic(), 130)
    assert "interrupted" in err and "Traceback" not in err
    assert_finished_tasks_kept(out)


def test_sigterm_to_the_command_alone_leaves_no_worker_running(dataset: Path, tmp_path: Path) -> None:
    """SIGTERM to the main process only (a job scheduler's kill): the workers notice their
    parent is gone and end."""
    out = tmp_path / "out"
    proc = start_eval(dataset, out)
    wait_for_first_results(proc, out)
    proc.send_signal(signal.SIGTERM)
    assert_ends_cleanly(proc, time.monotonic(), -signal.SIGTERM)
    assert_finished_tasks_kept(out)
