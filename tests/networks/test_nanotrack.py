"""NanoTrack's network and published step (wmiltrack/networks/nanotrack.py), its runtimes
(networks/backends.py) and the one registry of its versions (networks/files.py's model sets).

The tests that run the real network read NanoTrack's model files from ``nanotrack_models``
(conftest: ``../shared/models/nanotrack`` or ``$WMILTRACK_TEST_MODELS``; skipped without them,
a failure under CI).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from wmiltrack.data.synthetic import make_sequence
from wmiltrack.eval.metrics import iou
from wmiltrack.networks.nanotrack import NanoNetwork
from wmiltrack.trackers import make_tracker


@pytest.mark.extras("onnxruntime", "onnx")
def test_both_runtimes_give_the_same_features(nanotrack_models: dict[str, tuple[Path, Path]]
                                              ) -> None:
    """onnxruntime (its backbone made size-free on load) and OpenCV's dnn give the same
    feature maps for the 127 px exemplar and the 255 px search crop, and the same head."""
    rng = np.random.default_rng(0)
    for version, files in nanotrack_models.items():
        ort, dnn = NanoNetwork(*files, "onnxruntime"), NanoNetwork(*files, "opencv")
        z, x = (rng.integers(0, 256, (n, n, 3), dtype=np.uint8) for n in (127, 255))
        fz, fx = ort.features(z), ort.features(x)
        assert fz.shape[-2:] == (8, 8) and fx.shape[-2:] == (16, 16)
        np.testing.assert_allclose(fz, dnn.features(z), atol=1e-3, rtol=1e-4)
        np.testing.assert_allclose(fx, dnn.features(x), atol=1e-3, rtol=1e-4)
        for a, b in zip(ort.head(fz, fx), dnn.head(fz, fx)):
            np.testing.assert_allclose(a, b, atol=1e-3, rtol=1e-4)
        assert ort.head(fz, fx)[0].shape[-1] == (16 if version == "v2" else 15)


@pytest.mark.parametrize("version", ["v2", "v3"])
def test_nanotrack_alone_follows_a_generated_target(
        version: str, nanotrack_models: dict[str, tuple[Path, Path]]) -> None:
    """The published step with either version keeps the box on a moving generated target."""
    tracker = make_tracker(f"nanotrack:{version}",
                           backbone=str(nanotrack_models[version][0]),
                           head=str(nanotrack_models[version][1]))
    seq = make_sequence(60, seed=1, occlusion=False)
    frames, gt = seq.load(), np.asarray(seq.groundtruth, dtype=np.float64)
    tracker.init(frames[0], tuple(gt[0]))
    boxes = np.array([tracker.update(f).box for f in frames[1:]])
    assert np.nanmean(iou(boxes, gt[1:])) > 0.5
