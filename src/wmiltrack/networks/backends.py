"""The runtimes that run a network's ONNX file: onnxruntime and OpenCV's ``cv2.dnn``, each a
small :class:`Backend` with the same one method, chosen by :func:`load_backend`.

A network family's module (:mod:`wmiltrack.networks.nanotrack`) loads each of its files with
:func:`load_backend` and never asks which runtime runs it. A backend is copied and pickled by
its file, runtime and threads, and loads the file again (a runtime's session cannot be copied).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, Protocol

import numpy as np

__all__ = ["RUNTIMES", "Backend", "DnnBackend", "OrtBackend", "choose_runtime", "load_backend",
           "make_dynamic"]

RUNTIMES: tuple[str, ...] = ("auto", "onnxruntime", "opencv")
"""The runtimes a network can be run by; ``"auto"`` is onnxruntime where it is installed, else
OpenCV's dnn."""


class Backend(Protocol):
    """One network file, loaded by one runtime."""

    path: Path

    def run(self, feeds: Mapping[str, np.ndarray], outputs: Sequence[str] | None = None
            ) -> list[np.ndarray]:
        """The network's outputs named ``outputs`` (None: all, in the file's order) for the
        inputs ``feeds`` (by input name)."""
        ...


def make_dynamic(model: Any) -> Any:
    """The ONNX model ``model`` (an ``onnx.ModelProto``) with its inputs' and outputs' height
    and width made symbolic and its stored intermediate shapes dropped, so that onnxruntime
    accepts an exemplar of 127 x 127 in a backbone exported for 255 x 255 (its layers are all
    convolutions and pointwise operations, which take any size). ``model`` is changed."""
    graph = model.graph
    for value in [*graph.input, *graph.output]:
        dims = value.type.tensor_type.shape.dim
        if len(dims) == 4:
            dims[2].dim_param, dims[3].dim_param = f"{value.name}_h", f"{value.name}_w"
    del graph.value_info[:]
    return model


class OrtBackend:
    """A file run by onnxruntime on ``threads`` threads, sequentially; with ``dynamic`` its
    spatial sizes are made symbolic first (:func:`make_dynamic`, which needs ``onnx``)."""

    def __init__(self, path: Path, threads: int = 1, *, dynamic: bool = False) -> None:
        self.path, self.threads, self.dynamic = Path(path), threads, dynamic
        self._load()

    def _load(self) -> None:
        import onnxruntime as ort

        options = ort.SessionOptions()
        options.intra_op_num_threads = self.threads
        options.inter_op_num_threads = 1
        options.execution_mode = ort.ExecutionMode.ORT_SEQUENTIAL
        options.log_severity_level = 3
        source: Any = str(self.path)
        if self.dynamic:
            import onnx

            source = make_dynamic(onnx.load(str(self.path))).SerializeToString()
        self._session = ort.InferenceSession(source, sess_options=options,
                                             providers=["CPUExecutionProvider"])

    def __getstate__(self) -> dict[str, Any]:
        return {"path": self.path, "threads": self.threads, "dynamic": self.dynamic}

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._load()

    def run(self, feeds: Mapping[str, np.ndarray], outputs: Sequence[str] | None = None
            ) -> list[np.ndarray]:
        """See :meth:`Backend.run`."""
        names = None if outputs is None else list(outputs)
        return [np.asarray(o) for o in self._session.run(names, dict(feeds))]


class DnnBackend:
    """A file run by OpenCV's ``cv2.dnn`` (its own threads: ``cv2.setNumThreads``)."""

    def __init__(self, path: Path) -> None:
        self.path = Path(path)
        self._load()

    def _load(self) -> None:
        import cv2

        self._net = cv2.dnn.readNet(str(self.path))

    def __getstate__(self) -> dict[str, Any]:
        return {"path": self.path}

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._load()

    def run(self, feeds: Mapping[str, np.ndarray], outputs: Sequence[str] | None = None
            ) -> list[np.ndarray]:
        """See :meth:`Backend.run` (``outputs`` None: the network's last output only)."""
        if len(feeds) == 1 and outputs is None:
            self._net.setInput(next(iter(feeds.values())))
            return [np.asarray(self._net.forward())]
        for name, blob in feeds.items():
            self._net.setInput(blob, name)
        if outputs is None:
            return [np.asarray(self._net.forward())]
        return [np.asarray(o) for o in self._net.forward(list(outputs))]


def choose_runtime(runtime: str = "auto", threads: int = 1) -> str:
    """``runtime`` checked (one of :data:`RUNTIMES`, and ``threads`` a positive int), with
    ``"auto"`` made onnxruntime where it is installed, else ``"opencv"``."""
    if runtime not in RUNTIMES:
        raise ValueError(f"runtime must be 'auto', 'onnxruntime' or 'opencv', got {runtime!r}")
    if isinstance(threads, bool) or not isinstance(threads, int) or threads < 1:
        raise ValueError(f"threads must be a positive int, got {threads!r}")
    if runtime == "auto":
        return "onnxruntime" if _has_onnxruntime() else "opencv"
    return runtime


def load_backend(path: Path, runtime: str = "auto", threads: int = 1, *,
                 dynamic: bool = False) -> Backend:
    """The file at ``path`` loaded by ``runtime`` (:func:`choose_runtime`); ``dynamic``: its
    spatial sizes may change from call to call (onnxruntime needs to be told, OpenCV's dnn
    does not)."""
    if choose_runtime(runtime, threads) == "onnxruntime":
        return OrtBackend(path, threads, dynamic=dynamic)
    return DnnBackend(path)


def _has_onnxruntime() -> bool:
    try:
        import onnxruntime  # noqa: F401
    except ImportError:
        return False
    return True
