"""The narrow search (wmiltrack/networks/nanotrack.py, ``narrow``): NanoTrack's step over a
smaller crop at the published scale, its head rewritten for the smaller map when it is loaded
(``resize_head``); and rcwmil-nano taking it only after a frame its judge vouched for
(``narrow_search``, engine/experts.py).

The network's outputs are compared on NanoTrack's own files where they are there
(``nano_network``: else the stand-ins, whose head is size-free like the rewritten one), by both
runtimes (onnxruntime where the ``nano`` extra is installed).
"""

from __future__ import annotations

import copy
import logging
import pickle
import sys
from pathlib import Path

import numpy as np
import onnx
import pytest

import wmiltrack
from wmiltrack.data.synthetic import make_sequence
from wmiltrack.engine.state import Verdict
from wmiltrack.eval.metrics import iou
from wmiltrack.networks import backends
from wmiltrack.networks.files import ModelFileUnreadable
from wmiltrack.networks.nanotrack import (
    NanoNetwork,
    NanoTrackStep,
    check_narrow,
    nanotrack_constants,
    resize_head,
)
from wmiltrack.networks.siamese import as_bgr

#: Both runtimes; onnxruntime only where the nano extra is installed (a failure under CI's extras run).
RUNTIMES = ["opencv", pytest.param("onnxruntime", marks=pytest.mark.extras("onnxruntime"))]


@pytest.mark.parametrize("runtime", RUNTIMES)
@pytest.mark.parametrize("version", ["v2", "v3"])
@pytest.mark.parametrize("narrow", [223, 191])
def test_the_narrow_head_answers_the_smaller_map(nano_network: dict[str, tuple[Path, Path]],
                                                 version: str, narrow: int, runtime: str) -> None:
    """A crop of ``16 k - 1`` px gives a map of ``k`` cells and an answer of the published grid
    less as many points as the map has cells fewer; the published search is unchanged beside it."""
    net = NanoNetwork(*nano_network[version], runtime, narrow=narrow)
    rng = np.random.default_rng(0)
    template = net.features(rng.integers(0, 255, (127, 127, 3), dtype=np.uint8))
    grid = nanotrack_constants(version).grid
    cells = (narrow + 1) // 16
    for side, want in ((255, grid), (narrow, grid - (16 - cells))):
        search = net.features(rng.integers(0, 255, (side, side, 3), dtype=np.uint8))
        assert search.shape[-2:] == ((side + 1) // 16,) * 2
        scores, sides = net.head(template, search)
        assert scores.shape == (2, want, want) and sides.shape == (4, want, want)


@pytest.mark.parametrize("runtime", RUNTIMES)
@pytest.mark.parametrize("version", ["v2", "v3"])
def test_the_narrow_answer_is_the_published_answer_near_the_centre(
        nano_network: dict[str, tuple[Path, Path]], version: str, runtime: str) -> None:
    """Over the same frame the narrow search chooses about the box the published search chooses,
    with about its score (the backbone sees the same pixels at the same scale, less the margin)."""
    net = NanoNetwork(*nano_network[version], runtime, narrow=223)
    seq = make_sequence(2, seed=3)
    step = NanoTrackStep(net, nanotrack_constants(version))
    frames = [as_bgr(f) for f in seq.frames]
    step.start(frames[0], tuple(float(v) for v in seq.groundtruth[0]))
    wide = step.search_at(frames[1], step.centre, step.size, window=True)
    narrow = step.search_at(frames[1], step.centre, step.size, window=True, narrow=True)
    assert iou(np.array(wide.box), np.array(narrow.box)) > 0.7
    assert abs(wide.score - narrow.score) < 0.2


def test_resize_head_moves_only_the_map_sizes(nano_network: dict[str, tuple[Path, Path]]) -> None:
    """The rewrite moves the declared search and answer sizes and leaves the template's and
    every weight alone; the file itself is never written."""
    path = nano_network["v3"][1]
    before = path.read_bytes()
    model = resize_head(onnx.load(str(path)), 14)
    assert path.read_bytes() == before
    dims = {v.name: [d.dim_value or d.dim_param for d in v.type.tensor_type.shape.dim]
            for v in [*model.graph.input, *model.graph.output]}
    assert dims["input1"][2:] == [8, 8]
    assert dims["input2"][2:] in ([14, 14], [16, 16]) or isinstance(dims["input2"][2], str)
    original = onnx.load(str(path))
    weights = {t.name: t.raw_data for t in original.graph.initializer if t.data_type == onnx.TensorProto.FLOAT}
    assert weights == {t.name: t.raw_data for t in model.graph.initializer
                       if t.data_type == onnx.TensorProto.FLOAT}


@pytest.mark.parametrize("value", [-1, 1, 127, 200, 255, 271, 223.0, True, "223"])
def test_a_narrow_size_that_is_no_crop_is_refused(value: object) -> None:
    with pytest.raises(ValueError, match="narrow must be 0 or a crop side of 16 k - 1 px"):
        check_narrow(value)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="narrow"):
        wmiltrack.Tracker("rcwmil-nano", narrow_search=value)


@pytest.mark.parametrize("runtime", RUNTIMES)
def test_a_head_that_cannot_be_resized_is_one_line(tmp_path: Path, runtime: str,
                                                   nano_network: dict[str, tuple[Path, Path]]) -> None:
    """A head whose grid does not follow the map (here: its answer sliced back to a fixed
    size) is refused when the network is loaded, in one line naming the setting."""
    from onnx import TensorProto, helper, numpy_helper

    backbone, head = nano_network["v3"]
    model = onnx.load(str(head))
    graph = model.graph
    out = graph.output[0]
    inner = out.name + "_free"
    for node in graph.node:
        node.output[:] = [inner if o == out.name else o for o in node.output]
    graph.node.append(helper.make_node("Slice", [inner, "fix_at", "fix_to", "fix_axes"], [out.name]))
    graph.initializer.extend([numpy_helper.from_array(np.array(v, np.int64), n) for n, v in
                              (("fix_at", [0, 0]), ("fix_to", [10, 10]), ("fix_axes", [2, 3]))])
    out.type.tensor_type.shape.dim[2].dim_value = out.type.tensor_type.shape.dim[3].dim_value = 10
    del graph.value_info[:]
    assert TensorProto.FLOAT == out.type.tensor_type.elem_type
    broken = tmp_path / "fixed_head.onnx"
    onnx.save(model, str(broken))
    NanoNetwork(backbone, broken, runtime)  # (the published search alone is not affected)
    with pytest.raises(ModelFileUnreadable) as info:
        NanoNetwork(backbone, broken, runtime, version="v3", narrow=223)
    message = str(info.value)
    assert len(message.splitlines()) == 1 and "narrow_search=0" in message and str(broken) in message


@pytest.mark.parametrize("runtime", RUNTIMES)
def test_copies_keep_the_narrow_search(nano_network: dict[str, tuple[Path, Path]], runtime: str) -> None:
    net = NanoNetwork(*nano_network["v3"], runtime, narrow=191)
    search = net.features(np.full((191, 191, 3), 90, np.uint8))
    template = net.features(np.full((127, 127, 3), 90, np.uint8))
    for other in (pickle.loads(pickle.dumps(net)), copy.deepcopy(net)):
        assert other.narrow == 191
        np.testing.assert_array_equal(other.head(template, search)[0], net.head(template, search)[0])


def test_without_onnx_the_narrow_search_is_off_after_one_note(
        nano_network: dict[str, tuple[Path, Path]], monkeypatch: pytest.MonkeyPatch,
        caplog: pytest.LogCaptureFixture) -> None:
    monkeypatch.setitem(sys.modules, "onnx", None)
    monkeypatch.setattr(backends, "_NOTED", set())
    with caplog.at_level(logging.WARNING, logger="wmiltrack"):
        nets = [NanoNetwork(*nano_network["v3"], "opencv", narrow=223) for _ in range(2)]
    assert [n.narrow for n in nets] == [0, 0]
    notes = [r.getMessage() for r in caplog.records if r.name == "wmiltrack"]
    assert len(notes) == 1 and "narrow search is off" in notes[0] and "pip install onnx" in notes[0]


class _Recorder:
    """Wraps a step's ``locate`` to record each call's ``narrow``."""

    def __init__(self, step: NanoTrackStep) -> None:
        self.step, self.narrow = step, []  # type: ignore[var-annotated]

    def __call__(self, frame: np.ndarray, *, narrow: bool = False):  # type: ignore[no-untyped-def]
        self.narrow.append(narrow)
        return NanoTrackStep.locate(self.step, frame, narrow=narrow)


def _searches(narrow_search: int) -> tuple[list[bool], list[bool]]:
    """rcwmil-nano over a generated sequence with a hidden stretch: for each frame whether its
    network search was narrow, and whether the judge vouched for the frame before (tracked)."""
    seq = make_sequence(40, seed=5, full_occlusion=(15, 24))
    t = wmiltrack.Tracker("rcwmil-nano", narrow_search=narrow_search)
    t.init(seq.frames[0], tuple(int(v) for v in seq.groundtruth[0]))
    expert = t._parts.expert  # noqa: SLF001 (the test looks inside the part it checks)
    rec = _Recorder(expert.locator)
    expert.locator.locate = rec
    vouched = []
    for frame in seq.frames[1:]:
        last = t._last  # noqa: SLF001
        vouched.append(last.vouched and last.verdict is Verdict.TRACKED)
        t.update(frame)
    return rec.narrow, vouched


@pytest.mark.usefixtures("nano_in_environment")
def test_the_expert_searches_narrow_only_after_a_vouched_frame() -> None:
    """Each frame's search is narrow exactly when the frame before was tracked and vouched for
    (never on a lost target's frame, some frames both ways); with ``narrow_search=0``, never."""
    narrow, vouched = _searches(0)
    assert not any(narrow) and any(vouched)
    narrow, vouched = _searches(223)
    assert narrow == vouched and 0 < sum(narrow) < len(narrow)


def test_rcwmil_nano_with_the_narrow_search_follows_a_target(
        nano_in_environment: tuple[Path, Path]) -> None:
    """On a generated sequence the narrow search holds the target about as well as the
    published crop on every frame."""
    seq = make_sequence(60, seed=11)
    scores = {}
    for narrow in (0, 223):
        boxes = wmiltrack.Tracker("rcwmil-nano", narrow_search=narrow).track(seq.frames, seq.groundtruth[0])
        scores[narrow] = float(np.mean([iou(b, g) for b, g in zip(boxes, seq.groundtruth)]))
    assert scores[223] > scores[0] - 0.1 and scores[223] > 0.4, scores
