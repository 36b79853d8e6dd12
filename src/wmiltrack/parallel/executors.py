"""Running independent jobs and getting each result back as soon as its job is finished.

One job is a picklable function applied to one picklable item (an evaluation task, a clip to
track); an executor's ``map(fn, items)`` yields the results in the order the jobs finish, so
the caller can write each one at once and an interruption loses only the jobs not finished.
``wmiltrack eval`` and ``wmiltrack track --list`` choose among the same three
(:func:`make_executor`):

* :class:`SerialExecutor`: one after the other in this process;
* :class:`ProcessExecutor`: ``jobs`` worker processes on this machine (spawned: OpenCV's thread
  pool does not survive a fork reliably);
* :class:`DaskExecutor`: a Dask ``LocalCluster`` of ``jobs`` single-thread worker processes, or
  an existing cluster given by its scheduler's address (its workers must have wmiltrack
  installed and see the input files at the same paths). A job that fails (its result says
  so, or its worker died) is submitted once more before its failure is reported.

In every case OpenCV's own thread pool is set to ``cv_threads`` where the jobs run (1 by
default: one thread per tracker, as wmiltrack's core uses). ``distributed`` is an optional
dependency (``pip install "wmiltrack[cluster]"``), imported only when a Dask executor is made.
"""

from __future__ import annotations

import os
import signal
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import Future, ProcessPoolExecutor, as_completed
from contextlib import contextmanager
from multiprocessing import active_children, get_context
from typing import Any, Literal, Protocol, TypeVar

__all__ = [
    "EXECUTORS",
    "INSTALL_HINT",
    "DaskExecutor",
    "Executor",
    "ExecutorName",
    "ProcessExecutor",
    "SerialExecutor",
    "make_executor",
    "require_distributed",
    "set_cv_threads",
]

T = TypeVar("T")
R = TypeVar("R")

ExecutorName = Literal["serial", "process", "dask"]
#: The executors :func:`make_executor` knows, by name (``--executor``).
EXECUTORS: tuple[ExecutorName, ...] = ("serial", "process", "dask")

INSTALL_HINT = (
    "--executor dask needs Dask's distributed scheduler: pip install \"wmiltrack[cluster]\" "
    "(or pip install \"dask[distributed]\")"
)


def set_cv_threads(n: int | None) -> int:
    """Set OpenCV's thread pool size (``cv2.setNumThreads``) and return the previous size.

    Parameters
    ----------
    n:
        Threads; ``None`` leaves the setting alone.

    Returns
    -------
    int
        ``cv2.getNumThreads()`` before the call.
    """
    import cv2

    before = int(cv2.getNumThreads())
    if n is not None:
        cv2.setNumThreads(int(n))
    return before


class Executor(Protocol):
    """Maps jobs to results, yielding each result as soon as its job is finished."""

    def map(self, fn: Callable[[Any], Any], items: Sequence[Any]) -> Iterator[Any]:
        """Run ``fn`` on every item; yield the results in the order they finish."""
        ...


class SerialExecutor:
    """Runs the jobs one after the other in this process.

    Parameters
    ----------
    cv_threads:
        ``cv2.setNumThreads`` while the jobs run (restored afterwards); ``None`` leaves it.
    """

    def __init__(self, cv_threads: int | None = 1) -> None:
        self.cv_threads = cv_threads

    def map(self, fn: Callable[[T], R], items: Sequence[T]) -> Iterator[R]:
        """Run ``fn`` on every item in order, yielding each result at once."""
        before = set_cv_threads(self.cv_threads)
        try:
            for item in items:
                yield fn(item)
        finally:
            set_cv_threads(before)


class ProcessExecutor:
    """Runs the jobs in ``jobs`` worker processes (spawned).

    Parameters
    ----------
    jobs:
        Worker processes.
    cv_threads:
        ``cv2.setNumThreads`` in every worker; ``None`` leaves OpenCV's default.
    """

    def __init__(self, jobs: int, cv_threads: int | None = 1) -> None:
        if jobs < 1:
            raise ValueError(f"jobs must be at least 1, got {jobs}")
        self.jobs = jobs
        self.cv_threads = cv_threads

    def map(self, fn: Callable[[T], R], items: Sequence[T]) -> Iterator[R]:
        """Submit every job; yield results as they finish.

        Closing the iterator early (an interruption, an exception in the caller) cancels the
        jobs not yet started and terminates the workers at once, without waiting for the jobs
        they are running: their results would be thrown away, and a Ctrl-C must not take as
        long as a job. Only a run that yields every result waits for the workers to exit.
        """
        if not items:
            return
        before = {p.pid for p in active_children()}
        pool = ProcessPoolExecutor(
            max_workers=min(self.jobs, len(items)),
            mp_context=get_context("spawn"),
            initializer=_start_worker,
            initargs=(self.cv_threads, os.getpid()),
        )
        finished = False
        try:
            futures: list[Future[R]] = [pool.submit(fn, item) for item in items]
            for fut in as_completed(futures):
                yield fut.result()
            finished = True
        finally:
            if finished:
                pool.shutdown(wait=True)
            else:
                _stop_pool(pool, before)


#: Seconds a terminated worker is given to exit before it is killed.
_TERMINATE_GRACE = 1.0


def _stop_pool(pool: ProcessPoolExecutor, before: set[int | None]) -> None:
    """Cancel the pool's queued jobs and end its workers now: SIGTERM, then SIGKILL for any
    still alive after :data:`_TERMINATE_GRACE` seconds; each is joined (no zombie left).

    The workers are this process's children started since ``before`` (the children's ids when
    the pool was made), found with :func:`multiprocessing.active_children`, which is public,
    rather than through the pool's private attributes. SIGINT is ignored meanwhile (in the main
    thread), so that a second Ctrl-C cannot cut the clean-up short and leave workers for
    Python's exit to wait on for good.
    """
    with _sigint_ignored():
        pool.shutdown(wait=False, cancel_futures=True)
        workers = [p for p in active_children() if p.pid not in before]
        for p in workers:
            p.terminate()
        deadline = time.monotonic() + _TERMINATE_GRACE
        for p in workers:
            p.join(max(0.0, deadline - time.monotonic()))
            if p.is_alive():
                p.kill()
                p.join()
        # the pool's manager thread sees its workers gone and ends; join it so that Python's
        # exit finds nothing to wait for
        pool.shutdown(wait=True)


@contextmanager
def _sigint_ignored() -> Iterator[None]:
    """Ignore SIGINT inside the block when called in the main thread (elsewhere a no-op:
    signal handlers belong to the main thread)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def _start_worker(cv_threads: int | None, parent: int) -> None:
    """A worker process's set-up: OpenCV's threads, Ctrl-C left to the parent, and an end
    when the parent is gone.

    A Ctrl-C at a terminal reaches every process of the group; the parent stops the run and
    terminates the workers, while a worker that took it would print its own traceback. A parent
    killed outright (SIGKILL) can terminate nothing, so a daemon thread of the worker checks
    every half second that its parent is still the one that started it and ends the worker
    otherwise.
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    set_cv_threads(cv_threads)
    threading.Thread(target=_exit_with_parent, args=(parent,), daemon=True,
                     name="wmiltrack-parent-watch").start()


def _exit_with_parent(parent: int) -> None:
    """End this process as soon as ``parent`` is no longer its parent process."""
    while os.getppid() == parent:
        time.sleep(0.5)
    os._exit(1)


def require_distributed() -> Any:
    """Import and return :mod:`distributed`.

    Raises
    ------
    RuntimeError
        When it is not installed; the message says how to install it.
    """
    try:
        import distributed
    except ImportError as exc:
        raise RuntimeError(INSTALL_HINT) from exc
    return distributed


class _WithCVThreads:
    """``fn(item)`` after ``cv2.setNumThreads(cv_threads)`` in the worker (picklable)."""

    def __init__(self, fn: Callable[[Any], Any], cv_threads: int | None) -> None:
        self.fn = fn
        self.cv_threads = cv_threads

    def __call__(self, item: Any) -> Any:
        set_cv_threads(self.cv_threads)
        return self.fn(item)


def _error_attribute(result: Any) -> str | None:
    error = getattr(result, "error", None)
    return None if error is None else str(error)


class DaskExecutor:
    """Runs the jobs on a Dask cluster.

    Parameters
    ----------
    jobs:
        Worker processes of the ``LocalCluster`` (ignored with ``scheduler``: the cluster has
        the workers it has).
    cv_threads:
        ``cv2.setNumThreads`` in the workers; ``None`` leaves OpenCV's default.
    scheduler:
        Address of an existing scheduler (``tcp://host:8786``); ``None`` starts a
        ``LocalCluster``.
    retries:
        Times a failed job is submitted again (default 1).
    log:
        Receives a line for every retry (default: nothing).
    failed:
        ``failed(item, error)``: the result to yield for a job that gave none (its future
        failed: a worker died, the job could not be unpickled...). Default: raise
        ``RuntimeError``.
    error_of:
        The error a result reports, or ``None`` (default: its ``error`` attribute); a result
        with an error is retried like a failed future.
    describe:
        An item as the retry line names it (default ``str``).
    processes:
        Worker processes (default) or threads of this process for the ``LocalCluster``.
    """

    def __init__(
        self,
        jobs: int = 1,
        cv_threads: int | None = 1,
        scheduler: str | None = None,
        retries: int = 1,
        log: Callable[[str], None] | None = None,
        *,
        failed: Callable[[Any, str], Any] | None = None,
        error_of: Callable[[Any], str | None] = _error_attribute,
        describe: Callable[[Any], str] = str,
        processes: bool = True,
    ) -> None:
        if jobs < 1:
            raise ValueError(f"jobs must be at least 1, got {jobs}")
        if retries < 0:
            raise ValueError(f"retries must be at least 0, got {retries}")
        self.jobs = jobs
        self.cv_threads = cv_threads
        self.scheduler = scheduler
        self.retries = retries
        self.log = log
        self.failed = failed
        self.error_of = error_of
        self.describe = describe
        self.processes = processes

    def _client(self, distributed: Any) -> tuple[Any, Any]:
        if self.scheduler is not None:
            return distributed.Client(self.scheduler), None
        cluster = distributed.LocalCluster(
            n_workers=self.jobs,
            threads_per_worker=1,
            processes=self.processes,
            dashboard_address=None,
            # No dashboard; the scheduler's small HTTP server (health, metrics) on a free port
            # instead of its default 8787, which another cluster or program may hold.
            scheduler_kwargs={"dashboard_address": ":0"},
        )
        return distributed.Client(cluster), cluster

    def _failed(self, item: Any, error: str) -> Any:
        if self.failed is None:
            raise RuntimeError(f"{self.describe(item)} failed: {error}")
        return self.failed(item, error)

    def map(self, fn: Callable[[T], R], items: Sequence[T]) -> Iterator[R]:
        """Submit every job; yield results as they finish (a failed one after its retry).
        Closing the iterator early (an interruption) cancels the jobs not yet finished and
        closes the client (and the ``LocalCluster`` it started)."""
        if not items:
            return
        distributed = require_distributed()
        client, cluster = self._client(distributed)
        job = _WithCVThreads(fn, self.cv_threads)
        live: dict[Any, tuple[Any, T, int]] = {}  # key -> (future, item, tries so far)
        try:
            for item in items:
                fut = client.submit(job, item, pure=False)
                live[fut.key] = (fut, item, 0)
            pending = distributed.as_completed([f for f, _, _ in live.values()])
            for fut in pending:
                _, item, n_tries = live.pop(fut.key)
                if fut.status == "finished":
                    result: R = fut.result()
                    error = self.error_of(result)
                else:
                    exc = fut.exception()
                    error = f"{type(exc).__name__}: {exc}"
                    result = self._failed(item, error)
                fut.release()
                if error is not None and n_tries < self.retries:
                    if self.log is not None:
                        self.log(f"retrying {self.describe(item)} after: {error}")
                    again = client.submit(job, item, pure=False)
                    live[again.key] = (again, item, n_tries + 1)
                    pending.add(again)
                    continue
                yield result
        finally:
            try:
                if live:
                    client.cancel([f for f, _, _ in live.values()])
            finally:
                client.close()
                if cluster is not None:
                    cluster.close()


def make_executor(
    name: ExecutorName | None,
    jobs: int = 1,
    cv_threads: int | None = 1,
    scheduler: str | None = None,
    *,
    log: Callable[[str], None] | None = None,
    failed: Callable[[Any, str], Any] | None = None,
    describe: Callable[[Any], str] = str,
) -> SerialExecutor | ProcessExecutor | DaskExecutor:
    """The executor of ``--executor NAME -j JOBS [--scheduler ADDRESS]``.

    ``name`` ``None`` picks ``"serial"`` for one job and ``"process"`` for more. ``log``,
    ``failed`` and ``describe`` go to :class:`DaskExecutor`. A Dask executor checks at once
    that ``distributed`` is installed, so that a missing extra is said before anything runs.

    Raises
    ------
    ValueError
        An unknown name, ``--scheduler`` without ``dask``, or ``serial`` with ``jobs`` > 1.
    RuntimeError
        ``dask`` without ``distributed`` installed (the message says how to install it).
    """
    if name is None:
        name = "serial" if jobs == 1 else "process"
    if scheduler is not None and name != "dask":
        raise ValueError("--scheduler needs --executor dask")
    if name == "serial":
        if jobs != 1:
            raise ValueError(f"--executor serial runs one task at a time; -j {jobs} needs another")
        return SerialExecutor(cv_threads)
    if name == "process":
        return ProcessExecutor(jobs, cv_threads)
    if name == "dask":
        require_distributed()
        return DaskExecutor(jobs, cv_threads, scheduler=scheduler, log=log, failed=failed,
                            describe=describe)
    raise ValueError(f"executor must be one of {', '.join(EXECUTORS)}, not {name!r}")
