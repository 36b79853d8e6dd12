"""How far the two network runtimes' boxes differ: onnxruntime against OpenCV's dnn.

The network trackers (``rcwmil-nano``, ``nanotrack:v2``/``v3``) run their ONNX files with
onnxruntime where it is installed, else with OpenCV's ``cv2.dnn``. The two runtimes compute
the same network in a different order of floating-point operations, so their features differ
in the last bits, and a tracker that follows them can end up elsewhere after many frames.
For each tracker spec, this runs every sequence once with each runtime (one seed, the first
box as given, one thread each) and prints, per tracker:

* the mean IoU between the two runtimes' boxes (over every frame after the first, then over
  sequences), the smallest sequence's mean, and the largest centre distance in pixels;
* the success AUC (mean over sequences) of each runtime.

    WMILTRACK_MODELS=/path/to/models python benchmarks/runtimes.py ../shared/data/otb \\
        --trackers rcwmil-nano,nanotrack:v3 -j 2 [--json out.json]

The runtime is set per tracker: ``network_runtime=`` for wmiltrack's presets, ``runtime=`` for
``nanotrack:VERSION``.
"""

from __future__ import annotations

import argparse
import json
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np

from wmiltrack.data.sequences import load_dataset
from wmiltrack.eval.metrics import iou, ope_metrics
from wmiltrack.eval.runner import run_sequence
from wmiltrack.progress import progress
from wmiltrack.trackers import split_specs

RUNTIMES = ("onnxruntime", "opencv")


def with_runtime(spec: str, runtime: str) -> str:
    """``spec`` with its runtime set: ``runtime=`` for NanoTrack alone, else
    ``network_runtime=``."""
    key = "runtime" if spec.startswith("nanotrack:") else "network_runtime"
    return f"{spec}:{key}={runtime}"


def _run(job: tuple[str, str, str, str, int]) -> dict[str, Any]:
    """One tracker with one runtime on one sequence: its boxes (a frame without a box keeps
    the last one)."""
    spec, runtime, root, name, seed = job
    import cv2

    cv2.setNumThreads(1)
    seq = load_dataset(root, [name])[0]
    run = run_sequence(with_runtime(spec, runtime), seq.load(), seq.init_box, seed=seed,
                       raise_errors=True)
    boxes = run.boxes.copy()
    for i in range(1, len(boxes)):
        if not np.all(np.isfinite(boxes[i])):
            boxes[i] = boxes[i - 1]
    return {"spec": spec, "runtime": runtime, "name": name, "boxes": boxes.tolist()}


def compare(runs: list[dict[str, Any]], gts: dict[str, np.ndarray]) -> dict[str, Any]:
    """One tracker's figures from its runs with both runtimes."""
    by = {(r["runtime"], r["name"]): np.asarray(r["boxes"]) for r in runs}
    names = sorted(gts)
    agree, far = {}, 0.0
    for n in names:
        a, b = by[(RUNTIMES[0], n)], by[(RUNTIMES[1], n)]
        agree[n] = float(np.mean(iou(a[1:], b[1:])))
        ca, cb = a[:, :2] + a[:, 2:] / 2, b[:, :2] + b[:, 2:] / 2
        far = max(far, float(np.max(np.hypot(*(ca - cb).T))))
    auc = {rt: float(np.mean([ope_metrics(by[(rt, n)], gts[n], missing="hold").auc
                              for n in names])) for rt in RUNTIMES}
    worst = min(agree, key=lambda n: agree[n])
    return {"mean_iou": float(np.mean(list(agree.values()))), "worst": worst,
            "worst_iou": agree[worst], "largest_centre_px": far, "auc": auc,
            "per_sequence_iou": agree}


def main(argv: list[str] | None = None) -> int:
    """Run the trackers with both runtimes and print how far their boxes differ."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("root", type=Path, help="an OTB-layout folder of sequences")
    ap.add_argument("--trackers", default="rcwmil-nano,nanotrack:v3")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--sequences", default=None, help="comma-separated names (default all)")
    ap.add_argument("-j", "--jobs", type=int, default=1)
    ap.add_argument("--json", type=Path, default=None, help="write every figure here")
    args = ap.parse_args(argv)
    names = None if args.sequences is None else args.sequences.split(",")
    seqs = load_dataset(args.root, names)
    gts = {s.name: s.groundtruth for s in seqs}
    specs = split_specs(args.trackers)
    order = sorted(gts, key=lambda n: -len(gts[n]))  # long sequences first
    jobs = [(spec, rt, str(args.root), n, args.seed) for spec in specs for n in order
            for rt in RUNTIMES]
    with ProcessPoolExecutor(args.jobs) as pool:
        runs = list(progress(pool.map(_run, jobs), total=len(jobs), desc="runs"))
    summary = {}
    print(f"{len(gts)} sequences, seed {args.seed}, one run each")
    print("| tracker | mean IoU between runtimes | lowest (sequence) | largest centre gap (px) "
          "| AUC onnxruntime | AUC OpenCV dnn |")
    print("|---|---|---|---|---|---|")
    for spec in specs:
        s = compare([r for r in runs if r["spec"] == spec], gts)
        summary[spec] = s
        print(f"| {spec} | {s['mean_iou']:.3f} | {s['worst_iou']:.3f} ({s['worst']}) | "
              f"{s['largest_centre_px']:.1f} | {s['auc']['onnxruntime']:.3f} | "
              f"{s['auc']['opencv']:.3f} |")
    if args.json is not None:
        args.json.write_text(json.dumps({"summary": summary, "runs": runs}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
