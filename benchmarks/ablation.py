"""rcwmil-plus's ablation: mean AUC over seeds and update FPS of each component, added to
rcwmil one at a time and taken out of rcwmil-plus one at a time; with ``--preset rcwmil-cf``,
rcwmil-cf's parts taken out (or changed) one at a time.

Usage::

    python benchmarks/ablation.py                      # 17 shared sequences x seeds 0-2, ~4 min
    python benchmarks/ablation.py --preset rcwmil-cf -j 2   # rcwmil-cf's parts, ~3 min
    python benchmarks/ablation.py --seeds 3,4 -j 2     # other seeds, two worker processes
    python benchmarks/ablation.py --json ablation.json --rows "+ colour,rcwmil-plus"

AUC: ``wmiltrack eval``'s OPE pipeline (:func:`wmiltrack.eval.pipeline.run_eval`) on the OTB
folder (``--otb``, default ``$WMILTRACK_OTB`` or ``../shared/data/otb``), one run per seed,
a box on every frame (``missing="hold"``), one OpenCV thread; the mean over sequences for each
seed, then over seeds.  FPS: update-only, measured in this process one configuration after the
other (interleaved within each round) on the first ``--fps-frames`` frames of a few sequences
decoded into memory beforehand, seed 0, median over ``--fps-repeats`` rounds.  OpenCV's
TrackerMIL (and CSRT where the installed ``cv2`` has it) run on the same frames in the same
rounds as the reference.  The configurations are tracker specs (``name:field=value``), so a
row of the table is also a ``wmiltrack.Tracker`` call.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import tempfile
from collections.abc import Sequence
from pathlib import Path

import numpy as np

try:
    import wmiltrack  # noqa: F401
except ImportError:  # a checkout that was not installed
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))

from wmiltrack.engine.params import Params

#: Each component with the rcwmil-plus values that switch it on (added to rcwmil) and the
#: values that switch it off (taken out of rcwmil-plus).
_PLUS = Params.for_variant("rcwmil-plus")
COMPONENTS: dict[str, tuple[dict[str, object], dict[str, object]]] = {
    "scale": (
        {"scale_steps": _PLUS.scale_steps, "scale_factor": _PLUS.scale_factor,
         "scale_model": _PLUS.scale_model, "scale_mix": _PLUS.scale_mix,
         "scale_penalty": _PLUS.scale_penalty, "scale_negatives": _PLUS.scale_negatives},
        {"scale_steps": 0, "scale_negatives": 0},
    ),
    "colour": (
        {"colour_weight": _PLUS.colour_weight, "colour_relative": _PLUS.colour_relative,
         "colour_learning_rate": _PLUS.colour_learning_rate, "colour_sample": _PLUS.colour_sample,
         "gray_colour": _PLUS.gray_colour},
        {"colour_weight": 0.0},
    ),
    "motion": ({"motion": _PLUS.motion}, {"motion": "none"}),
    "channels": ({"channels": ("luma", "grad", "opp_rg", "opp_yb")}, {}),
    "scale contrast": ({}, {"scale_contrast": 0.0}),
    "relative merge": ({}, {"colour_relative": None}),
    "slow colour learning": ({}, {"colour_learning_rate": 0.04}),
    "luma on gray": ({}, {"gray_colour": False}),
    "first-frame score": ({}, {"score_colour": 0.0, "score_luma": 0.0}),
}


#: rcwmil-cf's parts: the values that take each one out of rcwmil-cf (or change it).
CF_PARTS: dict[str, dict[str, object]] = {
    "- template": {"template_weight": 0.0, "judge_memory": 0.0, "judge_gates": False,
                   "judge_holds": False},
    "- the judge": {"judge_memory": 0.0, "judge_gates": False, "judge_holds": False},
    "- the judge's hold": {"judge_holds": False},
    "- DSST's vote": {"scale_dsst": 0.0},
    "DSST as the scale model": {"scale_model": "dsst", "scale_dsst": 0.0},
    "- compression": {"template_channels": 0},
    "- learning from the search sample": {"template_reuse": False},
    "- lost state": {"redetect": False, "judge_holds": False},
    "33 scale samples": {"scale_samples": 33},
}


def spec(name: str, overrides: dict[str, object]) -> str:
    """``name:field=value:...`` (values as Python literals, read back by ``literal_eval``)."""
    return ":".join([name, *(f"{k}={v!r}" for k, v in overrides.items())])


def default_rows(preset: str = "rcwmil-plus") -> dict[str, str]:
    """Row title -> tracker spec: rcwmil, + each component, rcwmil-plus, - each component;
    for rcwmil-cf: rcwmil-plus, rcwmil-cf, and rcwmil-cf with each part out or changed."""
    if preset == "rcwmil-cf":
        cf = {"rcwmil-plus": "rcwmil-plus", "rcwmil-cf": "rcwmil-cf"}
        cf.update({f"rcwmil-cf {title}": spec("rcwmil-cf", change)
                   for title, change in CF_PARTS.items()})
        return cf
    rows = {"rcwmil": "rcwmil"}
    for comp, (on, _) in COMPONENTS.items():
        if on:
            rows[f"rcwmil + {comp}"] = spec("rcwmil", on)
    rows["rcwmil-plus"] = "rcwmil-plus"
    for comp, (_, off) in COMPONENTS.items():
        if off:
            rows[f"rcwmil-plus - {comp}"] = spec("rcwmil-plus", off)
    return rows


def _parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0] if __doc__ else None)
    ap.add_argument("--otb", type=Path, default=None, help="OTB folder (default $WMILTRACK_OTB "
                    "or ../shared/data/otb)")
    ap.add_argument("--seeds", default="0,1,2", help="tracker seeds (default 0,1,2)")
    ap.add_argument("-j", "--jobs", type=int, default=1, help="worker processes for the AUC runs")
    ap.add_argument("--preset", choices=("rcwmil-plus", "rcwmil-cf"), default="rcwmil-plus",
                    help="whose parts (default rcwmil-plus)")
    ap.add_argument("--rows", default=None, help="comma-separated row titles (default: all)")
    ap.add_argument("--sequences", default=None, help="comma-separated sequence names (default all)")
    ap.add_argument("--fps-sequences", default="David,Coke,Surfer,Panda",
                    help="sequences whose first frames time the updates")
    ap.add_argument("--fps-frames", type=int, default=150)
    ap.add_argument("--fps-repeats", type=int, default=3)
    ap.add_argument("--no-progress", action="store_true")
    ap.add_argument("--json", type=Path, default=None, help="also write the figures here")
    return ap


def _aucs(root: Path, rows: dict[str, str], seeds: list[int], names: list[str] | None,
          args: argparse.Namespace) -> dict[str, list[float]]:
    """Mean AUC over the sequences, per row and seed: one run_eval per seed over every row (the
    pipeline's own conventions)."""
    from wmiltrack.eval.pipeline import EvalConfig, run_eval

    auc: dict[str, list[float]] = {title: [] for title in rows}
    with tempfile.TemporaryDirectory() as tmp:
        for seed in seeds:
            doc = run_eval(EvalConfig(root, Path(tmp) / f"seed{seed}", trackers=list(rows.values()),
                                      sequences=names, jobs=args.jobs, repeats=1, seed=seed,
                                      plots=False, show_progress=not args.no_progress))
            for title, s in rows.items():
                per_seq = doc["results"][s]
                auc[title].append(float(np.mean([v["runs"][0]["auc"] for v in per_seq.values()])))
    return auc


def _fps(paths: list[Path], timed: dict[str, str], args: argparse.Namespace) -> dict[str, float]:
    """Update FPS of every configuration on the same frames, in this process, interleaved."""
    from wmiltrack.data.sequences import load_otb_sequence
    from wmiltrack.eval.runner import run_sequence

    clips = []
    for path in paths:
        if path.name in args.fps_sequences.split(","):
            seq = load_otb_sequence(path)
            frames = seq.load()[: args.fps_frames]
            clips.append((frames, np.asarray(seq.groundtruth, dtype=np.float64)[0]))
    if not clips:
        return {}
    per: dict[str, list[float]] = {t: [] for t in timed}
    for _ in range(args.fps_repeats):
        for title, s in timed.items():
            n = sum(len(f) - 1 for f, _ in clips)
            seconds = sum((len(f) - 1) / run_sequence(s, f, box, seed=0, raise_errors=True).fps
                          for f, box in clips)
            per[title].append(n / seconds)
    return {t: statistics.median(v) for t, v in per.items()}


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ablation; print the markdown table; return the exit status."""
    from wmiltrack.data.sequences import default_otb_root, list_otb_sequences
    from wmiltrack.integrations.opencv_wheels import available_opencv_trackers
    from wmiltrack.parallel.executors import set_cv_threads

    args = _parser().parse_args(argv)
    root = args.otb or default_otb_root()
    paths = list_otb_sequences(root)
    if not paths:
        print(f"no OTB sequences under {root} (set --otb or $WMILTRACK_OTB)", file=sys.stderr)
        return 2
    rows = default_rows(args.preset)
    if args.rows:
        wanted = [r.strip() for r in args.rows.split(",") if r.strip()]
        unknown = [r for r in wanted if r not in rows]
        if unknown:
            print(f"unknown rows {unknown}; known: {list(rows)}", file=sys.stderr)
            return 2
        rows = {r: rows[r] for r in wanted}
    seeds = [int(s) for s in args.seeds.split(",")]
    names = [s.strip() for s in args.sequences.split(",")] if args.sequences else None

    auc = _aucs(root, rows, seeds, names, args)
    set_cv_threads(1)
    peers = [f"opencv:{n}" for n in ("MIL", "CSRT") if n in available_opencv_trackers()]
    fps = _fps(paths, {**rows, **{p: p for p in peers}}, args)

    print(f"\nrcwmil-plus ablation: {len(paths) if names is None else len(names)} sequences of "
          f"{root}, seeds {args.seeds}; mean AUC over sequences, then over seeds; update FPS on "
          f"the first {args.fps_frames} frames of {args.fps_sequences} (median of "
          f"{args.fps_repeats} rounds, one process, one OpenCV thread)\n")
    print("| configuration | mean AUC | " + " / ".join(f"seed {s}" for s in seeds) + " | FPS |")
    print("|---|---|---|---|")
    for title in rows:
        a = auc[title]
        print(f"| {title} | {np.mean(a):.3f} | " + " / ".join(f"{x:.3f}" for x in a)
              + f" | {fps.get(title, float('nan')):.0f} |")
    for p in peers:
        print(f"| {p} | (not run: see `wmiltrack eval`) | | {fps[p]:.0f} |")
    print("\nSpecs: " + "; ".join(f"{t}: `{s}`" for t, s in rows.items()))
    if args.json is not None:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps({"rows": rows, "seeds": seeds, "auc": auc, "fps": fps},
                                        indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
