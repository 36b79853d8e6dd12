"""Run evaluation tasks on Dask: a ``LocalCluster`` on this machine or an existing cluster.

:class:`DaskExecutor` has the ``map`` method of :class:`wmiltrack.eval.runner.Executor`, so
:func:`wmiltrack.eval.pipeline.run_tasks` (and ``wmiltrack eval --executor dask``) use it as
they use the process executor: outcomes come back as their tasks finish, and each one's box
file is written at once.

* Without a scheduler address a ``LocalCluster`` is started with ``jobs`` worker processes of
  one thread each (and no dashboard); with one (``tcp://host:8786``) the tasks go to that
  cluster's workers, which must have wmiltrack installed and see the dataset at the same path
  (the tasks carry absolute paths).
* OpenCV's thread pool is set to ``cv_threads`` in every worker before each task, as the
  process executor does in its workers.
* A task whose outcome has an error, or whose future failed (a worker died, the task could
  not be unpickled...), is submitted once more; its final outcome is yielded either way, a
  failure as an outcome with ``error`` set, never dropped.

``distributed`` is an optional dependency (``pip install "wmiltrack[cluster]"``); it is
imported only when :meth:`DaskExecutor.map` runs.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .runner import RunOutcome, Task, set_cv_threads

__all__ = ["INSTALL_HINT", "DaskExecutor", "failed_outcome", "require_distributed"]

INSTALL_HINT = (
    "--executor dask needs Dask's distributed scheduler: pip install \"wmiltrack[cluster]\" "
    "(or pip install \"dask[distributed]\")"
)


def require_distributed() -> Any:
    """Import and return :mod:`distributed`.

    Returns
    -------
    module
        :mod:`distributed`.

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
    """``fn(task)`` after ``cv2.setNumThreads(cv_threads)`` in the worker (picklable)."""

    def __init__(self, fn: Callable[[Task], RunOutcome], cv_threads: int | None) -> None:
        self.fn = fn
        self.cv_threads = cv_threads

    def __call__(self, task: Task) -> RunOutcome:
        set_cv_threads(self.cv_threads)
        return self.fn(task)


def failed_outcome(task: Task, error: str) -> RunOutcome:
    """The outcome of a task that gave no outcome at all (its future failed).

    Parameters
    ----------
    task:
        The task.
    error:
        What went wrong.

    Returns
    -------
    RunOutcome
        No boxes (the caller pads them to the sequence's length), ``error`` set, failed at
        frame 0.
    """
    return RunOutcome(
        tracker=task.tracker,
        sequence=Path(task.sequence).name,
        repeat=task.repeat,
        seed=task.seed,
        boxes=np.full((0, 4), np.nan),
        oks=np.zeros(0, dtype=bool),
        error=error,
        error_frame=0,
    )


class DaskExecutor:
    """Runs the tasks on a Dask cluster.

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
        Times a failed task is submitted again (default 1).
    log:
        Receives a line for every retry (default: nothing).
    """

    def __init__(
        self,
        jobs: int = 1,
        cv_threads: int | None = 1,
        scheduler: str | None = None,
        retries: int = 1,
        log: Callable[[str], None] | None = None,
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

    def _client(self, distributed: Any) -> tuple[Any, Any]:
        if self.scheduler is not None:
            return distributed.Client(self.scheduler), None
        cluster = distributed.LocalCluster(
            n_workers=self.jobs,
            threads_per_worker=1,
            processes=True,
            dashboard_address=None,
            # No dashboard; the scheduler's small HTTP server (health, metrics) on a free port
            # instead of its default 8787, which another cluster or program may hold.
            scheduler_kwargs={"dashboard_address": ":0"},
        )
        return distributed.Client(cluster), cluster

    def map(
        self, fn: Callable[[Task], RunOutcome], tasks: Sequence[Task]
    ) -> Iterator[RunOutcome]:
        """Submit every task; yield outcomes as they finish (a failed one after its retry).
        Closing the iterator early (an interruption) cancels the tasks not yet finished and
        closes the client (and the ``LocalCluster`` it started)."""
        if not tasks:
            return
        distributed = require_distributed()
        client, cluster = self._client(distributed)
        job = _WithCVThreads(fn, self.cv_threads)
        live: dict[Any, tuple[Any, Task, int]] = {}  # key -> (future, task, tries so far)
        try:
            for t in tasks:
                fut = client.submit(job, t, pure=False)
                live[fut.key] = (fut, t, 0)
            pending = distributed.as_completed([f for f, _, _ in live.values()])
            for fut in pending:
                _, task, n_tries = live.pop(fut.key)
                if fut.status == "finished":
                    outcome: RunOutcome = fut.result()
                else:
                    exc = fut.exception()
                    outcome = failed_outcome(task, f"{type(exc).__name__}: {exc}")
                fut.release()
                if outcome.error is not None and n_tries < self.retries:
                    if self.log is not None:
                        self.log(
                            f"retrying {task.tracker} on {outcome.sequence} (seed {task.seed}) "
                            f"after: {outcome.error}"
                        )
                    again = client.submit(job, task, pure=False)
                    live[again.key] = (again, task, n_tries + 1)
                    pending.add(again)
                    continue
                yield outcome
        finally:
            try:
                if live:
                    client.cancel([f for f, _, _ in live.values()])
            finally:
                client.close()
                if cluster is not None:
                    cluster.close()
