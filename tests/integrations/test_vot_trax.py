"""``python -m wmiltrack.vot`` speaks TraX: a trax.Client drives it as the VOT toolkit does."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import import_extra

pytestmark = pytest.mark.extras("trax")
trax = import_extra("trax")

from trax.client import Client  # noqa: E402

import wmiltrack  # noqa: E402
from wmiltrack.data.sequences import load_otb_sequence  # noqa: E402
from wmiltrack.vot import region_to_box  # noqa: E402


def _serve(tmp_path: Path, *args: str) -> subprocess.Popen[bytes]:
    env = dict(os.environ, WMILTRACK_VARIANT="ct")
    return subprocess.Popen([sys.executable, "-m", "wmiltrack.vot", *args], stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, env=env, cwd=tmp_path)


@pytest.mark.parametrize(("polygon", "variant"),
                         [(False, "rcwmil"), (True, "rcwmil"), (False, "rcwmil-plus")])
def test_trax_session_matches_direct_tracking(otb_root: Path, tmp_path: Path, polygon: bool,
                                              variant: str) -> None:
    seq = load_otb_sequence(otb_root / "Crossing")
    gt = np.asarray(seq.groundtruth)
    n = 25
    proc = _serve(tmp_path, "--variant", variant)
    assert proc.stdin is not None and proc.stdout is not None
    try:
        # vot-trax 4.0.2's Client needs a logger (log=None fails in ctypes)
        client = Client(stream=(proc.stdin.fileno(), proc.stdout.fileno()), timeout=30,
                        log=lambda text: None)
        assert client.tracker_name == f"wmiltrack-{variant}"
        x, y, w, h = (float(v) for v in gt[0])
        region = (trax.Polygon.create([(x, y), (x + w, y), (x + w, y + h), (x, y + h)]) if polygon
                  else trax.Rectangle.create(x, y, w, h))
        paths = [str(p) for p in seq.paths[:n]]
        objs, _ = client.initialize({"color": trax.FileImage.create(paths[0])}, [(region, {})], {})
        boxes = [region_to_box(objs[0][0])]
        confidences = []
        for p in paths[1:]:
            objs, _ = client.frame({"color": trax.FileImage.create(p)}, {}, [])
            boxes.append(region_to_box(objs[0][0]))
            confidences.append(float(objs[0][1].get("confidence", "nan")) if objs[0][1] else np.nan)
        client.quit()
    finally:
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
        proc.stdin.close()
        proc.stdout.close()
    direct = wmiltrack.Tracker(variant, seed=0)
    direct.init(seq.frame(0) if hasattr(seq, "frame") else next(iter(seq)), gt[0])
    expect = [direct.box]
    for i, frame in enumerate(seq):
        if 1 <= i < n:
            expect.append(direct.update(frame).box)
    np.testing.assert_allclose(np.array(boxes), np.array(expect), atol=1e-3)
    assert len(confidences) == n - 1 and all(0.0 <= c <= 1.0 for c in confidences)
    assert proc.returncode == 0


def test_region_to_box_of_a_rotated_polygon() -> None:
    poly = trax.Polygon.create([(10.0, 0.0), (20.0, 10.0), (10.0, 20.0), (0.0, 10.0)])
    assert region_to_box(poly) == (0.0, 0.0, 20.0, 20.0)
    assert region_to_box(trax.Rectangle.create(1.5, 2.0, 3.0, 4.0)) == (1.5, 2.0, 3.0, 4.0)


def test_help_names_the_trackers_ini_entry(tmp_path: Path) -> None:
    out = subprocess.run([sys.executable, "-m", "wmiltrack.vot", "--help"], capture_output=True,
                         text=True, check=True, cwd=tmp_path).stdout
    assert "TraX" in out and "--variant" in out
