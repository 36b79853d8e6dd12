"""Compare trackers on OTB sequences: accuracy (one-pass) and update-only speed.

Usage::

    python benchmarks/compare.py ../shared/data/otb
    python benchmarks/compare.py ../shared/data/otb --trackers rcwmil,ct,opencv:MIL \\
        --sequences David,Coke --repeats 3 --json results/compare.json

Every tracker runs on the same frames, decoded before any timing starts, one sequence at a
time.  The table lists per sequence and in the mean: success AUC (21 thresholds, IoU > t),
success rate at IoU 0.5, precision at 20 px, mean centre error, update-only FPS and the FPS
ratio to the reference tracker (``opencv:MIL`` unless ``--reference`` says otherwise), which
is always run too, in the same session, so the ratio compares like with like.

With ``--repeats R`` each (tracker, sequence) runs R times, the trackers interleaved within
each round; FPS is the median of the R runs, and the accuracy figures come from the first
run (all runs use the same ``--seed``; the JSON records whether they gave identical boxes).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

import numpy as np

try:
    import wmiltrack  # noqa: F401
except ImportError:  # running from a checkout that was not installed
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))

from wmiltrack.data.sequences import Sequence as OTBSequence
from wmiltrack.data.sequences import list_otb_sequences, load_otb_sequence
from wmiltrack.eval.peers import TrackerUnavailable, make_tracker
from wmiltrack.eval.runner import environment, evaluate_sequences, format_table, json_safe, summarize

DEFAULT_TRACKERS = "rcwmil,opencv:MIL"


class LazySequences:
    """Sized iterable that loads one OTB sequence at a time (frames freed after use)."""

    def __init__(self, paths: Sequence[Path]) -> None:
        self.paths = list(paths)

    def __len__(self) -> int:
        return len(self.paths)

    def __iter__(self) -> Iterator[OTBSequence]:
        for p in self.paths:
            yield load_otb_sequence(p)


def _split(text: str | None) -> list[str]:
    return [t.strip() for t in (text or "").split(",") if t.strip()]


def parse_args(argv: Sequence[str] | None = None) -> argparse.Namespace:
    """Command-line arguments."""
    ap = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0] if __doc__ else None,
        epilog=(
            "FPS counts tracker.update() time only (frames pre-decoded, init excluded). "
            "With --repeats the FPS is the median over runs and accuracy is from the first run."
        ),
    )
    ap.add_argument("root", type=Path, help="folder holding OTB sequence folders")
    ap.add_argument(
        "--trackers",
        default=DEFAULT_TRACKERS,
        help=f"comma-separated tracker names (default {DEFAULT_TRACKERS}); "
        "wmiltrack variants or opencv:NAME",
    )
    ap.add_argument("--sequences", default=None, help="comma-separated names (default: all)")
    ap.add_argument("--repeats", type=int, default=1, help="runs per tracker and sequence")
    ap.add_argument("--seed", type=int, default=0, help="tracker seed")
    ap.add_argument("--reference", default="opencv:MIL", help="tracker FPS ratios refer to")
    ap.add_argument("--json", type=Path, default=None, help="write all results to this file")
    ap.add_argument("--style", choices=("markdown", "plain"), default="markdown")
    ap.add_argument(
        "--cv-threads",
        type=int,
        default=None,
        help="cv2.setNumThreads(N) before running (default: OpenCV's own choice)",
    )
    ap.add_argument(
        "--missing",
        choices=("miss", "hold"),
        default="miss",
        help="frames where a tracker gives no box (OpenCV: not found): 'miss' scores IoU 0, "
        "'hold' uses its last box as the OTB toolkit does (default miss)",
    )
    ap.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")
    ap.add_argument("--seeds", default=None,
                    help="comma-separated seeds (e.g. 0,1,2,3): every tracker runs once per seed and "
                    "the summary gives mean ± std over seeds (overrides --seed)")
    ap.add_argument("--summary-only", action="store_true",
                    help="print only the per-tracker means, not the per-sequence rows")
    args = ap.parse_args(argv)
    if args.repeats < 1:
        ap.error("--repeats must be at least 1")
    return args


def format_summary(
    summaries: Sequence[dict[str, dict[str, Any]]], n_sequences: int, reference: str,
    seeds: Sequence[int] = (0,),
) -> str:
    """One markdown row per tracker, sorted by success AUC: means over the sequences, and
    with several seeds the mean (+- standard deviation) over seeds; FPS is the median over
    seeds."""

    def stat(name: str, key: str, fmt: str) -> str:
        vals = np.array([s[name][key] for s in summaries], dtype=float)
        text = format(float(np.mean(vals)), fmt)
        if len(vals) > 1:
            text += " ± " + format(float(np.std(vals)), fmt)
        return text

    names = list(summaries[0])
    mean_auc = {n: float(np.mean([s[n]["auc"] for s in summaries])) for n in names}
    seed_note = f", {len(seeds)} seeds ({', '.join(map(str, seeds))})" if len(seeds) > 1 else ""
    lines = [
        f"Mean over {n_sequences} sequences{seed_note}; FPS ratio: to {reference} in the same run",
        "",
        "| Tracker | AUC | SR@0.5 | P@20 | CLE px | FPS | FPS ratio |",
        "|---|---|---|---|---|---|---|",
    ]
    for name in sorted(names, key=lambda n: -mean_auc[n]):
        fps = float(np.median([s[name]["fps"] for s in summaries]))
        ratio = float(np.median([s[name]["fps_ratio"] for s in summaries]))
        lines.append(
            f"| {name} | {stat(name, 'auc', '.3f')} | {stat(name, 'success_50', '.3f')} | "
            f"{stat(name, 'precision_20', '.3f')} | {stat(name, 'mean_center_error', '.1f')} | "
            f"{fps:.0f} | {ratio:.1f} |"
        )
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the comparison; return the process exit status."""
    args = parse_args(argv)
    trackers = _split(args.trackers)
    if not trackers:
        print("no trackers given", file=sys.stderr)
        return 2
    if args.reference not in trackers:
        trackers.append(args.reference)
    # fail before any long run if a tracker cannot even be created
    for spec in trackers:
        try:
            make_tracker(spec, seed=args.seed)
        except (TrackerUnavailable, ValueError, ImportError) as exc:
            print(f"cannot create tracker {spec!r}: {exc}", file=sys.stderr)
            return 2

    try:
        paths = list_otb_sequences(args.root)
    except FileNotFoundError as exc:
        print(exc, file=sys.stderr)
        return 2
    wanted = _split(args.sequences)
    if wanted:
        by_name = {p.name: p for p in paths}
        missing = [n for n in wanted if n not in by_name]
        if missing:
            print(
                f"sequence(s) not found: {', '.join(missing)}; "
                f"available: {', '.join(sorted(by_name))}",
                file=sys.stderr,
            )
            return 2
        paths = [by_name[n] for n in wanted]
    if not paths:
        print(f"no OTB sequence under {args.root}", file=sys.stderr)
        return 2

    if args.cv_threads is not None:
        import cv2

        cv2.setNumThreads(args.cv_threads)
    env = environment()
    print(
        f"# {len(paths)} sequences, trackers {', '.join(trackers)}, repeats {args.repeats}, "
        f"seed {args.seed}\n# python {env['python']}, numpy {env['numpy']}, {env['opencv_wheel']} "
        f"({env['opencv_threads']} threads), wmiltrack {env['wmiltrack']}, "
        f"{env['cpu']}, {env['cpu_count']} CPUs; frames without a box scored as {args.missing}\n"
    )
    seeds = [int(v) for v in args.seeds.split(",")] if args.seeds else [args.seed]
    t0 = time.perf_counter()
    per_seed = []
    for seed in seeds:
        records = evaluate_sequences(
            trackers,
            LazySequences(paths),
            seed=seed,
            repeats=args.repeats,
            progress=not args.no_progress,
            missing=args.missing,
        )
        per_seed.append((seed, records))
    wall = time.perf_counter() - t0
    records = per_seed[0][1]
    if not args.summary_only:
        if len(seeds) > 1:
            print(f"Per sequence, seed {seeds[0]}:\n")
        print(format_table(records, reference=args.reference, style=args.style))
        print()
    summaries = [summarize(recs, reference=args.reference) for _, recs in per_seed]
    print(format_summary(summaries, len(paths), args.reference, seeds))
    print(f"\n(wall time {wall:.1f} s)")

    if args.json is not None:
        out = {
            "environment": env,
            "args": {
                "root": str(args.root),
                "trackers": trackers,
                "sequences": [p.name for p in paths],
                "repeats": args.repeats,
                "seed": args.seed,
                "seeds": seeds,
                "reference": args.reference,
                "accuracy_from": "first run",
                "missing": args.missing,
                "fps": "median over runs of update-only FPS",
            },
            "seeds": seeds,
            "summary": summaries[0],
            "summary_per_seed": dict(zip(map(str, seeds), summaries)),
            "records": [r.to_dict() for r in records],
        }
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(json_safe(out), indent=1, allow_nan=False))
        print(f"wrote {args.json}")
    return 1 if any(r.error is not None for r in records) else 0


if __name__ == "__main__":
    sys.exit(main())
