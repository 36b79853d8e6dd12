"""A TraX server, so that the VOT toolkit can run wmiltrack: ``python -m wmiltrack.vot``.

The VOT toolkit starts this module as a tracker process and talks TraX with it (``vot-trax``
package). A ``trackers.ini`` entry for a VOT workspace::

    [wmiltrack_rcwmil]
    label = wmiltrack_rcwmil
    protocol = traxpython
    command = wmiltrack.vot
    python = /path/to/venv/bin/python
    env_WMILTRACK_VARIANT = rcwmil

With ``protocol = traxpython`` and a bare module name the toolkit runs
``<python> -m wmiltrack.vot``; ``python`` names an interpreter that has wmiltrack and
vot-trax installed (it may differ from the one running the toolkit).

Options (command line or environment): the variant (``--variant`` / ``WMILTRACK_VARIANT``,
default ``rcwmil``) and the seed (``--seed`` / ``WMILTRACK_SEED``). The server accepts
rectangle and polygon regions (a polygon is replaced by its axis-aligned bounding box),
reads image paths, answers with rectangles and reports ``confidence`` = the tracker's score.
Nothing is printed on standard output, which may carry the protocol.
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Sequence
from typing import Any

import cv2
import numpy as np

from ..engine.tracker import Tracker

__all__ = ["main", "region_to_box", "serve"]


def region_to_box(region: Any) -> tuple[float, float, float, float]:
    """The ``(x, y, w, h)`` bounding box of a TraX region.

    Parameters
    ----------
    region : trax.Rectangle or trax.Polygon
        Region received from the client (a polygon gives its axis-aligned bounding box).

    Returns
    -------
    tuple of 4 float
        ``(x, y, w, h)``.
    """
    import trax

    if isinstance(region, trax.Polygon):
        pts = np.array([region[i] for i in range(region.size())], dtype=np.float64)
        x0, y0 = pts.min(axis=0)
        x1, y1 = pts.max(axis=0)
        return float(x0), float(y0), float(x1 - x0), float(y1 - y0)
    x, y, w, h = region.bounds()
    return float(x), float(y), float(w), float(h)


def _read(image: Any) -> np.ndarray:
    path = image.path()
    frame = cv2.imread(path, cv2.IMREAD_COLOR)
    if frame is None:
        raise FileNotFoundError(f"cannot read image {path}")
    return frame


def serve(variant: str = "rcwmil", seed: int = 0, **overrides: Any) -> None:
    """Serve one TraX session (until the client quits) with a wmiltrack tracker.

    Parameters
    ----------
    variant : str
        wmiltrack variant.
    seed : int
        Random seed.
    **overrides
        Parameter overrides, as for :class:`wmiltrack.Tracker`.
    """
    import trax

    tracker = Tracker(variant, seed=seed, **overrides)
    with trax.Server([trax.Region.RECTANGLE, trax.Region.POLYGON], [trax.Image.PATH],
                     tracker_name=f"wmiltrack-{variant}", tracker_family="wmiltrack") as server:
        while True:
            request = server.wait()
            if request.type == trax.TraxStatus.QUIT:
                break
            frame = _read(request.image["color"])
            if request.type == trax.TraxStatus.INITIALIZE:
                region = request.objects[0][0]
                tracker.init(frame, region_to_box(region))
                x, y, w, h = tracker.box
                score = 1.0
            else:
                r = tracker.update(frame)
                (x, y, w, h), score = r.box, r.score
            server.status([(trax.Rectangle.create(x, y, w, h), {"confidence": score})],
                          {"confidence": score})


def main(argv: Sequence[str] | None = None) -> int:
    """Command line of ``python -m wmiltrack.vot``.

    Parameters
    ----------
    argv : sequence of str, optional
        Arguments (default ``sys.argv[1:]``); see ``--help``.

    Returns
    -------
    int
        Exit status.
    """
    ap = argparse.ArgumentParser(
        prog="python -m wmiltrack.vot",
        description="Serve a wmiltrack tracker over TraX for the VOT toolkit (started by the "
        "toolkit through trackers.ini; see the README's 'Ecosystem' section).")
    ap.add_argument("--variant", default=os.environ.get("WMILTRACK_VARIANT", "rcwmil"),
                    help="variant (default $WMILTRACK_VARIANT or rcwmil)")
    ap.add_argument("--seed", type=int, default=int(os.environ.get("WMILTRACK_SEED", "0")),
                    help="random seed (default $WMILTRACK_SEED or 0)")
    args = ap.parse_args(argv)
    try:
        import trax  # noqa: F401
    except ImportError:
        print("wmiltrack.vot needs the vot-trax package: pip install vot-trax", file=sys.stderr)
        return 2
    serve(args.variant, args.seed)
    return 0


if __name__ == "__main__":
    sys.exit(main())
