"""``wmiltrack eval``: benchmark trackers on an OTB-layout dataset (OPE, VOT or long-term).

Usage::

    wmiltrack eval DATASET --trackers rcwmil,fct,opencv:MIL --out DIR [-j N] [--repeats R]
                   [--executor serial|process|dask] [--scheduler ADDRESS] [--resume]
                   [--layout otb|lasot|got10k|uav123|uav123_10fps|uav20l|dtb70|trackingnet|vot]
                   [--protocol ope|vot|longterm] [--sequences A,B] [--seed S]
    wmiltrack eval DATASET --results BOXDIR --out DIR      # score another tracker's files

``DATASET`` is a folder of OTB sequence folders (``<Seq>/img/`` + ``groundtruth_rect.txt``,
optionally ``start.txt``) or one such sequence folder, or a dataset in another layout of
:mod:`wmiltrack.data.layouts` (LaSOT, GOT-10k, UAV123, UAV123_10fps, UAV20L, DTB70,
TrackingNet, VOT; detected, or named with ``--layout``). Absent frames are scored as each
benchmark does (LaSOT: failures; the others: left out); GOT-10k datasets also get AO, SR@0.5
and SR@0.75; sequences annotated on the first frame only are run but not scored. ``--resume``
(OPE) skips the runs whose box file and ``.run.json`` record are already in ``--out``.

Protocols
---------
``ope`` (one-pass evaluation, OTB)
    Each tracker starts from the first ground-truth box and runs to the end.  Scores from
    :func:`wmiltrack.eval.metrics.ope_metrics`: success curve (IoU > t, t = 0, 0.05, ..., 1), its
    AUC (mean of the 21 points), success rate at 0.5, precision at 20 px (error <= t),
    normalised precision at 0.2, mean centre error.  Frames whose ground truth is missing
    (NaN or non-positive size) are left out of every figure and counted ("GT missing").
    Frames without a box (``--missing``, the same rule for every tracker): ``hold``
    (default, as the OTB and got10k toolkits) gives a frame where the tracker gave no box its
    last box; ``miss`` takes away the box of every frame the tracker reports lost.  A frame
    left without a box is a miss in every figure, the mean centre error included
    (:mod:`wmiltrack.eval.scoring`).
``longterm`` (VOT long-term measures)
    One pass from the first frame as ``ope``; scored by :mod:`wmiltrack.eval.longterm`:
    tracking precision, recall and F-score over the tracker's confidence thresholds (and at
    its own lost flag), frames where the target is absent counted, per sequence and averaged
    as the VOT toolkit does. Needs each frame's confidence, so neither ``--results`` nor
    ``--resume``; box files as given (NaN where the tracker gave none) in ``boxes_longterm/``;
    plots ``precision_recall_longterm.png`` and ``fscore_longterm.png``.
``vot`` (VOT-style supervised: VOT2015's rules on OTB's axis-aligned boxes, not VOT's numbers)
    :func:`wmiltrack.eval.vot_style.run_supervised`: failure when the overlap drops to 0,
    re-initialisation 5 frames later, accuracy without the 10 frames after each
    (re)initialisation; failures per sequence and robustness ``exp(-100 F / N)``.

Speed
-----
Update-only frames per second on frames decoded before timing (``tracker.update`` alone is
inside the clock) and the time of ``init``; OpenCV runs with one thread per tracker
(``--cv-threads``, default 1), as wmiltrack does.  Tasks run in parallel processes with
``-j N``; on a machine with few cores the processes compete for them (and for memory
bandwidth), so FPS measured with ``-j`` > 1 is lower and noisier than with ``-j 1``, which
gives the most honest speed figures.

Repeats
-------
``--repeats R`` runs every (tracker, sequence) R times with seeds ``seed, seed+1, ...``;
figures are reported as mean ± standard deviation (population, ``ddof=0``) over the repeats.

Stages
------
:mod:`~wmiltrack.eval.runner` runs tasks, one per (tracker, sequence, seed), through an
executor; each finished task's box file is written at once, so a failing task (reported in
the table and the JSON) or an interrupted run keeps every finished result.  Executors:
``serial`` (``-j 1``), ``process`` (``-j N`` worker processes) and ``dask``
(:class:`~wmiltrack.eval.cluster.DaskExecutor`: a ``LocalCluster`` of ``-j N`` workers, or an
existing cluster with ``--scheduler ADDRESS``; a failed task is retried once there).
Tracker specs may carry overrides (``rcwmil:num_selected=30``), so a sweep is a list of specs.
:mod:`~wmiltrack.eval.scoring` scores the runs and :mod:`~wmiltrack.eval.report` writes the
table, JSON and plots.

Outputs in ``--out DIR``
------------------------
``eval_<protocol>.md`` (table), ``eval_<protocol>.json`` (every figure per tracker and
sequence, per repeat; ``runtimes``: the runtime and its version that ran each network tracker,
as their boxes are the same for the same runtime and version only), ``success_ope.png`` and
``precision_ope.png`` (OPE), and the boxes:
``boxes/<tracker>/<seq>.txt`` (OPE; repeat ``k`` > 0 in ``<seq>.r<k>.txt``) or
``boxes_vot/...`` (VOT; NaN rows on frames not tracked) or ``boxes_longterm/...`` (long-term;
the boxes as given), each with a ``<seq>[.r<k>].run.json`` record (seed, error, frames reported
lost; for the long-term protocol also every frame's score and lost flag) that ``--resume``
reads.  The OPE box files hold the boxes that were scored (after the ``--missing`` rule; NaN
rows are misses).  Tracker names are made
filesystem-safe (``opencv:MIL`` -> ``opencv_MIL``).  ``--results DIR`` reads exactly this
layout (``DIR/<tracker>/<seq>.txt``), e.g. ``--results OUT/boxes``.
"""

from __future__ import annotations

import json
import os
import sys
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Literal

import numpy as np
import numpy.typing as npt

from ..integrations.opencv_wheels import TrackerUnavailable
from ..networks.backends import runtime_version
from ..parallel.executors import Executor, ExecutorName, make_executor
from ..trackers import tracker_labels
from .metrics import PRECISION_THRESHOLDS, SUCCESS_THRESHOLDS
from .report import (
    box_path,
    caption,
    environment,
    format_longterm_table,
    format_ope_table,
    format_vot_table,
    json_safe,
    plural,
    read_results,
    safe_name,
    write_longterm_plots,
    write_plots,
    write_run_boxes,
)
from .runner import RunOutcome, SerialExecutor, Task, run_task
from .scoring import Missing, run_boxes, score_ope, score_vot

__all__ = ["EvalArgumentError", "EvalConfig", "make_tasks", "run_eval", "run_tasks"]

FloatArray = npt.NDArray[np.float64]
Protocol = Literal["ope", "vot", "longterm"]
REFERENCE = "opencv:MIL"


def make_tasks(
    paths: Sequence[Path],
    trackers: Sequence[str],
    seeds: Sequence[int],
    protocol: Protocol = "ope",
    skip: int = 5,
    burnin: int = 10,
    *,
    layout: str = "otb",
    dataset: str | None = None,
) -> list[Task]:
    """Every (sequence, seed, tracker) task, sequence by sequence, the trackers interleaved
    within each seed (so slow drifts of the machine hit all of them alike).

    Parameters
    ----------
    paths:
        Sequence paths (:func:`wmiltrack.data.sequences.list_otb_sequences`).
    trackers:
        Tracker specs.
    seeds:
        One seed per repeat.
    protocol, skip, burnin:
        Protocol settings.
    layout, dataset:
        For a layout other than OTB: ``paths`` are sequence names in the ``dataset`` folder.

    Returns
    -------
    list of Task
    """
    run_as: Literal["ope", "vot"] = "vot" if protocol == "vot" else "ope"  # longterm: one pass
    return [
        Task(t, str(p), seed, r, run_as, skip, burnin, layout, dataset)
        for p in paths
        for r, seed in enumerate(seeds)
        for t in trackers
    ]


def run_tasks(
    tasks: Sequence[Task],
    executor: Executor,
    on_result: Callable[[RunOutcome], None] | None = None,
    show_progress: bool = False,
) -> list[RunOutcome]:
    """Run ``tasks`` through ``executor``, handing each outcome to ``on_result`` at once.

    Parameters
    ----------
    tasks:
        What to run.
    executor:
        :class:`~wmiltrack.eval.runner.SerialExecutor`, :class:`~wmiltrack.eval.runner.
        ProcessExecutor`, or anything with their ``map``.
    on_result:
        Called with every outcome as soon as its task is finished (e.g. to write its box
        file), before the next one is waited for.
    show_progress:
        Progress bar on stderr.

    Returns
    -------
    list of RunOutcome
        In the order of ``tasks``.  If the run is interrupted (``KeyboardInterrupt``), the
        exception propagates after the executor has stopped; ``on_result`` has seen every
        task finished before it.
    """
    from ..progress import progress

    order = {(t.tracker, Path(t.sequence).name, t.repeat): i for i, t in enumerate(tasks)}
    out: list[tuple[int, RunOutcome]] = []
    it: Iterator[RunOutcome] = executor.map(run_task, tasks)
    bar = progress(it, total=len(tasks), desc="eval", enabled=None if show_progress else False)
    try:
        for run in bar:
            if on_result is not None:
                on_result(run)
            out.append((order.get((run.tracker, run.sequence, run.repeat), len(order)), run))
    finally:
        close = getattr(it, "close", None)
        if close is not None:
            close()
    out.sort(key=lambda x: x[0])
    return [r for _, r in out]


def _sequence_paths(dataset: Path, names: Sequence[str] | None) -> list[Path]:
    from ..data.sequences import GT_FILE, list_otb_sequences

    if (dataset / "img").is_dir() and (dataset / GT_FILE).is_file():
        paths = [dataset]
    else:
        paths = list_otb_sequences(dataset)
    if names:
        by_name = {p.name: p for p in paths}
        missing = [n for n in names if n not in by_name]
        if missing:  # a bad --sequences: a command line that cannot run as given
            raise EvalArgumentError(
                f"{'sequence' if len(missing) == 1 else 'sequences'} not found: "
                f"{', '.join(missing)}; available: "
                f"{', '.join(sorted(by_name))}"
            )
        paths = [by_name[n] for n in names]
    if not paths:
        raise FileNotFoundError(
            f"no OTB sequence folder (img/ + groundtruth_rect.txt) in {dataset}"
        )
    return paths


def _ground_truths(paths: Sequence[Path]) -> dict[str, FloatArray]:
    """Every sequence's ground truth, loaded before anything runs: a sequence whose images
    and ground truth do not line up stops the run at once, saying why."""
    from ..data.sequences import load_otb_sequence

    out: dict[str, FloatArray] = {}
    for p in paths:
        seq = load_otb_sequence(p)
        assert seq.groundtruth is not None
        out[seq.name] = np.asarray(seq.groundtruth, dtype=np.float64)
    return out


@dataclass(frozen=True)
class _Dataset:
    layout: str
    root: Path
    paths: list[Path]  # OTB: sequence folders; other layouts: sequence names
    gts: dict[str, FloatArray]
    metas: dict[str, dict[str, Any]]


def _open_dataset(dataset: Path, layout: str | None, names: Sequence[str] | None) -> _Dataset:
    """The sequences' names and ground truths (no image is decoded but OTB's first ones)."""
    from ..data.layouts import LayoutError, detect_layout, load_layout

    if layout is None:
        try:
            layout = detect_layout(dataset)
        except LayoutError:
            layout = "otb"  # the OTB reader's own message says what is wrong
    if layout == "otb":
        paths = _sequence_paths(dataset, names)
        gts = _ground_truths(paths)
        return _Dataset("otb", dataset, paths, gts, {n: {"layout": "otb"} for n in gts})
    seqs = load_layout(dataset, layout, list(names) if names else None)
    if not seqs:
        raise FileNotFoundError(f"no sequence in {dataset}")
    gts = {}
    metas: dict[str, dict[str, Any]] = {}
    for seq in seqs:
        assert seq.groundtruth is not None  # every layout loader reads it
        gts[seq.name] = np.asarray(seq.groundtruth, dtype=np.float64)
        metas[seq.name] = dict(seq.meta)
    return _Dataset(layout, dataset, [Path(n) for n in gts], gts, metas)


def _got10k_section(
    runs: Sequence[RunOutcome],
    gts: dict[str, FloatArray],
    metas: dict[str, dict[str, Any]],
    missing: Missing,
) -> tuple[dict[str, Any], str]:
    """GOT-10k's AO, SR@0.5 and SR@0.75 per tracker (the toolkit's overall figures: frames of
    every sequence pooled), per repeat and as mean ± std over repeats; JSON part and table."""
    from .got10k_metrics import got10k_aggregate, got10k_metrics

    per: dict[str, dict[int, list[Any]]] = {}
    for run in runs:
        if run.sequence not in gts:
            continue
        res = metas[run.sequence].get("resolution")
        bound = (float(res[0]), float(res[1])) if res is not None else None
        fig = got10k_metrics(run_boxes(run, missing), gts[run.sequence], bound=bound)
        per.setdefault(run.tracker, {}).setdefault(run.repeat, []).append(fig)
    doc: dict[str, Any] = {}
    lines = [
        "",
        "GOT-10k figures (got10k toolkit: first frame skipped, frames with the target absent or "
        "fully covered left out, frames of all sequences pooled); mean ± std over repeats.",
        "",
        "| Tracker | AO | SR@0.5 | SR@0.75 |",
        "|---|---|---|---|",
    ]
    for tracker, reps in per.items():
        aggs = [got10k_aggregate(reps[r]) for r in sorted(reps)]
        entry: dict[str, Any] = {"per_repeat": [a.to_dict() for a in aggs]}
        cells = []
        for key in ("ao", "sr50", "sr75"):
            vals = np.array([getattr(a.pooled, key) for a in aggs], dtype=np.float64)
            entry[key] = float(np.mean(vals))
            entry[f"{key}_std"] = float(np.std(vals))
            cells.append(f"{entry[key]:.3f} ± {entry[f'{key}_std']:.3f}")
        doc[tracker] = entry
        lines.append(f"| {tracker} | " + " | ".join(cells) + " |")
    return doc, "\n".join(lines) + "\n"


def _check_trackers(specs: Sequence[str], notes: list[str],
                    runtimes: dict[str, str] | None = None) -> list[str]:
    """The specs whose trackers can start (the others noted in ``notes`` with their reason);
    ``runtimes`` receives the runtime of each one that runs a network
    (:func:`~wmiltrack.trackers.network_runtime`)."""
    from ..trackers import make_tracker, network_runtime

    ok: list[str] = []
    for spec in specs:
        try:
            tracker = make_tracker(spec)
        except TrackerUnavailable as exc:
            # the whole message, its install commands or model options included, on one line
            notes.append(f"skipped {spec}: {' '.join(line.strip() for line in str(exc).splitlines())}")
            continue
        runtime = network_runtime(tracker)
        if runtime is not None and runtimes is not None:
            runtimes[spec] = runtime
        if spec not in ok:
            ok.append(spec)
    return ok


def _executor(
    executor: Executor | ExecutorName | None,
    jobs: int,
    cv_threads: int | None,
    scheduler: str | None,
    say: Callable[[str], None],
) -> Executor:
    if executor is not None and not isinstance(executor, str):
        if scheduler is not None:
            raise ValueError("--scheduler needs --executor dask")
        return executor
    if executor == "serial" or (executor is None and jobs == 1):
        if jobs != 1:
            raise ValueError(f"--executor serial runs one task at a time; -j {jobs} needs another")
        if scheduler is not None:
            raise ValueError("--scheduler needs --executor dask")
        return SerialExecutor(cv_threads)  # eval's: also frees the decoded sequence
    from .cluster import describe_task, failed_outcome

    # fails before anything runs when --executor dask lacks distributed, saying how to install it
    return make_executor(executor, jobs, cv_threads, scheduler, log=say, failed=failed_outcome,
                         describe=describe_task)


def _executor_name(executor: Executor | ExecutorName | None, jobs: int) -> str:
    if executor is None:
        return "serial" if jobs == 1 else "process"
    return executor if isinstance(executor, str) else type(executor).__name__


def _run_record(path: Path) -> Path:
    """``<seq>[.r<k>].run.json`` beside a box file: the run's seed, error and ``n_lost``
    (what ``--resume`` needs besides the boxes: a failed run or another seed is run again)."""
    return path.with_suffix(".run.json")


def _split_resumable(
    tasks: Sequence[Task], box_root: Path, lengths: dict[str, int], missing: Missing,
    labels: dict[str, str],
) -> tuple[list[Task], list[RunOutcome]]:
    """``--resume``: the tasks still to run, and the outcomes of the others read back from
    their box files (a box file with one box per frame, and a record saying that the run
    ended without error, with this seed and this ``missing`` rule: the box files hold the
    boxes after it)."""
    from ..data.boxes import read_boxes

    todo: list[Task] = []
    done: list[RunOutcome] = []
    for t in tasks:
        seq = Path(t.sequence).name
        label = labels.get(t.tracker, t.tracker)
        path = box_path(box_root, label, seq, t.repeat)
        boxes = None
        record: dict[str, Any] = {}
        try:  # the record is written after the boxes: with it, the box file is complete
            record = json.loads(_run_record(path).read_text(encoding="utf-8"))
            same = record.get("seed") == t.seed and record.get("missing") == missing
            if record.get("error") is None and same:
                boxes = read_boxes(path)
        except (OSError, ValueError):  # missing, or cut short by a kill: run the task again
            boxes = None
        if boxes is None or boxes.shape != (lengths[seq], 4):
            todo.append(t)
            continue
        oks = np.all(np.isfinite(boxes), axis=1)
        n_lost = int(record.get("n_lost", 0))
        done.append(RunOutcome(label, seq, t.repeat, t.seed, boxes, oks, n_lost=n_lost))
    return todo, done


def _full_length(run: RunOutcome, lengths: dict[str, int]) -> RunOutcome:
    """A failed task's outcome with NaN boxes on every frame when it has none at all (its
    sequence was never loaded, e.g. a Dask worker died under it)."""
    n = lengths.get(run.sequence)
    if n is None or run.boxes.shape[0] == n or run.boxes.shape[0] != 0:
        return run
    return replace(run, boxes=np.full((n, 4), np.nan), oks=np.zeros(n, dtype=bool))


def _box_writer(
    box_root: Path,
    protocol: Protocol,
    missing: Missing,
    say: Callable[[str], None],
    lengths: dict[str, int],
) -> Callable[[RunOutcome], None]:
    """What to do with each finished task: write its box file (the scored boxes for OPE) and
    report a failure at once."""

    def save(run: RunOutcome) -> None:
        run = _full_length(run, lengths)
        boxes = run_boxes(run, missing) if protocol == "ope" else run.boxes  # longterm: as given
        path = write_run_boxes(box_root, run, boxes)
        record = {
            "tracker": run.tracker,
            "sequence": run.sequence,
            "repeat": run.repeat,
            "seed": run.seed,
            "n_lost": run.n_lost,
            "missing": missing,
            "error": run.error,
        }
        if protocol == "longterm":  # what the figures are made of, besides the boxes
            record["scores"] = [None if not np.isfinite(v) else float(v) for v in run.scores]
            record["oks"] = [bool(v) for v in run.oks]
        _run_record(path).write_text(json.dumps(record) + "\n", encoding="utf-8")
        if run.error is not None:
            say(f"{run.tracker} on {run.sequence} (seed {run.seed}) failed: {run.error}")

    return save


def _score_and_write(
    runs: Sequence[RunOutcome],
    gts: dict[str, FloatArray],
    out: Path,
    protocol: Protocol,
    settings: dict[str, Any],
    repeats: int,
    timed: bool,
    notes: list[str],
    want_plots: bool,
    files: dict[str, str],
    ds: _Dataset,
) -> dict[str, Any]:
    """Score stage and report stage: the table (captioned), plots; returns the JSON document
    (without the run's own fields) and records the files in ``files``."""
    env = environment(settings["cv_threads"])
    missing = settings["missing"]
    title = caption(env, {**settings, "missing": missing if protocol == "ope" else None})
    scored, table, got10k = _score(runs, gts, protocol, settings, repeats, timed, notes, ds, title)
    if notes:
        table += "\nNotes:\n" + "".join(f"- {n}\n" for n in notes)
    if want_plots:
        write = write_longterm_plots if protocol == "longterm" else write_plots
        files.update(write(scored, out, len(gts)))
    table_path = out / f"eval_{protocol}.md"
    table_path.write_text(table, encoding="utf-8")
    files["table"] = str(table_path)
    files["json"] = str(out / f"eval_{protocol}.json")
    return {
        "protocol": protocol,
        "sequences": list(gts),
        "repeats": repeats,
        "settings": settings,
        "caption": title,
        "environment": env,
        "notes": notes,
        "summary": scored["summary"],
        "results": scored["results"],
        "got10k": got10k,
        "files": files,
    }


def _score(runs: Sequence[RunOutcome], gts: dict[str, FloatArray], protocol: Protocol,
           settings: dict[str, Any], repeats: int, timed: bool, notes: list[str], ds: _Dataset,
           title: str) -> tuple[dict[str, Any], str, dict[str, Any] | None]:
    """The protocol's scores, its table (without the notes; the notes it adds go to ``notes``)
    and, for GOT-10k, its own section's figures."""
    missing = settings["missing"]
    got10k: dict[str, Any] | None = None
    if protocol == "ope":
        fail = [n for n in gts if ds.metas[n].get("absent_policy") == "fail"]
        scored = score_ope(runs, gts, missing=missing, reference=REFERENCE, absent_fail=fail)
        table = format_ope_table(
            scored, repeats, timed, title=title, missing=missing, reference=REFERENCE
        )
        if fail:
            notes.append(
                f"{plural(len(fail), 'sequence')} ({ds.layout}): as the benchmark's toolkit does, "
                "count frames where the target is absent as failures"
            )
        if ds.layout == "got10k":
            got10k, section = _got10k_section(runs, gts, ds.metas, missing)
            table += section
    elif protocol == "longterm":
        from .longterm import longterm_scores

        scored = longterm_scores(runs, gts)
        if scored["left_out"]:
            notes.append(f"not scored: {', '.join(scored['left_out'])} (the target is present on "
                         "no frame after the first, so there is no recall to measure)")
        table = format_longterm_table(scored, title=title)
    else:
        scored = score_vot(runs, reference=REFERENCE)
        table = format_vot_table(scored, repeats, settings["skip"], settings["burnin"], title=title)
    return scored, table, got10k


class EvalArgumentError(ValueError):
    """Arguments :func:`run_eval` cannot honour together (checked before any work); the command
    line reports it as a bad command line, exit status 2."""


def _check_eval_arguments(repeats: int, jobs: int, protocol: str, missing: str, resume: bool,
                          results: str | os.PathLike[str] | None) -> None:
    """:class:`EvalArgumentError` for arguments :func:`run_eval` cannot honour, before any
    work."""
    if repeats < 1:
        raise EvalArgumentError(f"--repeats must be at least 1, got {repeats}")
    if jobs < 1:
        raise EvalArgumentError(f"-j must be at least 1, got {jobs}")
    if protocol not in ("ope", "vot", "longterm"):
        raise EvalArgumentError(f"protocol must be 'ope', 'vot' or 'longterm', not {protocol!r}")
    if missing not in ("hold", "miss"):
        raise EvalArgumentError(f"missing must be 'hold' or 'miss', not {missing!r}")
    if resume and (protocol != "ope" or results is not None):
        raise EvalArgumentError(
            f"--resume reads OPE box files back; the {protocol} protocol's figures need the run "
            "itself (the VOT protocol's resets, the long-term protocol's confidences)"
            if results is None
            else "--resume is for running trackers, not with --results"
        )
    if results is not None and protocol == "vot":
        raise EvalArgumentError(
            "--results scores box files with the OPE protocol; the VOT protocol "
            "re-initialises the tracker, so it has to run it"
        )
    if results is not None and protocol == "longterm":
        raise EvalArgumentError(
            "--results scores box files with the OPE protocol; the long-term protocol needs "
            "each frame's confidence, which box files do not hold, so it has to run the trackers"
        )


def _run_trackers(ds: Any, tracker_names: list[str], cfg: EvalConfig, ex: Executor,
                  box_root: Path, notes: list[str],
                  say: Callable[[str], None]) -> tuple[list[RunOutcome], int, int]:
    """Run every (tracker, sequence, seed) task on ``ex``, writing each box file as its task
    ends (or, with ``resume``, reading back those already written); the runs in task order,
    named by their trackers' labels (:func:`~wmiltrack.trackers.tracker_labels`), how many
    were read back, and how many failed on sequences that are not scored."""
    labels = tracker_labels(tracker_names)
    seeds, protocol, skip, burnin = cfg.seeds, cfg.protocol, cfg.skip, cfg.burnin
    missing = cfg.missing
    # absolute paths: the workers of a cluster may run in other folders
    if ds.layout == "otb":
        tasks = make_tasks(
            [p.resolve() for p in ds.paths], tracker_names, seeds, protocol, skip, burnin
        )
    else:
        tasks = make_tasks(
            ds.paths, tracker_names, seeds, protocol, skip, burnin,
            layout=ds.layout, dataset=str(ds.root.resolve()),
        )
    all_tasks = list(tasks)
    lengths = {name: gt.shape[0] for name, gt in ds.gts.items()}
    resumed: list[RunOutcome] = []
    if cfg.resume:
        tasks, resumed = _split_resumable(tasks, box_root, lengths, missing, labels)
        if resumed:
            notes.append(
                f"resumed: {len(resumed)} of {len(tasks) + len(resumed)} runs read back from "
                f"their box files in {box_root} (untimed: no FPS; the mean rows' FPS is over the "
                "runs made now)"
            )
            say(notes[-1])
    save = _box_writer(box_root, protocol, missing, say, lengths)

    def labelled(run: RunOutcome) -> RunOutcome:
        return replace(run, tracker=labels.get(run.tracker, run.tracker))

    new = run_tasks(tasks, ex, lambda run: save(labelled(run)), cfg.show_progress) if tasks else []
    new = [labelled(r) for r in new]
    order = {(t, s, r): i for i, (t, s, r) in enumerate(
        (labels[t.tracker], Path(t.sequence).name, t.repeat) for t in all_tasks
    )}
    runs = sorted(
        [_full_length(r, lengths) for r in new] + resumed,
        key=lambda r: order.get((r.tracker, r.sequence, r.repeat), len(order)),
    )
    skipped = {r.sequence: r.skipped_frames for r in runs if r.skipped_frames}
    for seq, problems in skipped.items():
        more = f" and {len(problems) - 3} more" if len(problems) > 3 else ""
        notes.append(f"{seq}: {plural(len(problems), 'frame')} could not be decoded (skipped), "
                     f"every tracker keeping its last box there ({'; '.join(problems[:3])}{more})")
        say(notes[-1])
    unscored_errors = 0
    for r in runs:
        if ds.metas[r.sequence].get("first_frame_only") and r.error is not None:
            unscored_errors += 1
            notes.append(f"{r.tracker} on {r.sequence} (seed {r.seed}, not scored): {r.error}")
    return runs, len(resumed), unscored_errors


@dataclass(frozen=True)
class EvalConfig:
    """What :func:`run_eval` runs (or reads) and scores, and how.

    Attributes
    ----------
    dataset:
        Folder of OTB sequence folders, or one sequence folder.
    out:
        Output folder (created).
    trackers:
        Tracker names (``rcwmil``, ``fct``, ``opencv:CSRT``...); unavailable OpenCV trackers
        are skipped with a note.  Ignored with ``results``.
    results:
        Folder ``<tracker>/<seq>.txt`` of boxes to score instead of running trackers (OPE).
    protocol:
        ``"ope"`` or ``"vot"``.
    sequences:
        Names to use (default: all).
    jobs:
        Worker processes (tasks in parallel); 1 runs in this process.
    repeats:
        Runs per (tracker, sequence), seeds ``seed .. seed + repeats - 1``.
    seed:
        First seed.
    skip, burnin:
        VOT re-initialisation delay and accuracy burn-in.
    missing:
        OPE convention for frames without a box (:func:`wmiltrack.eval.scoring.scored_boxes`):
        ``"hold"`` (default) or ``"miss"``; the same for every tracker.
    plots:
        Write the success and precision plots (OPE).
    cv_threads:
        ``cv2.setNumThreads`` wherever trackers run (default 1; ``None``: OpenCV's default).
    show_progress:
        Progress bar on stderr.
    log:
        Receives notes (skipped trackers, odd files); default prints to stderr.
    executor:
        Runs the tasks: an executor object, or ``"serial"``, ``"process"`` (``jobs``
        processes) or ``"dask"`` (:class:`~wmiltrack.eval.cluster.DaskExecutor`: a
        ``LocalCluster`` of ``jobs`` workers, or the cluster at ``scheduler``).  Default:
        serial for ``jobs == 1``, else process.
    scheduler:
        Address of a Dask scheduler (``tcp://host:8786``) for ``executor="dask"``.
    layout:
        Dataset layout (:data:`wmiltrack.data.layouts.LAYOUTS`); ``None`` detects it
        (:func:`wmiltrack.data.layouts.detect_layout`).  Each benchmark's absent frames are
        handled as its toolkit does (LaSOT: failures); GOT-10k datasets get AO, SR@0.5 and
        SR@0.75 too; sequences annotated on the first frame only are run (boxes written) but
        not scored.
    resume:
        Do not run a task whose box file is already in ``out`` with its ``.run.json`` record
        (same seed and ``missing`` rule, no error): read its boxes back instead (untimed; a
        note in the table says how many).  OPE only.
    """

    dataset: str | os.PathLike[str]
    out: str | os.PathLike[str]
    trackers: Sequence[str] = ("rcwmil",)
    results: str | os.PathLike[str] | None = None
    protocol: Protocol = "ope"
    sequences: Sequence[str] | None = None
    jobs: int = 1
    repeats: int = 1
    seed: int = 0
    skip: int = 5
    burnin: int = 10
    missing: Missing = "hold"
    plots: bool = True
    cv_threads: int | None = 1
    show_progress: bool = True
    log: Callable[[str], None] | None = None
    executor: Executor | ExecutorName | None = None
    scheduler: str | None = None
    resume: bool = False
    layout: str | None = None

    @property
    def seeds(self) -> tuple[int, ...]:
        """The seeds of the repeats: ``seed .. seed + repeats - 1``."""
        return tuple(self.seed + r for r in range(self.repeats))


def _as_config(config: EvalConfig | str | os.PathLike[str], out: str | os.PathLike[str] | None,
               options: dict[str, Any]) -> EvalConfig:
    """``config`` itself, or the :class:`EvalConfig` of the older keyword call."""
    if isinstance(config, EvalConfig):
        if out is not None or options:
            raise TypeError("run_eval(config) takes no other argument: set them in the EvalConfig")
        return config
    if out is None:
        raise TypeError("run_eval(dataset, out, ...) needs out, the output folder")
    return EvalConfig(config, out, **options)


def _scored_truths(ds: _Dataset, notes: list[str]) -> tuple[dict[str, FloatArray], list[str]]:
    """The ground truths that are scored, and the names of the sequences annotated on the first
    frame only (run, their boxes written, but left to the benchmark's server to score; a note
    says so)."""
    first_only = [n for n in ds.gts if ds.metas[n].get("first_frame_only")]
    gts = {n: g for n, g in ds.gts.items() if n not in first_only}
    if first_only:
        notes.append(
            f"not scored: {plural(len(first_only), 'sequence')} annotated on the first frame only "
            "(the benchmark's server scores them); their boxes are written"
        )
    return gts, first_only


@dataclass(frozen=True)
class _Runs:
    """What the run stage hands to scoring: the runs (scored sequences only), whether they were
    timed, the trackers' names, the number of repeats, and how many runs were read back
    (``--resume``) or failed on sequences that are not scored."""

    runs: list[RunOutcome]
    timed: bool
    trackers: list[str]
    repeats: int
    n_resumed: int
    unscored_errors: int
    runtimes: dict[str, dict[str, str]] = field(default_factory=dict)


def _obtain_runs(cfg: EvalConfig, ds: _Dataset, gts: dict[str, FloatArray], out: Path,
                 notes: list[str], files: dict[str, str], say: Callable[[str], None]) -> _Runs:
    """The run stage: read the box files of ``cfg.results`` (untimed), or run the usable
    trackers on the executor, writing their boxes under ``out`` (recorded in ``files``)."""
    if cfg.results is not None:
        runs = read_results(Path(cfg.results), gts, notes)
        out.mkdir(parents=True, exist_ok=True)
        names = list(dict.fromkeys(r.tracker for r in runs))
        return _Runs(runs, False, names, 1 + max(r.repeat for r in runs), 0, 0)
    specs = [t.strip() for t in cfg.trackers if t.strip()]
    runtimes: dict[str, str] = {}
    names = _check_trackers(specs, notes, runtimes)
    for n in notes:
        say(n)
    if not names:
        raise ValueError("no tracker left to run")
    out.mkdir(parents=True, exist_ok=True)  # once a tracker can start: nothing made before
    protocol = cfg.protocol
    box_root = out / {"ope": "boxes", "vot": "boxes_vot"}.get(protocol, f"boxes_{protocol}")
    files["boxes"] = str(box_root)
    ex = _executor(cfg.executor, cfg.jobs, cfg.cv_threads, cfg.scheduler, say)
    runs, n_resumed, unscored_errors = _run_trackers(ds, names, cfg, ex, box_root, notes, say)
    runs = [r for r in runs if r.sequence in gts]  # not the first-frame-only ones
    labels = tracker_labels(names)
    ran_by = {labels[n]: {"runtime": r, "version": runtime_version(r)} for n, r in runtimes.items()}
    return _Runs(runs, True, [labels[n] for n in names], cfg.repeats, n_resumed, unscored_errors,
                 ran_by)


def _settings(cfg: EvalConfig, n_resumed: int) -> dict[str, Any]:
    """The settings recorded in the JSON document and the table's caption: how the runs were
    made (or ``None`` where box files were read) and how they are scored."""
    results = cfg.results
    return {
        "jobs": cfg.jobs,
        "executor": None if results is not None else _executor_name(cfg.executor, cfg.jobs),
        "resumed_runs": n_resumed,
        "missing": cfg.missing,
        "skip": cfg.skip,
        "burnin": cfg.burnin,
        "cv_threads": cfg.cv_threads,
        "seeds": list(cfg.seeds) if results is None else None,
        "success_thresholds": [float(t) for t in SUCCESS_THRESHOLDS],
        "precision_thresholds": [float(t) for t in PRECISION_THRESHOLDS],
        "std": "population (ddof=0) over repeats",
    }


def run_eval(config: EvalConfig | str | os.PathLike[str],
             out: str | os.PathLike[str] | None = None, **options: Any) -> dict[str, Any]:
    """Run (or read) and score trackers on a dataset; write the table, JSON, plots and boxes.

    Parameters
    ----------
    config:
        What to run and how (:class:`EvalConfig`). For convenience the dataset folder may be
        given instead, with ``out`` and any other :class:`EvalConfig` field as keywords:
        ``run_eval(dataset, out, trackers=[...])`` is ``run_eval(EvalConfig(dataset, out,
        trackers=[...]))``.

    Returns
    -------
    dict
        The JSON document written to ``eval_<protocol>.json``, plus ``"files"``: paths
        written.

    Raises
    ------
    ValueError
        Bad arguments (``repeats < 1``, ``--results`` with VOT, no usable tracker), or a
        sequence whose images and ground truth do not line up.
    FileNotFoundError
        Missing dataset, sequences or result files.
    RuntimeError
        matplotlib missing while plots are wanted, or ``distributed`` missing with
        ``executor="dask"`` (the messages say how to install them).
    KeyboardInterrupt
        Passed on after the box files of every finished task are written.
    """
    cfg = _as_config(config, out, options)
    say = cfg.log if cfg.log is not None else (lambda s: print(s, file=sys.stderr))
    protocol, results = cfg.protocol, cfg.results
    _check_eval_arguments(cfg.repeats, cfg.jobs, protocol, cfg.missing, cfg.resume, results)
    want_plots = cfg.plots and protocol in ("ope", "longterm")
    if want_plots:
        from .plots import require_matplotlib

        require_matplotlib()  # fail before a long run, not after it
    dataset_p = Path(cfg.dataset)
    out_p = Path(cfg.out)
    ds = _open_dataset(dataset_p, cfg.layout, cfg.sequences)
    notes: list[str] = []
    gts, first_only = _scored_truths(ds, notes)
    t_start = time.perf_counter()
    files: dict[str, str] = {}
    got = _obtain_runs(cfg, ds, gts, out_p, notes, files, say)
    wall = time.perf_counter() - t_start
    settings = _settings(cfg, got.n_resumed)
    source = "run" if results is None else f"results:{Path(results).resolve()}"
    doc = _score_and_write(
        got.runs, gts, out_p, protocol, settings, got.repeats, got.timed, notes,
        want_plots and bool(gts), files, ds,
    )
    doc.update(
        dataset=str(dataset_p.resolve()),
        layout=ds.layout,
        unscored_sequences=first_only,
        unscored_errors=got.unscored_errors,
        trackers=got.trackers,
        box_folders={t: safe_name(t) for t in got.trackers},
        seeds=settings["seeds"],
        runtimes=got.runtimes,
        source=source,
        wall_time=wall,
    )
    Path(files["json"]).write_text(
        json.dumps(json_safe(doc), indent=1, allow_nan=False), encoding="utf-8"
    )
    return doc
