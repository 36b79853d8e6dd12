"""``wmiltrack demo``: track the built-in generated sequence and print accuracy and speed."""

from __future__ import annotations

import argparse

from .options import EXIT_CODES_EPILOG, Subparsers, check_tracker_spec, trackers_help


def _cmd_demo(args: argparse.Namespace) -> int:
    from ..data.synthetic import make_preset
    from ..trackers import split_specs
    from .eval import score_runs  # the demo's scores are the eval command's

    trackers = split_specs(args.trackers)
    for spec in trackers:
        check_tracker_spec(spec)  # an unknown tracker or parameter: exit status 2
    seq = make_preset("all", seed=args.seed, n_frames=args.frames)
    frames = seq.load()
    gt = seq.groundtruth
    assert gt is not None
    print(f"built-in sequence: {len(frames)} frames of {frames[0].shape[1]}x{frames[0].shape[0]}, "
          "moving textured target with partial occlusion, illumination change and clutter")
    width = max(len("tracker"), *(len(t) for t in trackers))
    print(f"{'tracker':<{width}} {'AUC':>6} {'SR@0.5':>7} {'P@20':>6} {'fps':>8}")
    for name, scores, error in score_runs(trackers, frames, gt, args.seed):
        if error:
            first, *rest = error.splitlines()
            print(f"{name:<{width}} {first}")
            for line in rest:  # e.g. the install commands of a tracker not installed
                print(f"{'':<{width}} {line}")
            continue
        auc, success_50, precision_20, fps = scores
        print(f"{name:<{width}} {auc:6.3f} {success_50:7.3f} {precision_20:6.3f} {fps:8.0f}")
    return 0


def add_demo(sub: Subparsers) -> None:
    """Add the ``demo`` subcommand to ``sub``."""
    p = sub.add_parser("demo", help="run the tracker on a built-in generated sequence",
                       description="Track the target of a generated sequence (moving textured target, "
                       "partial occlusion, illumination change, cluttered background) and print the "
                       "success AUC, success rate, precision and update-only frames per second.",
                       epilog=EXIT_CODES_EPILOG + " For demo: a tracker that cannot start (one "
                       "not installed, or whose model files are missing) is skipped with its "
                       "reason, one that fails is named in the table, and the status stays 0.")
    p.add_argument("--trackers", default="rcwmil",
                   help="comma-separated trackers, each " + trackers_help() + "; e.g. "
                   "rcwmil,ct,opencv:MIL")
    p.add_argument("--frames", type=int, default=300, help="sequence length (default 300)")
    p.add_argument("--seed", type=int, default=0, help="seed of the sequence and trackers")
    p.set_defaults(func=_cmd_demo)
