"""Accuracy and the lost flag on the development set, split in its two fixed halves.

The development set is every OTB-layout sequence folder under the roots given: the 17 shared
sequences, the 17 that ``shared/data/more/build.py`` builds and the 26 that
``shared/data/more2/build.py`` builds, 60 in all. Its halves are fixed
before any setting is chosen: the sequence names sorted with Python's ``sorted``, then
alternated (half 1 = positions 0, 2, 4, ...). A setting is chosen on one half and kept only
if it helps on both.

For each tracker spec (as ``wmiltrack eval`` takes them, ``opencv:Nano`` included) and seed,
every sequence is tracked from its first box with a box on every frame (a tracker that gives
none keeps its last box), and this prints:

* the mean success AUC per half (the mean over sequences, then over seeds) and over all;
* the lost flag: the share of frames with IoU >= 0.5 that the tracker flagged lost (it should
  be small), and the share of frames with IoU == 0 or an absent target that it flagged lost
  (it should be large), pooled over sequences and seeds. A sequence annotated only on some
  frames (its pool's ``_meta.json`` calls it sparse: a missing box there means "not
  annotated", not "absent") counts only its annotated frames;
* with ``--against``: the collapse check, every sequence where the first tracker scores below
  0.10 while one of the others scores above 0.40.

One pixel of the first box can move a deterministic tracker's set mean by 0.04, so every run
starts from a jittered first box (``--jitter``, on by default): seed ``s`` on sequence ``n``
shifts the box by ``(dx, dy)``, a seeded draw (from ``s`` and ``n`` only, so the same for every
tracker) of length between 0.25 and 1 pixel in a uniform direction. OpenCV's trackers and
NanoTrack, which take no seed, so get three different runs too. The spread printed is the
standard deviation over seeds of each half's mean. ``--jitter 0`` starts from the box as given.

    python benchmarks/devset.py --roots ../shared/data/otb,$MORE_DIR,$MORE2_DIR \\
        --trackers rcwmil-cf,rcwmil-plus --seeds 0,1,2 -j 2 [--json out.json]

``WMILTRACK_DEVSET`` (a comma-separated list of roots) replaces ``--roots``. OpenCV's
TrackerNano reads its two model files from ``WMILTRACK_NANO_BACKBONE`` and
``WMILTRACK_NANO_HEAD`` (never shipped with the project). OpenCV runs on one thread.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
from collections.abc import Collection
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np

from wmiltrack.data.sequences import load_dataset
from wmiltrack.eval.metrics import iou, ope_metrics, valid_mask
from wmiltrack.eval.runner import run_sequence
from wmiltrack.progress import progress
from wmiltrack.trackers import split_specs


def halves(names: list[str]) -> tuple[list[str], list[str]]:
    """The two fixed halves: ``sorted`` names, alternated."""
    ordered = sorted(names)
    return ordered[0::2], ordered[1::2]


def sparse_sequences(roots: list[Path]) -> set[str]:
    """The sequences whose pool (``_meta.json`` beside them, as ``shared/data/more2/build.py``
    writes it) says their ground truth is sparse: a missing box means "not annotated"."""
    out: set[str] = set()
    for root in roots:
        meta = Path(root) / "_meta.json"
        if not meta.is_file():
            continue
        for name, entry in json.loads(meta.read_text()).items():
            text = f"{entry.get('gt_format', '')} {entry.get('notes', '')}" if isinstance(entry, dict) else ""
            if "sparse" in text.lower():
                out.add(name)
    return out


def find_sequences(roots: list[Path]) -> dict[str, Path]:
    """Sequence name -> the root that holds it (names must be unique over the roots)."""
    where: dict[str, Path] = {}
    for root in roots:
        for seq in load_dataset(root, None):
            if seq.name in where:
                raise SystemExit(f"sequence {seq.name} is in both {where[seq.name]} and {root}")
            where[seq.name] = root
    return where


def jitter(box: Any, seed: int, name: str, pixels: float) -> tuple[float, float, float, float]:
    """``box`` shifted by the seeded offset of ``seed`` and ``name`` (the same for every
    tracker): a length in ``[pixels / 4, pixels]``, a uniform direction."""
    x, y, w, h = (float(v) for v in box)
    if pixels <= 0:
        return x, y, w, h
    key = [seed, *name.encode()]
    rng = np.random.default_rng(key)
    length = rng.uniform(0.25 * pixels, pixels)
    angle = rng.uniform(0.0, 2.0 * math.pi)
    return x + length * math.cos(angle), y + length * math.sin(angle), w, h


def _run(job: tuple[str, int, str, str, float]) -> dict[str, Any]:
    """One tracker on one sequence with one seed (``wmiltrack.eval``'s own run) from the
    jittered first box: per-frame boxes (a frame without a box keeps the last one), scores
    and lost flags."""
    spec, seed, root, name, pixels = job
    import cv2

    cv2.setNumThreads(1)
    seq = load_dataset(root, [name])[0]
    start = jitter(seq.init_box, seed, name, pixels)
    run = run_sequence(spec, seq.load(), start, seed=seed, raise_errors=True)
    boxes = run.boxes.copy()
    for i in range(1, len(boxes)):
        if not np.all(np.isfinite(boxes[i])):
            boxes[i] = boxes[i - 1]
    return {"spec": spec, "seed": seed, "name": name, "boxes": boxes.tolist(),
            "lost": (~run.oks).tolist(), "scores": run.scores.tolist(),
            "seconds": float(np.nansum(run.update_times)), "updates": run.n_updates}


def summarise(runs: list[dict[str, Any]], gts: dict[str, np.ndarray], names: list[str],
              sparse: Collection[str] = ()) -> dict[str, Any]:
    """Per-half AUC and lost-flag shares of one tracker's runs."""
    h1, h2 = halves(names)
    auc: dict[str, dict[int, float]] = {}
    well = flagged_well = bad = flagged_bad = 0
    for r in runs:
        gt = gts[r["name"]]
        boxes = np.asarray(r["boxes"])
        auc.setdefault(r["name"], {})[r["seed"]] = ope_metrics(boxes, gt, missing="hold").auc
        ov = iou(boxes[1:], gt[1:])
        absent = ~valid_mask(gt[1:])
        if r["name"] in sparse:  # a missing box is "not annotated": leave those frames out
            ov = np.where(absent, np.nan, ov)
            absent = np.zeros_like(absent)
        lost = np.asarray(r["lost"][1:], dtype=bool)
        good = np.isfinite(ov) & (ov >= 0.5) & ~absent
        off = absent | (np.isfinite(ov) & (ov == 0))
        well += int(good.sum())
        flagged_well += int((good & lost).sum())
        bad += int(off.sum())
        flagged_bad += int((off & lost).sum())
    seeds = sorted({r["seed"] for r in runs})

    def per_seed(ns: list[str]) -> list[float]:
        return [float(np.mean([auc[n][s] for n in ns])) for s in seeds]

    return {
        "half1": float(np.mean(per_seed(h1))), "half2": float(np.mean(per_seed(h2))),
        "all": float(np.mean(per_seed(sorted(names)))),
        "half1_spread": float(np.std(per_seed(h1))), "half2_spread": float(np.std(per_seed(h2))),
        "per_sequence": {n: float(np.mean(list(auc[n].values()))) for n in sorted(auc)},
        "well_tracked_flagged_lost": flagged_well / well if well else math.nan,
        "off_target_flagged_lost": flagged_bad / bad if bad else math.nan,
        "frames_well_tracked": well, "frames_off_target": bad,
        "updates_per_second": sum(r["updates"] for r in runs) / sum(r["seconds"] for r in runs),
    }


def main(argv: list[str] | None = None) -> int:
    """Run the trackers over the development set and print the figures."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--roots", default=os.environ.get("WMILTRACK_DEVSET"),
                    help="comma-separated OTB-layout folders (default: $WMILTRACK_DEVSET)")
    ap.add_argument("--trackers", default="rcwmil-cf")
    ap.add_argument("--seeds", default="0,1,2")
    ap.add_argument("--sequences", default=None, help="comma-separated names (default all)")
    ap.add_argument("-j", "--jobs", type=int, default=1)
    ap.add_argument("--against", action="store_true",
                    help="the collapse check of the first tracker against the others")
    ap.add_argument("--jitter", type=float, default=1.0,
                    help="largest shift of the first box in pixels, seeded per seed and sequence "
                    "(default 1; 0: the box as given)")
    ap.add_argument("--json", type=Path, default=None, help="write every figure here")
    args = ap.parse_args(argv)
    if not args.roots:
        ap.error("give --roots or set WMILTRACK_DEVSET")
    where = find_sequences([Path(r) for r in args.roots.split(",")])
    names = sorted(where) if args.sequences is None else sorted(args.sequences.split(","))
    gts = {n: load_dataset(where[n], [n])[0].groundtruth for n in names}
    specs = split_specs(args.trackers)
    seeds = [int(s) for s in args.seeds.split(",")]
    # Long sequences first, so that the pool does not end on one of them.
    order = sorted(names, key=lambda n: -len(gts[n]))
    jobs = [(spec, seed, str(where[n]), n, args.jitter) for spec in specs for seed in seeds
            for n in order]
    with ProcessPoolExecutor(args.jobs) as pool:
        runs = list(progress(pool.map(_run, jobs), total=len(jobs), desc="runs"))
    summary = {}
    for spec in specs:
        s = summarise([r for r in runs if r["spec"] == spec], gts, names,
                      sparse_sequences([Path(r) for r in args.roots.split(",")]))
        summary[spec] = s
        print(f"{spec}: half 1 {s['half1']:.3f} (sd {s['half1_spread']:.3f}), half 2 "
              f"{s['half2']:.3f} (sd {s['half2_spread']:.3f}), all {s['all']:.3f}; "
              f"lost flag on IoU>=0.5 {100 * s['well_tracked_flagged_lost']:.1f} %, on IoU=0 or "
              f"absent {100 * s['off_target_flagged_lost']:.1f} %; {s['updates_per_second']:.0f} "
              "updates/s (shared cores)")
    if len(specs) > 1:
        print("per sequence: " + " ".join(f"{n}" for n in names))
        for spec in specs:
            print(f"  {spec}: " + " ".join(f"{summary[spec]['per_sequence'][n]:.2f}" for n in names))
    if args.against and len(specs) > 1:
        first = summary[specs[0]]["per_sequence"]
        for n in names:
            others = {sp: summary[sp]["per_sequence"][n] for sp in specs[1:]}
            if first[n] < 0.10 and any(v > 0.40 for v in others.values()):
                print(f"collapse: {n} {specs[0]} {first[n]:.3f}, " +
                      ", ".join(f"{k} {v:.3f}" for k, v in others.items()))
    if args.json is not None:
        args.json.write_text(json.dumps({"halves": halves(names), "summary": summary,
                                         "runs": runs}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
