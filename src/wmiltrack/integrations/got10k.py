"""wmiltrack in the GOT-10k toolkit (``pip install got10k``; see the README's ``integrations``).

:class:`GOT10kTracker` is a ``got10k.trackers.Tracker``: the toolkit hands it RGB PIL images
and ``(x, y, w, h)`` boxes, so every experiment of the toolkit runs wmiltrack unchanged::

    from got10k.experiments import ExperimentOTB
    from wmiltrack.integrations.got10k import GOT10kTracker

    e = ExperimentOTB("data/OTB", version=2015)
    e.run(GOT10kTracker("rcwmil"))
    e.report(["wmiltrack-rcwmil"])

``ExperimentOTB`` downloads the 100 OTB sequences unless they are all there;
:func:`local_otb_experiment` builds one over the sequences you have, with no download. From
the command line::

    python -m wmiltrack.integrations.got10k --otb ../shared/data/otb --sequences Crossing,Couple
"""

from __future__ import annotations

import argparse
import contextlib
import io
import os
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import cv2
import numpy as np

try:
    from got10k.datasets import OTB
    from got10k.experiments import ExperimentOTB
    from got10k.trackers import Tracker as _Got10kTracker
except ImportError as exc:  # pragma: no cover - depends on the environment
    raise ImportError(
        "wmiltrack.integrations.got10k needs the GOT-10k toolkit: pip install --no-deps got10k "
        "six shapely wget (see the README, section 'Ecosystem')"
    ) from exc

from ..engine.tracker import Tracker

__all__ = ["GOT10kTracker", "local_otb_experiment", "main"]


class GOT10kTracker(_Got10kTracker):  # type: ignore[misc]  # got10k is untyped
    """A wmiltrack variant as a ``got10k.trackers.Tracker``.

    Parameters
    ----------
    variant : str
        wmiltrack variant (``"rcwmil"``, ``"ct"``, ...).
    seed : int
        Random seed; the tracker is deterministic for a given seed.
    name : str, optional
        Name under which the toolkit records results; default ``"wmiltrack-<variant>"``.
    **overrides
        Parameter overrides, as for :class:`wmiltrack.Tracker`.
    """

    def __init__(self, variant: str = "rcwmil", seed: int = 0, name: str | None = None,
                 **overrides: Any) -> None:
        super().__init__(name=name or f"wmiltrack-{variant}", is_deterministic=True)
        self.tracker = Tracker(variant, seed=seed, **overrides)

    @staticmethod
    def _bgr(image: Any) -> np.ndarray:
        """The toolkit's RGB PIL image (or an array) as a BGR/gray uint8 array."""
        arr = np.asarray(image)
        if arr.ndim == 3 and arr.shape[2] == 3:
            return cv2.cvtColor(arr, cv2.COLOR_RGB2BGR)
        return arr

    def init(self, image: Any, box: Any) -> None:
        """Start tracking ``box = (x, y, w, h)`` in ``image`` (RGB PIL image).

        Parameters
        ----------
        image : PIL.Image.Image or numpy.ndarray
            The first frame, RGB.
        box : sequence of 4 numbers
            ``(x, y, w, h)`` of the target.
        """
        self.tracker.init(self._bgr(image), [float(v) for v in box])

    def update(self, image: Any) -> np.ndarray:
        """Track into ``image`` and return the box as the toolkit expects.

        Parameters
        ----------
        image : PIL.Image.Image or numpy.ndarray
            The next frame, RGB.

        Returns
        -------
        numpy.ndarray
            ``[x, y, w, h]`` (float64).
        """
        return np.array(self.tracker.update(self._bgr(image)).box, dtype=np.float64)


def local_otb_experiment(root: str | os.PathLike[str], sequences: Sequence[str] | None = None, *,
                         result_dir: str | os.PathLike[str] = "results",
                         report_dir: str | os.PathLike[str] = "reports",
                         version: int | str = 2015) -> Any:
    """An ``ExperimentOTB`` over the OTB sequences found in ``root``, without downloading.

    Parameters
    ----------
    root : path
        Folder of OTB sequence folders (``<Seq>/img/*.jpg`` + ``groundtruth_rect.txt``).
    sequences : sequence of str, optional
        Names to keep (default: every sequence of ``version`` found in ``root``). The
        toolkit cuts ``David`` to images 300-770 of the full OTB folder, so pass only
        folders laid out as OTB publishes them.
    result_dir, report_dir : path
        Where the toolkit writes boxes/times and reports/plots.
    version : int or str
        OTB version whose sequence list applies (2013, 2015, ``"tb50"``, ``"tb100"``).

    Returns
    -------
    got10k.experiments.ExperimentOTB
        Ready for ``run(tracker)`` and ``report([names])``.
    """
    with contextlib.redirect_stdout(io.StringIO()):  # one warning per absent sequence
        dataset = OTB(os.fspath(root), version, download=False)
    if sequences is not None:
        missing = sorted(set(sequences) - set(dataset.seq_names))
        if missing:
            raise ValueError(f"sequences not found in {root} (or not in OTB {version}): {', '.join(missing)}")
        keep = [i for i, n in enumerate(dataset.seq_names) if n in set(sequences)]
        dataset.anno_files = [dataset.anno_files[i] for i in keep]
        dataset.seq_dirs = [dataset.seq_dirs[i] for i in keep]
        dataset.seq_names = [dataset.seq_names[i] for i in keep]
    experiment = ExperimentOTB.__new__(ExperimentOTB)
    experiment.dataset = dataset
    experiment.result_dir = os.path.join(os.fspath(result_dir), f"OTB{version}")
    experiment.report_dir = os.path.join(os.fspath(report_dir), f"OTB{version}")
    experiment.nbins_iou = 21
    experiment.nbins_ce = 51
    return experiment


def main(argv: Sequence[str] | None = None) -> int:
    """Run the GOT-10k toolkit's OTB experiment on local sequences and print its report.

    Parameters
    ----------
    argv : sequence of str, optional
        Command-line arguments (default ``sys.argv[1:]``); see ``--help``.

    Returns
    -------
    int
        Exit status.
    """
    ap = argparse.ArgumentParser(
        prog="python -m wmiltrack.integrations.got10k",
        description="Run wmiltrack through the GOT-10k toolkit's ExperimentOTB on local OTB "
        "sequences (no download) and write its report and success/precision plots.")
    ap.add_argument("--otb", type=Path, default=Path("../shared/data/otb"),
                    help="folder of OTB sequences (default ../shared/data/otb)")
    ap.add_argument("--sequences", default="Crossing,Couple",
                    help="comma-separated sequence names (default Crossing,Couple)")
    ap.add_argument("--trackers", default="rcwmil", help="comma-separated variants (default rcwmil)")
    ap.add_argument("--out", type=Path, default=Path("results/got10k"),
                    help="folder for the toolkit's results/ and reports/ (default results/got10k)")
    args = ap.parse_args(argv)
    import matplotlib

    matplotlib.use("Agg")
    e = local_otb_experiment(args.otb, [s.strip() for s in args.sequences.split(",") if s.strip()],
                             result_dir=args.out / "results", report_dir=args.out / "reports")
    names = []
    for variant in args.trackers.split(","):
        t = GOT10kTracker(variant.strip())
        e.run(t)
        names.append(t.name)
    perf = e.report(names)
    for name in names:
        o = perf[name]["overall"]
        print(f"{name}: success score {o['success_score']:.3f}, precision score "
              f"{o['precision_score']:.3f}, success rate {o['success_rate']:.3f}, {o['speed_fps']:.0f} fps")
    print(f"report and plots: {Path(e.report_dir) / names[0]}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
