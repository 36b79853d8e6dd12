"""``wmiltrack demo``: track the built-in generated sequence and print accuracy and speed."""

from __future__ import annotations

import argparse

from .options import Subparsers


def _cmd_demo(args: argparse.Namespace) -> int:
    from ..data.synthetic import make_preset
    from ..eval.metrics import ope_metrics
    from ..eval.runner import run_sequence
    from ..eval.scoring import scored_boxes

    seq = make_preset("all", seed=args.seed, n_frames=args.frames)
    frames = seq.load()
    gt = seq.groundtruth
    assert gt is not None
    print(f"built-in sequence: {len(frames)} frames of {frames[0].shape[1]}x{frames[0].shape[0]}, "
          "moving textured target with partial occlusion, illumination change and clutter")
    print(f"{'tracker':<10} {'AUC':>6} {'SR@0.5':>7} {'P@20':>6} {'fps':>8}")
    for name in args.trackers.split(","):
        run = run_sequence(name.strip(), frames, gt[0], seed=args.seed)
        if run.error:
            print(f"{name:<10} failed: {run.error}")
            continue
        m = ope_metrics(scored_boxes(run.boxes, run.oks), gt)  # hold the last box, as eval
        print(f"{name:<10} {m.auc:6.3f} {m.success_50:7.3f} {m.precision_20:6.3f} {run.fps:8.0f}")
    return 0


def add_demo(sub: Subparsers) -> None:
    """Add the ``demo`` subcommand to ``sub``."""
    p = sub.add_parser("demo", help="run the tracker on a built-in generated sequence",
                       description="Track the target of a generated sequence (moving textured target, "
                       "partial occlusion, illumination change, cluttered background) and print the "
                       "success AUC, success rate, precision and update-only frames per second.")
    p.add_argument("--trackers", default="rcwmil",
                   help="comma-separated trackers (default rcwmil), e.g. rcwmil,ct,opencv:MIL")
    p.add_argument("--frames", type=int, default=300, help="sequence length (default 300)")
    p.add_argument("--seed", type=int, default=0, help="seed of the sequence and trackers")
    p.set_defaults(func=_cmd_demo)
