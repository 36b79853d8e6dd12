"""The runtimes that run a network's ONNX file: onnxruntime and OpenCV's ``cv2.dnn``, each a
small :class:`Backend` with the same one method, chosen by :func:`load_backend`.

A network family's module (:mod:`wmiltrack.networks.nanotrack`) loads each of its files with
:func:`load_backend` and never asks which runtime runs it. :func:`load_backend` is the one place
where a file that cannot be run (empty, corrupt, truncated, a folder, another role's) becomes one
line naming it, its role and the fix (:class:`~wmiltrack.networks.files.ModelFileUnreadable`),
whichever runtime read it. A backend is copied and pickled by its file, runtime and threads, and
loads the file again (a runtime's session cannot be copied).

A file can be loaded rewritten (``rewrite``: a function on its ``onnx.ModelProto``, such as
NanoTrack's head resized for a smaller search map), by either runtime, with the ``onnx`` package.
onnxruntime runs a backbone at two sizes (:func:`make_dynamic`) only with the ``onnx`` package;
``"auto"`` therefore takes onnxruntime where both are installed, else OpenCV's dnn, and says
once (a logged warning) when onnxruntime is there without ``onnx``.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from ..integrations.opencv_wheels import TrackerUnavailable
from .files import ModelFileUnreadable, unreadable_message

__all__ = ["RUNTIMES", "Backend", "Rewrite", "DnnBackend", "OrtBackend", "choose_runtime", "load_backend",
           "make_dynamic", "note_once", "onnx_installed", "runtime_version"]

RUNTIMES: tuple[str, ...] = ("auto", "onnxruntime", "opencv")
"""The runtimes a network can be run by; ``"auto"`` is onnxruntime where it is installed (with
``onnx``), else OpenCV's dnn."""

_LOG = logging.getLogger("wmiltrack")
_NOTED: set[str] = set()


class Backend(Protocol):
    """One network file, loaded by one runtime."""

    path: Path

    def output_names(self) -> tuple[str, ...]:
        """The names of the network's outputs."""
        ...

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


Rewrite = Callable[[Any], Any]
"""A change made to a network's ``onnx.ModelProto`` before a runtime reads it (picklable: a
module-level function or a ``functools.partial`` of one, so that a backend copies)."""


def _rewritten(path: Path, rewrite: Rewrite | None, dynamic: bool = False) -> bytes | None:
    """The file at ``path`` as bytes after ``rewrite`` and, with ``dynamic``,
    :func:`make_dynamic`; None where neither is asked (the runtime reads the file itself)."""
    if rewrite is None and not dynamic:
        return None
    try:
        import onnx
    except ImportError:
        other = (", or choose OpenCV's dnn (network_runtime=opencv for a preset, runtime=opencv "
                 "for nanotrack:VERSION)") if dynamic else ""
        raise TrackerUnavailable(
            f"the runtime {'onnxruntime' if dynamic else 'here'} needs the onnx package to run "
            f"{'a network at two sizes' if dynamic else 'a rewritten network'}: pip install onnx "
            f"(the nano extra){other}") from None
    model = onnx.load(str(path))
    if rewrite is not None:
        model = rewrite(model)
    if dynamic:
        model = make_dynamic(model)
    data: bytes = model.SerializeToString()
    return data


class OrtBackend:
    """A file run by onnxruntime on ``threads`` threads, sequentially; ``rewrite`` changes it
    first, and with ``dynamic`` its spatial sizes are made symbolic (:func:`make_dynamic`); both
    need ``onnx``."""

    def __init__(self, path: Path, threads: int = 1, *, dynamic: bool = False,
                 rewrite: Rewrite | None = None) -> None:
        self.path, self.threads, self.dynamic, self.rewrite = Path(path), threads, dynamic, rewrite
        self._load()

    def _load(self) -> None:
        try:
            import onnxruntime as ort
        except ImportError:
            raise TrackerUnavailable(
                "the runtime onnxruntime is not installed: pip install onnxruntime onnx (the "
                "nano extra), or choose OpenCV's dnn (network_runtime=opencv for a preset, "
                "runtime=opencv for nanotrack:VERSION)") from None
        options = ort.SessionOptions()
        options.intra_op_num_threads = self.threads
        options.inter_op_num_threads = 1
        options.execution_mode = ort.ExecutionMode.ORT_SEQUENTIAL
        options.log_severity_level = 3
        source: Any = _rewritten(self.path, self.rewrite, self.dynamic) or str(self.path)
        self._session = ort.InferenceSession(source, sess_options=options,
                                             providers=["CPUExecutionProvider"])

    def __getstate__(self) -> dict[str, Any]:
        return {"path": self.path, "threads": self.threads, "dynamic": self.dynamic,
                "rewrite": self.rewrite}

    def output_names(self) -> tuple[str, ...]:
        """See :meth:`Backend.output_names`."""
        return tuple(o.name for o in self._session.get_outputs())

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._load()

    def run(self, feeds: Mapping[str, np.ndarray], outputs: Sequence[str] | None = None
            ) -> list[np.ndarray]:
        """See :meth:`Backend.run`."""
        names = None if outputs is None else list(outputs)
        return [np.asarray(o) for o in self._session.run(names, dict(feeds))]


class DnnBackend:
    """A file run by OpenCV's ``cv2.dnn`` (its own threads: ``cv2.setNumThreads``);
    ``rewrite`` changes it first (with ``onnx``)."""

    def __init__(self, path: Path, *, rewrite: Rewrite | None = None) -> None:
        self.path, self.rewrite = Path(path), rewrite
        self._load()

    def _load(self) -> None:
        import cv2

        data = _rewritten(self.path, self.rewrite)
        self._net = (cv2.dnn.readNet(str(self.path)) if data is None
                     else cv2.dnn.readNetFromONNX(np.frombuffer(data, np.uint8)))

    def __getstate__(self) -> dict[str, Any]:
        return {"path": self.path, "rewrite": self.rewrite}

    def output_names(self) -> tuple[str, ...]:
        """See :meth:`Backend.output_names`."""
        return tuple(self._net.getUnconnectedOutLayersNames())

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
    ``"auto"`` made onnxruntime where it is installed with ``onnx``, else ``"opencv"`` (and,
    once, a logged note when onnxruntime is there without ``onnx``)."""
    if runtime not in RUNTIMES:
        raise ValueError(f"runtime must be 'auto', 'onnxruntime' or 'opencv', got {runtime!r}")
    if isinstance(threads, bool) or not isinstance(threads, int) or threads < 1:
        raise ValueError(f"threads must be a positive int, got {threads!r}")
    if runtime != "auto":
        return runtime
    if not _importable("onnxruntime"):
        return "opencv"
    if _importable("onnx"):
        return "onnxruntime"
    note_once("onnx", "wmiltrack: onnxruntime is installed without the onnx package, which it "
              "needs to run a backbone at two sizes; the networks run on OpenCV's dnn, over their "
              "published search window only (pip install onnx to run them on onnxruntime)")
    return "opencv"


def onnx_installed() -> bool:
    """Whether the ``onnx`` package can be imported: a file is rewritten before it is loaded
    (``rewrite``, ``dynamic``) only with it."""
    return _importable("onnx")


def note_once(key: str, message: str) -> None:
    """Log ``message`` as a warning, once a process for each ``key`` (``"onnx"``: the one note
    that the ``onnx`` package is missing, whatever needed it first)."""
    if key not in _NOTED:
        _NOTED.add(key)
        _LOG.warning(message)


def load_backend(path: Path, runtime: str = "auto", threads: int = 1, *,
                 dynamic: bool = False, role: str = "network", model: str | None = None,
                 outputs: Sequence[str] = (), rewrite: Rewrite | None = None,
                 rewritten: str = "") -> Backend:
    """The file at ``path`` loaded by ``runtime`` (:func:`choose_runtime`); ``dynamic``: its
    spatial sizes may change from call to call (onnxruntime needs to be told, OpenCV's dnn
    does not); ``rewrite``: a change made to the file's model before the runtime reads it,
    ``rewritten`` saying which in a message (the file itself is never written).

    ``role`` and ``model`` (a set of :data:`~wmiltrack.networks.files.MODELS`) say what the
    file was given as, and ``outputs`` the output names a file of that role has: a file that
    is no file, empty, unreadable by the runtime (corrupt, truncated) or without those outputs
    (another role's) is a :class:`~wmiltrack.networks.files.ModelFileUnreadable` whose one
    line names the file, its role and the fix."""
    chosen, path = choose_runtime(runtime, threads), Path(path)

    def unreadable(reason: str) -> ModelFileUnreadable:
        return ModelFileUnreadable(unreadable_message(path, role, reason, model))

    if not path.is_file():
        raise unreadable("it is a folder, not a file" if path.is_dir() else "there is no such file")
    if path.stat().st_size == 0:
        raise unreadable("it is empty (0 bytes)")
    try:
        backend: Backend = (OrtBackend(path, threads, dynamic=dynamic, rewrite=rewrite)
                            if chosen == "onnxruntime" else DnnBackend(path, rewrite=rewrite))
    except (ImportError, TrackerUnavailable):
        raise
    except Exception as exc:  # each runtime has its own errors (DecodeError, Fail, cv2.error...)
        runtime_name = "OpenCV's dnn" if chosen == "opencv" else chosen
        what = f"it {rewritten}" if rewritten else "it"
        raise unreadable(f"{runtime_name} cannot read {what} as an ONNX network (is it corrupt "
                         "or truncated?)") from exc
    missing = [name for name in outputs if name not in backend.output_names()]
    if missing:
        raise unreadable(f"it gives the outputs {', '.join(backend.output_names())}, where a {role} "
                         f"gives {', '.join(outputs)} (another role's file, given in the wrong place?)")
    return backend


def runtime_version(runtime: str) -> str:
    """The installed version of ``runtime`` (``"onnxruntime"`` or ``"opencv"``: ``cv2``'s), as
    its module says it; the boxes are the same for the same runtime and version only."""
    import importlib

    module = importlib.import_module("onnxruntime" if runtime == "onnxruntime" else "cv2")
    return str(getattr(module, "__version__", "unknown"))


def _importable(module: str) -> bool:
    """Whether ``module`` can be imported (the import is done: a later one is free)."""
    try:
        __import__(module)
    except ImportError:
        return False
    return True
