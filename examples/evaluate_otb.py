"""Evaluate trackers on an OTB-layout folder: a table, success and precision plots, box files.

    python examples/evaluate_otb.py                   # three generated sequences, no download
    python examples/evaluate_otb.py /data/otb --trackers rcwmil,rcwmil-plus,opencv:MIL

An OTB-layout folder holds one folder per sequence, each with ``img/0001.jpg, ...`` and
``groundtruth_rect.txt`` (one ``x,y,w,h`` line per frame). Without a folder, the script writes
three generated sequences (wmiltrack.data.synthetic) in that layout first. The evaluation is
the one behind ``wmiltrack eval``: it writes ``eval_ope.md`` (the table), ``eval_ope.json``,
``success_ope.png``, ``precision_ope.png`` and ``boxes/<tracker>/<sequence>.txt``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import cv2

from wmiltrack.data.boxes import write_boxes
from wmiltrack.data.synthetic import make_preset
from wmiltrack.eval.pipeline import EvalConfig, run_eval


def write_otb_folder(root: Path) -> Path:
    """Write three generated 60-frame sequences in the OTB layout under ``root``."""
    for scenario in ("occlusion", "illumination", "clutter"):
        seq = make_preset(scenario, seed=0, n_frames=60)
        folder = root / scenario.capitalize()
        (folder / "img").mkdir(parents=True, exist_ok=True)
        for i, frame in enumerate(seq.load(), start=1):
            if not cv2.imwrite(str(folder / "img" / f"{i:04d}.jpg"), frame):
                raise SystemExit(f"cannot write images under {folder}")
        assert seq.groundtruth is not None
        write_boxes(folder / "groundtruth_rect.txt", seq.groundtruth)
    return root


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("dataset", nargs="?", type=Path, help="OTB-layout folder (default: generated)")
    parser.add_argument("--trackers", default="rcwmil,rcwmil-plus,ct,opencv:MIL",
                        help="comma-separated tracker names (wmiltrack presets, opencv:NAME)")
    parser.add_argument("--out", type=Path, default=Path("results/example-eval"), help="output folder")
    args = parser.parse_args()

    dataset = args.dataset or write_otb_folder(args.out / "dataset")
    report = run_eval(EvalConfig(dataset, args.out, trackers=args.trackers.split(","),
                                 show_progress=False))

    print((args.out / "eval_ope.md").read_text())
    for kind, path in sorted(report["files"].items()):
        print(f"{kind}: {path}")


if __name__ == "__main__":
    main()
