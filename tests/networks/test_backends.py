"""The runtimes behind one interface (networks/backends.py) and the one registry of networks
(networks/files.py's model sets), on a small network generated here: no model file needed."""

from __future__ import annotations

import copy
import pickle
from pathlib import Path

import numpy as np
import pytest

from wmiltrack.engine.settings import NETWORKS
from wmiltrack.networks.backends import DnnBackend, OrtBackend, choose_runtime, load_backend
from wmiltrack.networks.families import load_siamese, siamese_networks
from wmiltrack.networks.files import MODELS, nanotrack_versions
from wmiltrack.networks.nanotrack import nanotrack_constants


def small_network(path: Path) -> Path:
    """A 3x3 convolution of a 3-channel input into 2 channels (fixed weights), input ``input``
    and output ``output`` as NanoTrack's backbone names them, its spatial size fixed at 9 x 9."""
    onnx = pytest.importorskip("onnx")
    from onnx import TensorProto, helper, numpy_helper

    weights = np.arange(2 * 3 * 3 * 3, dtype=np.float32).reshape(2, 3, 3, 3) / 50.0
    graph = helper.make_graph(
        [helper.make_node("Conv", ["input", "w"], ["output"], pads=[1, 1, 1, 1])], "small",
        [helper.make_tensor_value_info("input", TensorProto.FLOAT, [1, 3, 9, 9])],
        [helper.make_tensor_value_info("output", TensorProto.FLOAT, [1, 2, 9, 9])],
        [numpy_helper.from_array(weights, "w")])
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 13)])
    model.ir_version = 8
    onnx.save(model, str(path))
    return path


@pytest.mark.extras("onnxruntime", "onnx")
def test_both_runtimes_run_a_file_alike_and_survive_copies(tmp_path: Path) -> None:
    """onnxruntime (sizes made free with ``dynamic``) and OpenCV's dnn give the same outputs
    through the one method, and a copy or an unpickled backend loads its file again."""
    path = small_network(tmp_path / "small.onnx")
    blob = np.random.default_rng(0).uniform(0, 255, (1, 3, 9, 9)).astype(np.float32)
    ort, dnn = load_backend(path, "onnxruntime", dynamic=True), load_backend(path, "opencv")
    assert isinstance(ort, OrtBackend) and isinstance(dnn, DnnBackend)
    want = ort.run({"input": blob})[0]
    assert want.shape == (1, 2, 9, 9)
    np.testing.assert_allclose(dnn.run({"input": blob})[0], want, rtol=1e-5, atol=1e-3)
    np.testing.assert_allclose(dnn.run({"input": blob}, ["output"])[0], want, rtol=1e-5, atol=1e-3)
    for backend in (ort, dnn):
        for again in (copy.deepcopy(backend), pickle.loads(pickle.dumps(backend))):
            np.testing.assert_array_equal(again.run({"input": blob})[0], backend.run({"input": blob})[0])
    bigger = np.zeros((1, 3, 13, 13), np.float32)  # the dynamic session takes another size
    assert ort.run({"input": bigger})[0].shape == (1, 2, 13, 13)


def test_runtime_and_threads_are_checked() -> None:
    assert choose_runtime("auto") in ("onnxruntime", "opencv")
    with pytest.raises(ValueError, match="runtime"):
        choose_runtime("cuda")
    for bad in (0, True, 1.5):
        with pytest.raises(ValueError, match="threads"):
            choose_runtime("opencv", bad)  # type: ignore[arg-type]


def test_one_registry_of_networks_and_versions() -> None:
    """The settings' networks, the families' and NanoTrack's versions all come from the model
    sets; each version's constants are the published ones."""
    assert nanotrack_versions() == ("v2", "v3")
    assert siamese_networks() == tuple(MODELS) == ("nanotrack-v2", "nanotrack-v3")
    assert NETWORKS == ("", *siamese_networks())
    assert [tuple(vars(nanotrack_constants(v)).values()) for v in ("v2", "v3")] == [
        (16, 0.490, 0.150, 0.385), (15, 0.455, 0.138, 0.348)]
    with pytest.raises(ValueError, match="v4"):
        nanotrack_constants("v4")
    with pytest.raises(ValueError, match="no Siamese network 'vittrack'"):
        load_siamese("vittrack")
