"""Runs for scripts/simd_paths.sh: the trackers' boxes and scores on each code path of a build.

``run OUT`` tracks 40 frames of a generated sequence with every paper preset and rcwmil-plus
and writes the boxes and scores (as exact float hex) per code path the build offers: "avx2" and
"sse2" (forced portable) for a SIMD build, "scalar" for a WMILTRACK_NO_SIMD build; with them,
under "fhog", digests of the correlation filters' features (gray patches, fHOG, scale
samples) of a few of the frames, which no preset computes. With
WMILTRACK_SANITIZED_SITE set it imports the package copied there (the scalar build), never
the installed one. ``compare A B`` fails unless every path of both files gives the same
values, and unless the three paths are all present.
"""

from __future__ import annotations

import hashlib
import json
import os
import sys

VARIANTS = ("rcwmil", "ct", "fct", "mil", "wmil", "osil", "rcwmil-plus", "rcwmil-cf")
FHOG = "fhog"  # the key of the correlation-filter features' digests


def _import_site() -> None:
    site = os.environ.get("WMILTRACK_SANITIZED_SITE")
    if site:
        sys.meta_path = [f for f in sys.meta_path if "editable" not in type(f).__module__.lower()]
        sys.path.insert(0, site)


def _track(variant: str, frames: list, first: tuple) -> list[list[str]]:
    import wmiltrack

    tracker = wmiltrack.Tracker(variant, seed=0)
    tracker.init(frames[0], first)
    rows = []
    for f in frames[1:]:
        r = tracker.update(f)
        rows.append([float(v).hex() for v in r.box] + [float(r.score).hex()])
    return rows


def _fhog_digests(frames: list) -> list[str]:
    """sha256 of every feature array the correlation filters' kernels give on a few frames,
    regions inside and leaving the frame, shrunk (also by 4 and more, read on a lattice) and
    enlarged, output sizes not whole blocks."""
    from wmiltrack import _core

    digests = []
    for frame in frames[::10]:
        h, w = frame.shape[:2]
        for centre, size, out_size in [((w / 2, h / 2), (0.6 * w, 0.6 * h), (160, 160)),
                                       ((w / 3 + 0.4, h / 2 - 0.3), (37.0, 29.0), (61, 47)),
                                       ((3.0, h - 2.0), (1.5 * w, h), (96, 66)),
                                       # shrunk 4x and more: the tent on every n-th pixel
                                       ((w / 2 + 0.7, h / 2 - 0.2), (0.9 * w, 0.9 * h), (24, 18))]:
            for a in (_core.cf_gray_patch(frame, centre, size, out_size),
                      _core.fhog_region(frame, centre, size, out_size, 4),
                      _core.fhog_region(frame, centre, size, out_size, 3),
                      _core.scale_samples(frame, centre, size, [0.95, 1.0, 1.05], (64, 48), 4)):
                digests.append(hashlib.sha256(a.tobytes()).hexdigest())
    return digests


def run(out: str) -> None:
    _import_site()
    import wmiltrack
    from wmiltrack import _core
    from wmiltrack.data.synthetic import make_preset

    site = os.environ.get("WMILTRACK_SANITIZED_SITE")
    if site and not os.path.realpath(wmiltrack._core.__file__).startswith(os.path.realpath(site)):
        sys.exit(f"imported {wmiltrack._core.__file__}, not the copy in {site}")
    seq = make_preset("all", seed=3, n_frames=40)
    frames = seq.load()
    assert seq.groundtruth is not None
    first = tuple(float(v) for v in seq.groundtruth[0])
    paths = ["avx2", "sse2"] if _core.simd_path() == "avx2" else [_core.simd_path()]
    result = {}
    for path in paths:
        _core.set_simd_portable(path == "sse2")
        try:
            if _core.simd_path() != path:
                sys.exit(f"asked for the {path} path, the core runs {_core.simd_path()}")
            result[path] = {v: _track(v, frames, first) for v in VARIANTS}
            result[path][FHOG] = _fhog_digests(frames)
        finally:
            _core.set_simd_portable(False)
    with open(out, "w") as fh:
        json.dump(result, fh)
    print(f"{out}: paths {', '.join(paths)}, {len(VARIANTS)} variants x {len(frames) - 1} frames,"
          f" {len(result[paths[0]][FHOG])} correlation-filter feature arrays")


def compare(*files: str) -> None:
    runs: dict[str, dict] = {}
    for name in files:
        with open(name) as fh:
            runs.update(json.load(fh))
    missing = {"avx2", "sse2", "scalar"} - set(runs)
    if missing:
        sys.exit(f"paths missing from the runs: {', '.join(sorted(missing))}")
    ref = runs["scalar"]
    keys = (*VARIANTS, FHOG)
    bad = [(path, v) for path, r in runs.items() for v in keys if r[v] != ref[v]]
    if bad:
        sys.exit("paths disagree: " + ", ".join(f"{p}/{v}" for p, v in bad))
    print(f"avx2, sse2 and scalar paths agree bit for bit on {', '.join(VARIANTS)} and the"
          " correlation filters' features (gray patches, fHOG, scale samples)")


if __name__ == "__main__":
    if len(sys.argv) == 3 and sys.argv[1] == "run":
        run(sys.argv[2])
    elif len(sys.argv) >= 3 and sys.argv[1] == "compare":
        compare(*sys.argv[2:])
    else:
        sys.exit("usage: simd_paths_check.py run OUT | compare A.json B.json")
