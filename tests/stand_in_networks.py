"""Stand-in networks with NanoTrack's inputs, outputs and shapes, written by the tests
themselves (``onnx.helper``, seeded weights), so that the network expert's logic (the judge,
re-detection, recentring, copies, the bad-input matrix) is tested on a machine without
NanoTrack's model files. They are not NanoTrack: they follow a textured target roughly, and no
test of NanoTrack's own step or accuracy may run on them.

* backbone ``input`` ``(1, 3, H, W)`` -> ``output`` ``(1, C, H', W')``, any size (the spatial
  dimensions are symbolic): the BGR crop less 127.5, one 16 x 16 convolution of stride 16
  (padding 1, so 127 -> 8 and 255 -> 16 cells, as NanoTrack's), ReLU;
* head ``input1`` ``(1, C, 8, 8)`` (template), ``input2`` ``(1, C, 16, 16)`` (search) ->
  ``output1`` ``(1, 2, n, n)`` and ``output2`` ``(1, 4, n, n)``, ``n`` 16 (v2) or 15 (v3): the
  log-odds are a correlation, the cosine between the template's centre 2 x 2 cells and each
  2 x 2 window of the search map (v2's padded by a row and a column of zeros before, so that
  each window is centred on its grid point, 16 px apart), scaled about a threshold; the four
  side distances are 24..40 crop pixels from a 1 x 1 convolution of the search map and a
  sigmoid (about 32: the target's half side in the crop).

Only operators that both onnxruntime and OpenCV's dnn read (Conv, Relu, Add, Mul, Div, Sqrt,
Slice, Pad, ReduceMean, ReduceSum, AveragePool, Neg, Concat, Sigmoid), opset 11.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

#: Backbone channels by version, as NanoTrack's (v2: 48, v3: 96); head grid by version.
CHANNELS = {"v2": 48, "v3": 96}
GRID = {"v2": 16, "v3": 15}
OPSET = 11
#: The log-odds: ``GAIN x (cosine - THRESHOLD)`` for the target, its negative for the rest.
GAIN, THRESHOLD = 6.0, 0.6
LOC_WEIGHT = 0.002
_TO_END = 2**62  # (a Slice end beyond the dimension: up to its end)


def _const(name: str, values: np.ndarray | list[float] | list[int], dtype: type = np.float32):  # type: ignore[no-untyped-def]
    from onnx import numpy_helper

    return numpy_helper.from_array(np.asarray(values, dtype=dtype), name)


def _model(graph, producer: str):  # type: ignore[no-untyped-def]
    import onnx
    from onnx import helper

    model = helper.make_model(graph, producer_name=producer,
                              opset_imports=[helper.make_opsetid("", OPSET)])
    model.ir_version = 6  # (opset 11's; read by every onnxruntime and OpenCV since 2020)
    onnx.checker.check_model(model)
    return model


def backbone_model(version: str, seed: int):  # type: ignore[no-untyped-def]
    """The stand-in backbone of ``version`` as an ``onnx.ModelProto``."""
    from onnx import TensorProto, helper

    c = CHANNELS[version]
    rng = np.random.default_rng(seed)
    weights = rng.standard_normal((c, 3, 16, 16)) / np.sqrt(3 * 16 * 16)
    nodes = [
        helper.make_node("Add", ["input", "offset"], ["centred"]),
        helper.make_node("Conv", ["centred", "w", "b"], ["conv"], kernel_shape=[16, 16],
                         strides=[16, 16], pads=[1, 1, 1, 1]),
        helper.make_node("Relu", ["conv"], ["output"]),
    ]
    graph = helper.make_graph(
        nodes, f"stand_in_backbone_{version}",
        [helper.make_tensor_value_info("input", TensorProto.FLOAT, [1, 3, "height", "width"])],
        [helper.make_tensor_value_info("output", TensorProto.FLOAT, [1, c, "rows", "cols"])],
        [_const("offset", [-127.5]), _const("w", weights), _const("b", np.zeros(c))])
    return _model(graph, "wmiltrack tests: stand-in backbone")


def _correlation_nodes(search: str, n: int) -> list:  # type: ignore[type-arg]
    """Nodes making ``cosine`` ``(1, 1, n, n)``: at each point, the cosine between the
    template's centre 2 x 2 cells (``centre``) and the 2 x 2 cells of ``search`` there."""
    from onnx import helper

    nodes = [helper.make_node("Mul", [search, search], ["s_sq"]),
             helper.make_node("ReduceSum", ["s_sq"], ["s_ss"], axes=[1], keepdims=1),
             helper.make_node("AveragePool", ["s_ss"], ["s_win"], kernel_shape=[2, 2], strides=[1, 1]),
             helper.make_node("Mul", ["centre", "centre"], ["t_sq"]),
             helper.make_node("ReduceMean", ["t_sq"], ["t_ms"], axes=[1, 2, 3], keepdims=1)]
    terms = []
    for dy in (0, 1):
        for dx in (0, 1):
            k = f"{dy}{dx}"
            nodes += [helper.make_node("Slice", ["centre", f"at{k}", f"to{k}", "hw"], [f"t{k}"]),
                      helper.make_node("Slice", [search, f"at{k}", f"end{k}", "hw"], [f"s{k}"]),
                      helper.make_node("Mul", [f"s{k}", f"t{k}"], [f"st{k}"]),
                      helper.make_node("ReduceSum", [f"st{k}"], [f"dot{k}"], axes=[1], keepdims=1)]
            terms.append(f"dot{k}")
    nodes += [helper.make_node("Add", terms[:2], ["dot_a"]),
              helper.make_node("Add", terms[2:], ["dot_b"]),
              helper.make_node("Add", ["dot_a", "dot_b"], ["dot"]),
              helper.make_node("Mul", ["s_win", "t_ms"], ["norms_sq"]),
              helper.make_node("Add", ["norms_sq", "eps"], ["norms_sq_e"]),
              helper.make_node("Sqrt", ["norms_sq_e"], ["norms"]),
              helper.make_node("Div", ["dot", "norms"], ["dot_n"]),
              helper.make_node("Mul", ["dot_n", "norm_scale"], ["cosine"])]
    return nodes


def _correlation_constants(c: int) -> list:  # type: ignore[type-arg]
    """Slice bounds of :func:`_correlation_nodes` (the search map has one cell a side more
    than the answer): the windows' first cells are all cells less the last row or column, or
    less the first; counted from the ends, so that the head takes a search map of any size
    (as NanoTrack's head does once :func:`wmiltrack.networks.nanotrack.resize_head` moved its
    shape constants)."""
    out = [_const("hw", [2, 3], np.int64), _const("norm_scale", [0.25 / np.sqrt(c)])]
    for dy in (0, 1):
        for dx in (0, 1):
            k = f"{dy}{dx}"
            out += [_const(f"at{k}", [dy, dx], np.int64), _const(f"to{k}", [dy + 1, dx + 1], np.int64),
                    _const(f"end{k}", [dy - 1 if dy == 0 else _TO_END, dx - 1 if dx == 0 else _TO_END],
                           np.int64)]
    return out


def head_model(version: str, seed: int):  # type: ignore[no-untyped-def]
    """The stand-in head of ``version`` as an ``onnx.ModelProto``."""
    from onnx import TensorProto, helper

    c, n = CHANNELS[version], GRID[version]
    rng = np.random.default_rng(seed + 1)
    nodes = [helper.make_node("Slice", ["input1", "starts", "ends", "hw"], ["centre"])]
    search = "input2"
    if n == 16:  # a cell of zeros before the first row and column: 17 cells, 16 windows
        nodes.append(helper.make_node("Pad", ["input2", "pads"], ["padded"], mode="constant"))
        search = "padded"
    nodes += [*_correlation_nodes(search, n),
              helper.make_node("Add", ["cosine", "minus_threshold"], ["shifted"]),
              helper.make_node("Mul", ["shifted", "gain"], ["fg"]),
              helper.make_node("Neg", ["fg"], ["bg"]),
              helper.make_node("Concat", ["bg", "fg"], ["output1"], axis=1),
              helper.make_node("Slice", [search, "at00", "end00", "hw"], ["s_first"]),
              helper.make_node("Conv", ["s_first", "w_loc", "b_loc"], ["loc_raw"], kernel_shape=[1, 1]),
              helper.make_node("Sigmoid", ["loc_raw"], ["loc_unit"]),
              helper.make_node("Mul", ["loc_unit", "loc_span"], ["loc_span_px"]),
              helper.make_node("Add", ["loc_span_px", "loc_least"], ["output2"])]
    inits = [_const("starts", [3, 3], np.int64), _const("ends", [5, 5], np.int64),
             _const("pads", [0, 0, 1, 1, 0, 0, 0, 0], np.int64), _const("eps", [1e-6]),
             _const("minus_threshold", [-THRESHOLD]), _const("gain", [GAIN]),
             _const("w_loc", rng.standard_normal((4, c, 1, 1)) * LOC_WEIGHT), _const("b_loc", np.zeros(4)),
             _const("loc_span", [16.0]), _const("loc_least", [24.0]),
             *_correlation_constants(c)]
    graph = helper.make_graph(
        nodes, f"stand_in_head_{version}",
        [helper.make_tensor_value_info("input1", TensorProto.FLOAT, [1, c, 8, 8]),
         helper.make_tensor_value_info("input2", TensorProto.FLOAT, [1, c, 16, 16])],
        [helper.make_tensor_value_info("output1", TensorProto.FLOAT, [1, 2, n, n]),
         helper.make_tensor_value_info("output2", TensorProto.FLOAT, [1, 4, n, n])],
        inits)
    return _model(graph, "wmiltrack tests: stand-in head")


def write_stand_ins(folder: Path, seed: int = 0) -> dict[str, tuple[Path, Path]]:
    """Write both versions' stand-in backbone and head into ``folder/<version>/`` and return
    their paths by version, as ``nanotrack_models`` gives NanoTrack's."""
    import onnx

    out = {}
    for version in CHANNELS:
        d = Path(folder) / version
        d.mkdir(parents=True, exist_ok=True)
        files = (d / "stand_in_backbone.onnx", d / "stand_in_head.onnx")
        onnx.save(backbone_model(version, seed), str(files[0]))
        onnx.save(head_model(version, seed), str(files[1]))
        out[version] = files
    return out
