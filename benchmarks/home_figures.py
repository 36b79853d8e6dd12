"""The home page's figures from one run on the development sequences.

The accuracy-speed figure of the documentation's home page, and the success and precision plots
beside it on the performance page, must come from one run, on the sequences the development
figures are measured on: this runs ``wmiltrack eval`` once on every OTB-layout sequence under
the roots given, with every tracker of the README's table, and leaves in ``OUT/eval`` the
table, the JSON and the three plots of that run (``accuracy_speed.png``, ``success_ope.png``,
``precision_ope.png``)::

    python benchmarks/home_figures.py --roots ../shared/data/otb,$POOL_DIR --out results/home

``eval`` reads one dataset folder, so the sequences of the roots are linked into
``OUT/dataset`` first (symbolic links, nothing copied; a name found under two roots is an
error). Each tracker has one colour (and marker) in all three plots, fixed by its place in
``--trackers`` (default: the README table's order), as in every ``eval`` run.

Model files: rcwmil-nano and ``nanotrack:v3`` find NanoTrack v3's files in the models folder
(``wmiltrack models fetch nanotrack-v3``), ``nanotrack:v2`` v2's (``... fetch nanotrack-v2``).
OpenCV's TrackerNano runs v2's files; give them in its own spec
(``opencv:Nano:backbone=FILE:neckhead=FILE`` in ``--trackers``), not through
``WMILTRACK_NANO_BACKBONE``/``WMILTRACK_NANO_HEAD``, which rcwmil-nano would read too. CSRT, KCF
and MOSSE need the contrib wheel; a tracker that is not installed is skipped with a note in
the table. Copy the three plots into ``docs/images`` together and caption them with the run's
date, command and code (printed at the end).
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import time
from pathlib import Path

from wmiltrack.data.sequences import list_otb_sequences
from wmiltrack.eval.pipeline import EvalConfig, run_eval

#: The README table's trackers, in its order (which fixes their colours in the plots).
TRACKERS = ("rcwmil-nano,nanotrack:v3,nanotrack:v2,rcwmil-cf,rcwmil-plus,rcwmil,mil,fct,osil,wmil,"
            "ct,opencv:Nano,opencv:CSRT,opencv:MIL,opencv:KCF,opencv:MOSSE")


def link_sequences(roots: list[Path], folder: Path) -> list[str]:
    """Link every OTB sequence folder of ``roots`` into ``folder``; their names.

    Raises
    ------
    SystemExit
        A name found under two roots, or an existing entry of ``folder`` that is not the link
        this run would make (nothing of the user's is replaced).
    """
    found: dict[str, Path] = {}
    for root in roots:
        for seq in list_otb_sequences(root):
            if seq.name in found:
                raise SystemExit(f"sequence {seq.name} is under both {found[seq.name]} and {root}")
            found[seq.name] = seq.resolve()
    folder.mkdir(parents=True, exist_ok=True)
    for name, target in found.items():
        link = folder / name
        if link.is_symlink() and link.resolve() == target:
            continue
        if link.exists() or link.is_symlink():
            raise SystemExit(f"{link} exists and is not a link to {target}; give another --out")
        link.symlink_to(target, target_is_directory=True)
    return sorted(found)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--roots", required=True,
                    help="comma-separated folders of OTB-layout sequences (the development set)")
    ap.add_argument("--out", type=Path, required=True, help="folder for the links and the run")
    ap.add_argument("--trackers", default=TRACKERS,
                    help=f"in the order that fixes their colours (default: {TRACKERS})")
    ap.add_argument("--repeats", type=int, default=3, help="seeds 0.. (default 3)")
    ap.add_argument("-j", "--jobs", type=int, default=2, help="parallel sequences (default 2)")
    args = ap.parse_args(argv)
    roots = [Path(r) for r in args.roots.split(",") if r]
    names = link_sequences(roots, args.out / "dataset")
    print(f"{len(names)} sequences linked into {args.out / 'dataset'}", file=sys.stderr)
    start = time.strftime("%Y-%m-%d %H:%M", time.gmtime())
    doc = run_eval(EvalConfig(args.out / "dataset", args.out / "eval",
                              trackers=args.trackers.split(","), repeats=args.repeats,
                              jobs=args.jobs))
    end = time.strftime("%H:%M", time.gmtime())
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                            cwd=Path(__file__).parent, check=False).stdout.strip() or "unknown"
    print(Path(doc["files"]["table"]).read_text(encoding="utf-8"))
    print(f"run {start}-{end} UTC, code of {commit}, {len(names)} sequences, seeds "
          f"0-{args.repeats - 1}, -j {args.jobs}; plots: "
          + ", ".join(doc["files"][k] for k in ("accuracy_speed_plot", "success_plot", "precision_plot")
                      if k in doc["files"]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
