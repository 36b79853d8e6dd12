"""The six paper presets give exactly the boxes they gave before rcwmil-plus existed.

The digests were recorded on main (2f8933c) before the engine gained scale, motion, gated
update and channels: every ``rcwmil-plus`` component is off in the paper presets, so their
code path, random draws and boxes must not change.
"""

from __future__ import annotations

import hashlib

import numpy as np
import pytest

import wmiltrack
from wmiltrack.data.synthetic import make_preset

PINNED = {
    ("all", "rcwmil"): "9117f0938dbb32f1",
    ("all", "ct"): "d867fab35020efa2",
    ("all", "fct"): "8ce9b32c99d0df4d",
    ("all", "mil"): "89565033cc80040c",
    ("all", "wmil"): "63eb9a24bc3a7b85",
    ("all", "osil"): "069947eb3cbdf2c9",
    ("fast", "rcwmil"): "2edb9db4b2072747",
    ("fast", "ct"): "2a3459935a9a8e96",
    ("fast", "fct"): "2f47bb7d1f51cfd2",
    ("fast", "mil"): "ab9f0820c1a9fa84",
    ("fast", "wmil"): "8202450b3e68c125",
    ("fast", "osil"): "29d9e516c8457779",
}


@pytest.fixture(scope="module")
def sequences() -> dict[str, tuple[list[np.ndarray], np.ndarray]]:
    out = {}
    for preset in ("all", "fast"):
        seq = make_preset(preset, seed=3, n_frames=60)
        out[preset] = (seq.load(), seq.groundtruth)
    return out


def _digest(variant: str, frames: list[np.ndarray], gt: np.ndarray) -> str:
    t = wmiltrack.Tracker(variant, seed=1)
    t.init(frames[0], tuple(gt[0]))
    rows = []
    for f in frames[1:]:
        r = t.update(f)
        rows.append((*r.box, r.score, float(r.ok)))
    return hashlib.sha256(np.array(rows, dtype=np.float64).tobytes()).hexdigest()[:16]


@pytest.mark.parametrize(("preset", "variant"), sorted(PINNED))
def test_paper_preset_boxes_unchanged(sequences, preset: str, variant: str) -> None:
    frames, gt = sequences[preset]
    assert _digest(variant, frames, gt) == PINNED[(preset, variant)]
