"""``wmiltrack eval``: run and score trackers on a dataset (see :mod:`wmiltrack.eval`)."""

from __future__ import annotations

import argparse
import math
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from ..data.layouts import LAYOUTS
from .options import (
    EXIT_CODES_EPILOG,
    Subparsers,
    UsageError,
    add_executor_options,
    add_model_options,
    check_tracker_spec,
    specs_with_model_files,
    trackers_help,
)
from .outputs import check_output_folder


def _cmd_eval(args: argparse.Namespace) -> int:
    from ..trackers import split_specs

    if args.dataset.is_file():
        raise UsageError(f"{args.dataset} is a file, not a dataset folder: eval takes a folder of "
                         "sequences (OTB, LaSOT, GOT-10k, UAV123, UAV123_10fps, UAV20L, DTB70, "
                         "TrackingNet or VOT layout); to track one video use `wmiltrack track`")
    check_output_folder("--out", args.out, args.dataset)
    trackers = split_specs(args.trackers)
    if args.results is None and not trackers:
        raise UsageError("give --trackers (or --results DIR to score existing box files)")
    if args.results is None:
        for spec in trackers:
            check_tracker_spec(spec)  # an unknown tracker or parameter: exit status 2
        trackers = specs_with_model_files(trackers, args)
    from ..eval.pipeline import EvalArgumentError, EvalConfig, run_eval

    try:
        doc = run_eval(EvalConfig(
            args.dataset,
            args.out,
            trackers=trackers,
            results=args.results,
            protocol=args.protocol,
            sequences=split_specs(args.sequences) or None,
            jobs=args.jobs,
            repeats=args.repeats,
            seed=args.seed,
            skip=args.skip,
            burnin=args.burnin,
            missing=args.missing,
            plots=not args.no_plots,
            cv_threads=args.cv_threads,
            show_progress=not (args.no_progress or args.quiet),
            executor=args.executor,
            scheduler=args.scheduler,
            resume=args.resume,
            layout=args.layout,
        ))
    except EvalArgumentError as exc:  # options that do not go together: exit status 2
        raise UsageError(str(exc)) from None
    print(Path(doc["files"]["table"]).read_text(encoding="utf-8"))
    return _report(args, doc)


def _report(args: argparse.Namespace, doc: dict[str, Any]) -> int:
    """Print the table (and, unless --quiet, the files written); the exit status."""
    if not args.quiet:
        print(f"(wall time {doc['wall_time']:.1f} s)")
        for key, path in doc["files"].items():
            print(f"wrote {key}: {path}")
    errors = sum(s.get("errors", 0) for s in doc["summary"].values())
    errors += doc.get("unscored_errors", 0)
    return 1 if errors else 0


def score_runs(trackers: list[str], frames: list[Any], gt: Any, seed: int
               ) -> Iterator[tuple[str, tuple[float, float, float, float], str | None]]:
    """Each tracker run on ``frames`` from ``gt[0]`` and scored as ``eval`` scores it (the last
    box held): ``(name, (AUC, SR@0.5, P@20, update frames/s), problem)`` (for ``demo``). A
    tracker that cannot start (not installed, its model files missing) gives ``"skipped: "``
    and why, one that fails ``"failed: "`` and its error, both with NaN figures; the others
    still run. The problem is said here only (no warning besides)."""
    import warnings

    from ..eval.metrics import ope_metrics
    from ..eval.runner import run_sequence
    from ..eval.scoring import scored_boxes
    from ..integrations.opencv_wheels import TrackerUnavailable

    for name in (t.strip() for t in trackers):
        try:
            with warnings.catch_warnings():  # the failure is the table's line, not a warning
                warnings.filterwarnings("ignore", message="tracker .* raised at frame",
                                        category=RuntimeWarning)
                run = run_sequence(name, frames, gt[0], seed=seed)
        except TrackerUnavailable as exc:  # not installed, or its model files not given
            yield name, (math.nan,) * 4, f"skipped: {exc}"
            continue
        if run.error:
            yield name, (math.nan,) * 4, f"failed: {run.error}"
            continue
        m = ope_metrics(scored_boxes(run.boxes, run.oks), gt)
        yield name, (m.auc, m.success_50, m.precision_20, run.fps), None


def add_eval(sub: Subparsers) -> None:
    """Add the ``eval`` subcommand.

    Parameters
    ----------
    sub:
        The subparsers object of the ``wmiltrack`` parser.
    """
    p = sub.add_parser(
        "eval",
        help="benchmark trackers on an OTB-layout dataset (OPE, VOT or long-term protocol)",
        description="Run trackers on every sequence of an OTB-layout dataset (or score box "
        "files of other trackers with --results) and write a markdown table, a JSON file with "
        "every figure, success/precision plots and per-sequence box files to --out.",
        epilog="Speed: update-only FPS on pre-decoded frames, OpenCV on one thread unless "
        "--cv-threads says otherwise. Parallel workers (-j) share the cores: for honest speed "
        "figures use -j 1. A frame where a tracker gives no box keeps its last box (--missing "
        "hold); a frame left without a box is a miss in every figure. Besides the success and "
        "precision plots, accuracy_speed.png puts each tracker at its mean AUC and FPS of the "
        "same run. " + EXIT_CODES_EPILOG + " For eval: 1 also when a run of a tracker failed "
        "(the table names it); a tracker that is not installed, or whose model files are not "
        "given, is skipped with a note.",
    )
    p.add_argument(
        "dataset",
        type=Path,
        help="dataset folder (OTB, LaSOT, GOT-10k, UAV123, UAV123_10fps, UAV20L, DTB70, "
        "TrackingNet or VOT layout, detected), or one sequence folder",
    )
    p.add_argument(
        "--layout",
        choices=LAYOUTS,
        default=None,
        help="the dataset's layout (default: detected); absent frames are handled as each "
        "benchmark does, and GOT-10k datasets get AO, SR@0.5 and SR@0.75 too",
    )
    p.add_argument(
        "--trackers",
        default="rcwmil",
        help="comma-separated trackers, each " + trackers_help(None) + ", optionally with "
        ":key=value parameter overrides (values as Python literals; commas inside brackets or "
        "quotes stay in the value); default rcwmil",
    )
    p.add_argument(
        "--results",
        type=Path,
        default=None,
        metavar="DIR",
        help="score box files DIR/<tracker>/<seq>.txt instead of running trackers",
    )
    p.add_argument("--out", type=Path, required=True, help="output folder")
    add_executor_options(p, "the dataset")
    _add_protocol_options(p)
    _add_output_options(p)
    add_model_options(p)
    p.set_defaults(func=_cmd_eval)


def _add_protocol_options(p: argparse.ArgumentParser) -> None:
    """Add the options that say how the trackers are run and scored: repeats, the protocol,
    the sequences, the seed and each protocol's own settings (kept apart from ``add_eval`` so
    that each function reads as one group of the help text, in the same order)."""
    p.add_argument(
        "--repeats",
        type=int,
        default=1,
        help="runs per tracker and sequence with seeds seed, seed+1, ... (default 1)",
    )
    p.add_argument(
        "--protocol",
        choices=("ope", "vot", "longterm"),
        default="ope",
        help="ope: OTB one-pass (default); vot: VOT-style supervised with resets (VOT2015's "
        "rules on OTB's axis-aligned boxes); longterm: one pass scored with the VOT long-term "
        "measures, tracking precision, recall and F-score over each tracker's confidence "
        "thresholds and at its own lost flag, absent frames counted (rewards a tracker that "
        "says when it has lost the target)",
    )
    p.add_argument("--sequences", default=None, help="comma-separated names (default all)")
    p.add_argument("--seed", type=int, default=0, help="first tracker seed (default 0)")
    p.add_argument("--skip", type=int, default=5, help="VOT: frames to re-init (default 5)")
    p.add_argument(
        "--burnin",
        type=int,
        default=10,
        help="VOT: frames left out of accuracy after each init (default 10)",
    )
    p.add_argument(
        "--missing",
        choices=("hold", "miss"),
        default="hold",
        help="OPE: a frame where a tracker gives no box gets its last box (hold, default, as "
        "the OTB and got10k toolkits), or every frame a tracker reports lost is a miss (miss); "
        "either way the same rule for every tracker",
    )


def _add_output_options(p: argparse.ArgumentParser) -> None:
    """Add the options for the workers' threads, resuming, the plots and what is printed (the
    last group of ``eval``'s help text, in the same order)."""
    p.add_argument(
        "--cv-threads",
        type=int,
        default=1,
        help="cv2.setNumThreads(N) in every worker (default 1: one thread per tracker, as "
        "wmiltrack uses; 0 lets OpenCV choose)",
    )
    p.add_argument(
        "--resume",
        action="store_true",
        help="OPE: skip the runs whose box file is already in --out (read back, untimed), so an "
        "interrupted run finishes only what is missing; failed runs are run again",
    )
    p.add_argument("--no-plots", action="store_true", help="do not write the PNG plots")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("-q", "--quiet", action="store_true",
                   help="no progress bar, notes or list of files written: the table only")
