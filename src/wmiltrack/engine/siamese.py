"""NanoTrack's Siamese network as a locator: its two ONNX files run by onnxruntime or by
OpenCV's ``cv2.dnn``, and the published tracking step around them.

NanoTrack (HonglinChu/SiamTrackers, Apache-2.0) is a MobileNetV3 backbone and a depth-wise
correlation head. The backbone turns a 127 x 127 exemplar crop of the first frame into a
template (8 x 8 cells) and a 255 x 255 search crop of each new frame into a search map (16 x 16
cells); the head correlates the two and answers on a grid of 16 x 16 (v2) or 15 x 15 (v3)
points 16 px apart: the target's log-odds at each point and the distances from the point to the
four sides of the target's box. The step is the one of the SiamBAN / LightTrack family, as
NanoTrack's repository publishes it:

* crops: the box plus half its perimeter as context (side ``sqrt((w + p)(h + p))``, ``p =
  (w + h) / 2``), the search crop 255 / 127 times as wide, both resized; pixels beyond the frame
  take the first frame's mean colour; BGR, 0..255, as the network was trained;
* each point's score (softmax of the two classes) is multiplied by a penalty on the change of
  size and aspect ratio, ``exp(-k (r s - 1))``, then mixed with a cosine window (``window``);
* the best point gives the new centre; the size moves towards the point's box at a rate
  ``lr x penalty x score`` (size smoothing); the box is clipped to the frame.

``SiameseLocator`` is that step as a part of the engine: it can also be moved to a box without
forgetting its template (:meth:`SiameseLocator.recentre`), search a window centred anywhere
(:meth:`SiameseLocator.search_at`, for re-detection), and say how alike a box is to the first
frame's target (:meth:`SiameseLocator.likeness`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .geometry import centre

__all__ = ["NANO_VERSIONS", "NanoConstants", "NanoTracker", "NetworkRuntime", "SiameseLocator", "Located",
           "as_bgr", "context_side", "load_network", "make_dynamic"]

EXEMPLAR = 127
INSTANCE = 255
STRIDE = 16
CONTEXT = 0.5
MIN_SIDE = 10.0


@dataclass(frozen=True)
class NanoConstants:
    """The published post-processing constants of one NanoTrack version."""

    grid: int               # points per side of the head's answer
    window_influence: float
    penalty_k: float
    lr: float


NANO_VERSIONS: dict[str, NanoConstants] = {
    "v2": NanoConstants(grid=16, window_influence=0.490, penalty_k=0.150, lr=0.385),
    "v3": NanoConstants(grid=15, window_influence=0.455, penalty_k=0.138, lr=0.348),
}
"""NanoTrack's versions by name: the head's grid and the tracking step's constants (the
repository's configuration files; ``shared/models/nanotrack/README.md``)."""


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


class NetworkRuntime:
    """The backbone and head of one NanoTrack version, run by one runtime.

    ``features(crop)`` gives the backbone's map of a square BGR uint8 crop (127 or 255 px);
    ``head(template, search)`` the head's (scores, boxes): log-odds of the two classes
    ``(2, n, n)`` and the four side distances ``(4, n, n)``.
    """

    def __init__(self, backbone: Path, head: Path, runtime: str = "auto", threads: int = 1) -> None:
        if runtime not in ("auto", "onnxruntime", "opencv"):
            raise ValueError(f"runtime must be 'auto', 'onnxruntime' or 'opencv', got {runtime!r}")
        if isinstance(threads, bool) or not isinstance(threads, int) or threads < 1:
            raise ValueError(f"threads must be a positive int, got {threads!r}")
        if runtime == "auto":
            runtime = "onnxruntime" if _has_onnxruntime() else "opencv"
        self.runtime = runtime
        self.threads = threads
        self.files = (Path(backbone), Path(head))
        self._load()

    def _load(self) -> None:
        backbone, head = self.files
        if self.runtime == "onnxruntime":
            self._backbone = _ort_session(backbone, self.threads, dynamic=True)
            self._head = _ort_session(head, self.threads, dynamic=False)
        else:
            import cv2

            self._backbone = cv2.dnn.readNet(str(backbone))
            self._head = cv2.dnn.readNet(str(head))

    # (copy.deepcopy and pickling reload the files: sessions cannot be copied)
    def __getstate__(self) -> dict[str, Any]:
        return {"runtime": self.runtime, "threads": self.threads, "files": self.files}

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._load()

    def features(self, crop: np.ndarray) -> np.ndarray:
        """The backbone's feature map ``(1, c, h, w)`` of a square BGR crop."""
        blob = np.ascontiguousarray(crop.transpose(2, 0, 1)[None], dtype=np.float32)
        if self.runtime == "onnxruntime":
            out: np.ndarray = self._backbone.run(None, {"input": blob})[0]
            return out
        self._backbone.setInput(blob)
        return np.asarray(self._backbone.forward())

    def head(self, template: np.ndarray, search: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The head's log-odds ``(2, n, n)`` and side distances ``(4, n, n)``."""
        if self.runtime == "onnxruntime":
            cls, loc = self._head.run(None, {"input1": template, "input2": search})
        else:
            self._head.setInput(template, "input1")
            self._head.setInput(search, "input2")
            cls, loc = self._head.forward(["output1", "output2"])
        return np.asarray(cls)[0], np.asarray(loc)[0]


def _has_onnxruntime() -> bool:
    try:
        import onnxruntime  # noqa: F401
    except ImportError:
        return False
    return True


def _ort_session(path: Path, threads: int, *, dynamic: bool) -> Any:
    """An onnxruntime session of the file at ``path`` on ``threads`` threads (its spatial
    sizes made symbolic with ``dynamic``, which needs the ``onnx`` package)."""
    import onnxruntime as ort

    options = ort.SessionOptions()
    options.intra_op_num_threads = threads
    options.inter_op_num_threads = 1
    options.execution_mode = ort.ExecutionMode.ORT_SEQUENTIAL
    options.log_severity_level = 3
    source: Any = str(path)
    if dynamic:
        import onnx

        source = make_dynamic(onnx.load(str(path))).SerializeToString()
    return ort.InferenceSession(source, sess_options=options, providers=["CPUExecutionProvider"])


def load_network(backbone: Path, head: Path, runtime: str = "auto", threads: int = 1
                 ) -> NetworkRuntime:
    """:class:`NetworkRuntime` of two model files (``runtime``: ``"onnxruntime"``,
    ``"opencv"``, or ``"auto"``: onnxruntime when it is installed)."""
    return NetworkRuntime(backbone, head, runtime, threads)


def context_side(w: float, h: float) -> float:
    """The exemplar crop's side in frame pixels for a target of ``w x h``."""
    pad = CONTEXT * (w + h)
    return math.sqrt((w + pad) * (h + pad))


def crop(frame: np.ndarray, cx: float, cy: float, side: float, out: int,
         fill: tuple[float, float, float]) -> np.ndarray:
    """The square of ``side`` frame pixels (rounded) centred at ``(cx, cy)``, resized to
    ``out`` x ``out``; beyond the frame, ``fill``. One bilinear warp: the same pixel centres
    as cropping the integer window and resizing it."""
    import cv2

    n = max(1, int(round(side)))
    x0 = math.floor(cx - (n + 1) / 2 + 0.5)
    y0 = math.floor(cy - (n + 1) / 2 + 0.5)
    s = n / out
    m = np.array([[s, 0.0, x0 + 0.5 * s - 0.5], [0.0, s, y0 + 0.5 * s - 0.5]])
    return cv2.warpAffine(frame, m, (out, out), flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
                          borderMode=cv2.BORDER_CONSTANT, borderValue=fill)


@dataclass(frozen=True)
class Located:
    """One search of the network: the box it chose ``(x, y, w, h)``, its score there (the
    softmax of the point's two classes, before penalties) and the best penalised score."""

    box: tuple[float, float, float, float]
    score: float
    pscore: float


class SiameseLocator:
    """NanoTrack's tracking step (see the module's docstring) as an engine part.

    ``network`` runs the two ONNX files; ``constants`` are the version's (:data:`NANO_VERSIONS`).
    The template is taken on the first frame and kept: :meth:`recentre` moves the state
    without touching it, so that an expert moved by the judge remembers what it learnt.
    """

    def __init__(self, network: NetworkRuntime, constants: NanoConstants) -> None:
        self.network = network
        self.constants = constants
        n = constants.grid
        hann = np.hanning(n)
        self._window = np.outer(hann, hann).ravel()
        ticks = -(n // 2) * STRIDE + STRIDE * np.arange(n, dtype=np.float64)
        self._px = np.tile(ticks, n)
        self._py = np.repeat(ticks, n)
        self.centre = (0.0, 0.0)
        self.size = (0.0, 0.0)
        self.frame_wh = (0, 0)

    def start(self, frame: np.ndarray, box: tuple[float, float, float, float]) -> None:
        """Take the template from ``frame`` at ``box`` (the published centre convention:
        ``x + (w - 1) / 2``)."""
        x, y, w, h = (float(v) for v in box)
        self.centre = (x + (w - 1) / 2, y + (h - 1) / 2)
        self.size = (w, h)
        self.frame_wh = (frame.shape[1], frame.shape[0])
        self.fill = tuple(float(v) for v in frame.reshape(-1, 3).mean(axis=0))
        side = round(context_side(w, h))
        exemplar = crop(frame, *self.centre, side, EXEMPLAR, self.fill)  # type: ignore[arg-type]
        self.template = self.network.features(exemplar)
        self.first_embedding = _unit(self.template)

    @property
    def box(self) -> tuple[float, float, float, float]:
        """The current box ``(x, y, w, h)``."""
        (cx, cy), (w, h) = self.centre, self.size
        return cx - w / 2, cy - h / 2, w, h

    def recentre(self, box: tuple[float, float, float, float]) -> None:
        """Move the state to ``box`` (the template is kept)."""
        self.centre, self.size = centre(box), (float(box[2]), float(box[3]))

    def locate(self, frame: np.ndarray) -> Located:
        """One tracking step on ``frame`` from the current state; the state follows."""
        found = self.search_at(frame, self.centre, self.size, window=True)
        self.centre, self.size = centre(found.box), (found.box[2], found.box[3])
        return found

    def search_at(self, frame: np.ndarray, centre: tuple[float, float],
                  size: tuple[float, float], *, window: bool) -> Located:
        """The step's choice in a search window centred at ``centre`` for a target of
        ``size`` (with ``window``, the cosine window as in tracking; without it, for
        re-detection, the penalties only); the state does not change."""
        scores, boxes, scale = self._answer(frame, centre, size)
        w, h = size
        penalty = self._penalty(boxes, w * scale, h * scale)
        pscore = penalty * scores
        if window:
            infl = self.constants.window_influence
            pscore = pscore * (1 - infl) + self._window * infl
        best = int(np.argmax(pscore))
        lr = float(penalty[best] * scores[best]) * self.constants.lr
        bx, by, bw, bh = boxes[:, best] / scale
        cx, cy = centre[0] + bx, centre[1] + by
        nw, nh = w * (1 - lr) + bw * lr, h * (1 - lr) + bh * lr
        fw, fh = self.frame_wh
        cx, cy = min(max(cx, 0.0), fw), min(max(cy, 0.0), fh)
        nw, nh = min(max(nw, MIN_SIDE), fw), min(max(nh, MIN_SIDE), fh)
        return Located((float(cx - nw / 2), float(cy - nh / 2), float(nw), float(nh)),
                       float(scores[best]), float(pscore[best]))

    def _answer(self, frame: np.ndarray, centre: tuple[float, float], size: tuple[float, float]
                ) -> tuple[np.ndarray, np.ndarray, float]:
        """The head's scores (softmax) and boxes ``(cx, cy, w, h)`` relative to the search
        crop's centre, in crop pixels, over the grid; and the crop's scale."""
        side = context_side(*size)
        scale = EXEMPLAR / side
        search = crop(frame, centre[0], centre[1], side * INSTANCE / EXEMPLAR, INSTANCE,
                      self.fill)  # type: ignore[arg-type]
        logits, sides = self.network.head(self.template, self.network.features(search))
        logits = logits.reshape(2, -1).astype(np.float64)
        scores = 1.0 / (1.0 + np.exp(logits[0] - logits[1]))
        left, top, right, bottom = sides.reshape(4, -1).astype(np.float64)
        x1, y1 = self._px - left, self._py - top
        x2, y2 = self._px + right, self._py + bottom
        boxes = np.stack([(x1 + x2) / 2, (y1 + y2) / 2, x2 - x1, y2 - y1])
        return scores, boxes, scale

    def _penalty(self, boxes: np.ndarray, w: float, h: float) -> np.ndarray:
        """``exp(-k (r s - 1))``: the change of context size ``s`` and aspect ratio ``r``
        from the current size ``(w, h)`` (in crop pixels), each as max(x, 1/x)."""
        bw, bh = np.maximum(boxes[2], 1e-6), np.maximum(boxes[3], 1e-6)
        s = _sz(bw, bh) / _sz(np.asarray(w), np.asarray(h))
        r = (w / h) / (bw / bh)
        change = np.maximum(s, 1 / s) * np.maximum(r, 1 / r)
        out: np.ndarray = np.exp(-(change - 1) * self.constants.penalty_k)
        return out

    def likeness(self, frame: np.ndarray, box: tuple[float, float, float, float]) -> float:
        """How alike the exemplar crop at ``box`` is to the first frame's, by the backbone:
        the cosine of their feature maps (1: the same appearance). A memory of the target that
        the network's own score is not: its best point scores close to 1 on almost every
        frame, on the target or not, while this falls when the crop holds something else."""
        patch = crop(frame, *centre(box), context_side(box[2], box[3]), EXEMPLAR,
                     self.fill)  # type: ignore[arg-type]
        return float(np.dot(_unit(self.network.features(patch)), self.first_embedding))


def _unit(features: np.ndarray) -> np.ndarray:
    v = features.astype(np.float64).ravel()
    out: np.ndarray = v / max(float(np.linalg.norm(v)), 1e-12)
    return out


def _sz(w: np.ndarray, h: np.ndarray) -> np.ndarray:
    pad = (w + h) * 0.5
    out: np.ndarray = np.sqrt((w + pad) * (h + pad))
    return out


class NanoTracker:
    """NanoTrack alone, by its published tracking step (the peer ``nanotrack:v2`` /
    ``nanotrack:v3`` of ``wmiltrack eval``): a box on every frame, its score the network's
    softmax at the chosen point; it never reports a lost target (``ok`` is always True).

    ``backbone``, ``head``: the model files (else found by :func:`wmiltrack.models.nanotrack_files`);
    ``runtime``, ``threads``: as :func:`load_network`.
    """

    def __init__(self, version: str = "v3", *, backbone: str | Path | None = None,
                 head: str | Path | None = None, runtime: str = "auto", threads: int = 1) -> None:
        from ..models import nanotrack_files

        if version not in NANO_VERSIONS:
            raise ValueError(f"unknown NanoTrack version {version!r}; choose one of "
                             f"{', '.join(NANO_VERSIONS)}")
        files = nanotrack_files(version, backbone, head)
        self.version = version
        self._locator = SiameseLocator(load_network(*files, runtime, threads),
                                       NANO_VERSIONS[version])

    def init(self, frame: np.ndarray, box: Any) -> None:
        """Take the template from ``frame`` at ``box = (x, y, w, h)``."""
        from .frames import as_frame, clip_box

        img = as_bgr(as_frame(frame))
        x, y, w, h = clip_box(box, img.shape[1], img.shape[0])
        self._locator.start(img, (float(x), float(y), float(w), float(h)))

    def update(self, frame: np.ndarray) -> Any:
        """One tracking step: the new box and the network's score."""
        from .frames import as_frame
        from .result import TrackResult

        found = self._locator.locate(as_bgr(as_frame(frame)))
        return TrackResult(found.box, found.score, True)


def as_bgr(frame: np.ndarray) -> np.ndarray:
    """A checked frame (:func:`~wmiltrack.engine.frames.as_frame`) as BGR, what the network
    reads: grey (``H x W`` or ``H x W x 1``) repeated over three channels, BGRA's alpha
    dropped."""
    import cv2

    channels = 1 if frame.ndim == 2 else frame.shape[2]
    if channels == 3:
        return frame
    code = cv2.COLOR_GRAY2BGR if channels == 1 else cv2.COLOR_BGRA2BGR
    out: np.ndarray = cv2.cvtColor(np.ascontiguousarray(frame), code)
    return out
