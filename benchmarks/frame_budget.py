"""Where one ``update`` spends its time: a per-stage budget of each variant's frame step.

Usage::

    python benchmarks/frame_budget.py                       # generated 640x480 frames, 64-px box
    python benchmarks/frame_budget.py --otb ../shared/data/otb --sequences Coke,David
    python benchmarks/frame_budget.py --variants rcwmil,mil --json budget.json

Each stage is timed by wrapping the functions the tracker calls for it (the compiled calls of
``wmiltrack._core`` and ``wmiltrack._learn``, the tracker's integral-image step, the bag
sampler, the Gaussian pool, the colour model); whatever the wrappers do not cover is "Python glue" (argument checks, bookkeeping,
numpy slicing and the wrappers themselves, about 0.2 us per wrapped call).  For every frame
the stage times are summed; the table gives the median over frames (in us) and each stage's
share of the median ``update``.  The wrappers add a little time, so absolute figures are
slightly above those of ``fps_compare.py``; the shares are what this script is for.

Stages: integral image, search (coarse and fine grids; the colour-merged grid for
rcwmil-plus), scale search, bag sampling, projection (feature values of the bags), Gaussian
update, log ratios, selection (the last four in one call, "learning (one call)", where the
version has ``_core.learn``: the C++ benchmark splits it; with the bag sampling,
"bags and learning (one call)", where the version has ``_core.learn_at`` and the preset is
made of several parts; and the search and the bag sampling with them, "search, bags and
learning (one call)", where a paper preset's update is one ``_core.frame_step``), colour
model, the correlation filters' template and DSST, the lost state, glue.  The last row is the
share of the update that holds the GIL (everything but the compiled calls that release it):
what keeps two trackers in two threads from running twice as fast.  The same script runs on
older versions of the package (stages it does not find are reported as 0), which is how the
README's "before" table was made.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import statistics
import sys
import time
from collections import defaultdict
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any

import numpy as np

try:
    import wmiltrack  # noqa: F401
except ImportError:  # a checkout that was not installed
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))

import wmiltrack

try:
    from wmiltrack.timing import gc_paused, timed
except ImportError:  # a version older than wmiltrack.timing, measured for a before/after table
    import importlib.util

    _spec = importlib.util.spec_from_file_location(
        "wmiltrack_timing_of_checkout", Path(__file__).resolve().parents[1] / "src/wmiltrack/timing.py")
    assert _spec is not None and _spec.loader is not None
    _timing = importlib.util.module_from_spec(_spec)
    _spec.loader.exec_module(_timing)
    gc_paused, timed = _timing.gc_paused, _timing.timed

STAGES = ("integral", "search", "scale", "sampling", "projection", "gaussian update",
          "log ratios", "selection", "learning (one call)", "bags and learning (one call)",
          "search, bags and learning (one call)", "colour", "template", "DSST", "lost state",
          "glue")
# Stages that run in compiled calls with the GIL released (the others hold it all or part of
# the time: sampling and glue are Python and numpy, scale and colour mix both; MILBoost's
# selection also takes numpy's exp of its inputs first, with the GIL).
RELEASES_GIL = ("integral", "search", "projection", "gaussian update", "log ratios", "selection",
                "learning (one call)", "bags and learning (one call)",
                "search, bags and learning (one call)")
# Compiled calls of wmiltrack._core and the stage each belongs to.
CORE_STAGES = {"score_grid": "search", "search": "search", "project": "projection",
               "log_ratio": "log ratios", "learn": "learning (one call)",
               "learn_at": "bags and learning (one call)",
               "frame_step": "search, bags and learning (one call)"}


class _Clock:
    """Per-frame time of each stage; a timed call inside another counts in its own stage and
    is taken out of the outer one's."""

    def __init__(self) -> None:
        self.frame: dict[str, float] = defaultdict(float)
        self.inner: list[float] = []  # per open timed call: time of the timed calls inside it

    def wrap(self, stage: str, fn: Callable[..., Any]) -> Callable[..., Any]:
        def timed(*args: Any, **kwargs: Any) -> Any:
            self.inner.append(0.0)
            t0 = time.perf_counter()
            try:
                return fn(*args, **kwargs)
            finally:
                spent = time.perf_counter() - t0
                self.frame[stage] += spent - self.inner.pop()
                if self.inner:
                    self.inner[-1] += spent
        return timed


class _TimedModule:
    """Stands in for a compiled module: its listed functions are timed, the rest passed on."""

    def __init__(self, module: Any, clock: _Clock, stages: dict[str, str]) -> None:
        self._module = module
        self._timed = {name: clock.wrap(stage, getattr(module, name))
                       for name, stage in stages.items() if hasattr(module, name)}

    def __getattr__(self, name: str) -> Any:
        return self._timed.get(name) or getattr(self._module, name)


def _patch_optional_parts(patch: Callable[[Any, str, str], None]) -> None:
    """The parts that not every version has: the colour model, the correlation filters
    (rcwmil-cf) and the lost state."""
    try:
        from wmiltrack.engine import colour
        for name in ("integral", "learn"):
            patch(colour.ColourModel, name, "colour")
    except ImportError:  # versions without the colour model
        pass
    try:  # the correlation filters (rcwmil-cf) and the lost state
        from wmiltrack.engine import correlation, recovery
        for name in ("locate", "learn"):
            patch(correlation.CorrelationFilter, name, "template")
        patch(correlation.Location, "map", "template")
        for name in ("estimate", "learn"):
            patch(correlation.ScaleFilter, name, "DSST")
        for name in ("judge", "learn"):
            patch(recovery.Redetector, name, "lost state")
    except (ImportError, AttributeError):  # versions without them
        pass


@contextlib.contextmanager
def instrumented(clock: _Clock) -> Iterator[None]:
    """Wrap the stage functions of the installed wmiltrack for the duration of the block."""
    from wmiltrack.engine import classifier, sampling, tracker

    patches: list[tuple[Any, str, Any]] = []

    def patch(owner: Any, name: str, stage: str) -> None:
        if hasattr(owner, name):
            original = getattr(owner, name)
            patches.append((owner, name, original))
            setattr(owner, name, clock.wrap(stage, original))

    patches.append((tracker, "_core", tracker._core))
    tracker._core = _TimedModule(tracker._core, clock, CORE_STAGES)  # type: ignore[assignment]
    try:  # the engine as parts: the core is called from the appearance model and the requests
        from wmiltrack.engine import appearance, requests, scale
    except ImportError:  # versions with one Tracker class
        pass
    else:
        for module in (appearance, requests):
            patches.append((module, "_core", module._core))
            module._core = _TimedModule(module._core, clock, CORE_STAGES)  # type: ignore[assignment]
        patch(appearance.HaarAppearance, "compute_integral", "integral")
        patch(appearance, "milboost_select", "selection")
        patch(scale.HaarScale, "search", "scale")
    patch(tracker.Tracker, "_compute_integral", "integral")
    patch(tracker, "wmil_select", "selection")
    patch(tracker, "milboost_select", "selection")
    patch(sampling.BagSampler, "positives", "sampling")
    patch(sampling.BagSampler, "negatives", "sampling")
    patch(sampling.BagSampler, "weights", "sampling")
    patch(sampling.BagSampler, "draw", "sampling")
    patch(tracker, "instance_weights", "sampling")  # older versions
    patch(classifier.GaussianPool, "update", "gaussian update")
    patch(tracker.Tracker, "_scale_by_ratio", "scale")
    patch(tracker.Tracker, "_scale_by_likelihood", "scale")
    patch(tracker.Tracker, "_colour_stage", "search")
    _patch_optional_parts(patch)
    try:
        yield
    finally:
        for owner, name, original in reversed(patches):
            setattr(owner, name, original)


def budget(variant: str, frames: Sequence[np.ndarray], box: Any, repeats: int) -> dict[str, Any]:
    """Median per-frame time of each stage (us) and of the whole update, over all runs."""
    clock = _Clock()
    per_frame: list[dict[str, float]] = []
    with instrumented(clock), gc_paused():
        for _ in range(repeats):
            t = wmiltrack.Tracker(variant, seed=0)
            t.init(frames[0], box)
            for f in frames[1:]:
                clock.frame = defaultdict(float)
                _, total = timed(t.update, f)
                row = dict(clock.frame)
                row["glue"] = total - sum(row.values())
                row["total"] = total
                per_frame.append(row)
    med = {s: statistics.median(r.get(s, 0.0) for r in per_frame) * 1e6 for s in (*STAGES, "total")}
    return {"variant": variant, "frames": len(per_frame), "us": med}


def _print(name: str, results: list[dict[str, Any]]) -> None:
    print(f"\n### {name}\n")
    head = "| stage | " + " | ".join(r["variant"] for r in results) + " |"
    print(head)
    print("|---|" + "---|" * len(results))
    for s in STAGES:
        cells = []
        for r in results:
            us, total = r["us"][s], r["us"]["total"]
            cells.append("-" if us == 0 else f"{us:.0f} ({100 * us / total:.0f} %)")
        print(f"| {s} | " + " | ".join(cells) + " |")
    print("| **update (median)** | " + " | ".join(f"**{r['us']['total']:.0f}**" for r in results) + " |")
    held = []
    for r in results:
        free = sum(r["us"][s] for s in RELEASES_GIL)
        held.append(f"{100 * max(r['us']['total'] - free, 0.0) / r['us']['total']:.0f} %")
    print("| holds the GIL (update less the GIL-free stages) | " + " | ".join(held) + " |")


def main(argv: Sequence[str] | None = None) -> int:
    """Run the budget; return the exit status."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0] if __doc__ else None)
    ap.add_argument("--variants", default="rcwmil,ct,fct,mil,wmil,osil,rcwmil-plus")
    ap.add_argument("--otb", default=None,
                    help="OTB folder (default: $WMILTRACK_OTB; without either, generated frames only)")
    ap.add_argument("--sequences", default="Coke,David",
                    help="shared sequences to time (with --otb), comma-separated")
    ap.add_argument("--frames", type=int, default=100, help="frames per run")
    ap.add_argument("--repeats", type=int, default=2, help="runs per variant and sequence")
    ap.add_argument("--size", default="640x480", help="generated frame size WxH")
    ap.add_argument("--box", type=int, default=64, help="generated target size (px)")
    ap.add_argument("--json", default=None, help="also write the figures to this file")
    args = ap.parse_args(argv)

    from wmiltrack.data.synthetic import make_sequence
    from wmiltrack.eval.report import cpu_model

    variants = [v.strip() for v in args.variants.split(",") if v.strip()]
    known = set(wmiltrack.variants())
    variants = [v for v in variants if v in known]
    from wmiltrack import _core

    simd = getattr(_core, "simd_path", None)
    kernels = simd() if simd is not None else "none (this version predates them)"
    print(f"# {cpu_model()}; wmiltrack {getattr(wmiltrack, '__version__', '?')} from "
          f"{Path(wmiltrack.__file__).parent} (vectorised kernels: {kernels}); median us per frame over {args.frames - 1} updates "
          f"x {args.repeats} runs; share of the median update in brackets")

    runs: list[tuple[str, list[np.ndarray], Any]] = []
    w, h = (int(v) for v in args.size.lower().split("x"))
    seq = make_sequence(args.frames, size=(h, w), target_size=(args.box, args.box), seed=1)
    assert seq.groundtruth is not None
    runs.append((f"generated {w}x{h}, {args.box}-px box", seq.load(), seq.groundtruth[0]))
    otb = args.otb or os.environ.get("WMILTRACK_OTB")
    if otb:
        from wmiltrack.data.sequences import list_otb_sequences, load_otb_sequence
        wanted = {s.strip() for s in args.sequences.split(",")}
        for path in list_otb_sequences(otb):
            s = load_otb_sequence(path)
            if s.name in wanted and s.groundtruth is not None:
                frames = s.load()[: args.frames]
                runs.append((f"{s.name} (shared, {frames[0].shape[1]}x{frames[0].shape[0]}, box "
                             f"{int(s.groundtruth[0][2])}x{int(s.groundtruth[0][3])})",
                             frames, s.groundtruth[0]))

    report: dict[str, Any] = {}
    for name, frames, box in runs:
        results = [budget(v, frames, box, args.repeats) for v in variants]
        _print(name, results)
        report[name] = results
    if args.json:
        Path(args.json).write_text(json.dumps(report, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
