"""Summarise a VOT toolkit analysis (``vot analysis --name NAME`` -> analysis/NAME.json).

    python scripts/vot/summarize.py WORKSPACE/analysis/summary.json [--plot eao.png]

Prints one row per tracker: supervised (reset-based) accuracy, failures, EAO, and the
unsupervised (one-pass) average overlap, for the stack in scripts/vot/stack.yaml; with
``--plot`` draws the expected-average-overlap curves with a legend.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("analysis", type=Path)
    ap.add_argument("--plot", type=Path)
    args = ap.parse_args()
    d = json.loads(args.analysis.read_text())
    names = list(d["trackers"])
    ar, eao, curve = d["results"]["baseline"]["results"]
    ao = d["results"]["unsupervised"]["results"][0]
    seqs = ", ".join(f"{k} ({v['length']})" for k, v in d["sequences"].items())
    print(f"VOT toolkit {d['toolkit']}, sequences: {seqs}")
    print(f"{'tracker':<18} {'accuracy':>9} {'failures':>9} {'EAO':>7} {'AO (one-pass)':>14}")
    for i, n in enumerate(names):
        print(f"{n:<18} {ar[i][0]:9.3f} {ar[i][1]:9.1f} {eao[i][0]:7.3f} {ao[i][0]:14.3f}")
    if args.plot:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(5.5, 3.2), dpi=100)
        for i, n in enumerate(names):
            ax.plot(curve[i][0], label=f"{n} (EAO {eao[i][0]:.3f})")
        ax.set_xlabel("sequence length (frames)")
        ax.set_ylabel("expected average overlap")
        ax.set_ylim(0, 1)
        ax.set_title("VOT toolkit 0.7.4, supervised experiment", fontsize=10)
        ax.legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(args.plot)
    return 0


if __name__ == "__main__":
    sys.exit(main())
