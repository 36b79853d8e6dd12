"""Run the GOT-10k toolkit's own experiment on wmiltrack trackers.

    pip install ".[integrations]"                 # the got10k toolkit (and six), matplotlib
    python examples/got10k_experiment.py          # two generated sequences, no download
    python examples/got10k_experiment.py --root /data/GOT-10k --trackers rcwmil,rcwmil-plus

``wmiltrack.integrations.got10k.GOT10kTracker`` is a ``got10k.trackers.Tracker``, so the
toolkit's experiments (``ExperimentGOT10k``, ``ExperimentOTB``, ...) run it unchanged. Without
``--root`` the script writes two generated sequences (wmiltrack.data.synthetic) in the GOT-10k
``val`` layout first: ``val/list.txt`` and, per sequence, ``00000001.jpg, ...``,
``groundtruth.txt``, ``cover.label``, ``absence.label``, ``cut_by_image.label`` and
``meta_info.ini``. The toolkit then runs each tracker, writes its boxes under ``--out``/results
and its report (performance.json, success plot) under ``--out``/reports; the script prints the
toolkit's average overlap (AO) and success rate next to wmiltrack's own GOT-10k scoring of the
same boxes (wmiltrack.eval.got10k_metrics), which should agree.
"""

from __future__ import annotations

import argparse
import contextlib
import io
from pathlib import Path

import cv2
import matplotlib
import numpy as np

matplotlib.use("Agg")  # the toolkit's report draws a plot; no window needed

from got10k.experiments import ExperimentGOT10k  # noqa: E402

from wmiltrack.data.boxes import write_boxes  # noqa: E402
from wmiltrack.data.synthetic import make_preset  # noqa: E402
from wmiltrack.eval.got10k_metrics import got10k_aggregate, got10k_metrics  # noqa: E402
from wmiltrack.integrations.got10k import GOT10kTracker  # noqa: E402


def write_got10k_val(root: Path) -> Path:
    """Write two generated 60-frame sequences as a GOT-10k ``val`` split under ``root``."""
    names = []
    for k, scenario in enumerate(("occlusion", "clutter"), start=1):
        seq = make_preset(scenario, seed=k, n_frames=60)
        frames = seq.load()
        assert seq.groundtruth is not None
        name = f"GOT-10k_Val_{k:06d}"
        folder = root / "val" / name
        folder.mkdir(parents=True, exist_ok=True)
        for i, frame in enumerate(frames, start=1):
            if not cv2.imwrite(str(folder / f"{i:08d}.jpg"), frame):
                raise SystemExit(f"cannot write images under {folder}")
        write_boxes(folder / "groundtruth.txt", seq.groundtruth)
        n = len(frames)
        (folder / "absence.label").write_text("0\n" * n)       # the target is always there
        (folder / "cover.label").write_text("8\n" * n)         # 8: fully visible
        (folder / "cut_by_image.label").write_text("0\n" * n)
        h, w = frames[0].shape[:2]
        (folder / "meta_info.ini").write_text(
            f"[METAINFO]\nobject_class: generated target\nresolution: ({w}, {h})\n")
        names.append(name)
    (root / "val" / "list.txt").write_text("\n".join(names) + "\n")
    return root


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--root", type=Path, help="GOT-10k folder with val/ (default: generated)")
    parser.add_argument("--trackers", default="rcwmil,rcwmil-plus", help="comma-separated presets")
    parser.add_argument("--out", type=Path, default=Path("results/example-got10k"), help="output folder")
    args = parser.parse_args()

    # the trackers first: one that cannot start (no model files) stops before anything is written
    trackers = [GOT10kTracker(name, seed=0) for name in args.trackers.split(",")]
    root = args.root or write_got10k_val(args.out / "GOT-10k")
    experiment = ExperimentGOT10k(str(root), subset="val", result_dir=str(args.out / "results"),
                                  report_dir=str(args.out / "reports"))
    with contextlib.redirect_stdout(io.StringIO()):   # the toolkit prints a line per sequence
        for tracker in trackers:
            experiment.run(tracker)
        performance = experiment.report([t.name for t in trackers])

    dataset = experiment.dataset
    dataset.return_meta = True
    for tracker in trackers:
        ours = []
        for s, name in enumerate(dataset.seq_names):
            _, gt, meta = dataset[s]
            boxes = np.loadtxt(Path(experiment.result_dir) / tracker.name / name / f"{name}_001.txt",
                               delimiter=",")
            w, h = (float(v) for v in meta["resolution"].strip("()").split(","))
            ours.append(got10k_metrics(boxes, gt, visible=meta["cover"] > 0, bound=(w, h)))
        mine = got10k_aggregate(ours).pooled
        toolkit = performance[tracker.name]["overall"]
        print(f"{tracker.name}: toolkit AO {toolkit['ao']:.3f}, SR@0.5 {toolkit['sr']:.3f}; "
              f"wmiltrack's scoring AO {mine.ao:.3f}, SR@0.5 {mine.sr50:.3f}")
    print(f"boxes in {experiment.result_dir}, report and plot in {experiment.report_dir}")


if __name__ == "__main__":
    main()
