"""Run evaluation tasks on Dask: :class:`wmiltrack.parallel.executors.DaskExecutor` set up for
:class:`~wmiltrack.eval.runner.Task` and :class:`~wmiltrack.eval.runner.RunOutcome`.

A task whose outcome has an error, or whose future failed (a worker died, the task could not
be unpickled...), is submitted once more; its final outcome is yielded either way, a failure
as an outcome with ``error`` set (:func:`failed_outcome`), never dropped. See
:mod:`wmiltrack.parallel.executors` for the cluster itself (a ``LocalCluster``, or an existing one by
its scheduler's address).
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

from ..parallel import executors
from .runner import RunOutcome, Task

__all__ = ["DaskExecutor", "describe_task", "failed_outcome"]


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


def describe_task(task: Task) -> str:
    """A task as a retry line names it: ``rcwmil on Crossing (seed 0)``."""
    return f"{task.tracker} on {Path(task.sequence).name} (seed {task.seed})"


class DaskExecutor(executors.DaskExecutor):
    """:class:`wmiltrack.parallel.executors.DaskExecutor` whose failed task becomes a
    :class:`RunOutcome` with ``error`` set, and whose retry lines name the tracker, sequence
    and seed.

    Parameters
    ----------
    jobs, cv_threads, scheduler, retries, log:
        As for :class:`wmiltrack.parallel.executors.DaskExecutor`.
    """

    def __init__(
        self,
        jobs: int = 1,
        cv_threads: int | None = 1,
        scheduler: str | None = None,
        retries: int = 1,
        log: Callable[[str], None] | None = None,
    ) -> None:
        super().__init__(jobs, cv_threads, scheduler, retries, log, failed=failed_outcome,
                         describe=describe_task)
