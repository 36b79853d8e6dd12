"""NanoTrack's Siamese network and its published tracking step: a
:class:`~wmiltrack.networks.siamese.SiameseStep`.

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

A *narrow* search (``narrow``: a crop of 223 or 191 px instead of 255) is the same step over a
smaller window: the crop keeps the published scale, so the target looks the same and only the
window's reach shrinks (the backbone takes any size; the head is rewritten for the smaller map
when it is loaded, :func:`resize_head`), and each point keeps the cosine window's value it has
in the published grid. At 223 px a pass costs about two thirds of a published one, for a
target that moved little (rcwmil-nano's ``narrow_search``, off in the preset).

:class:`NanoTrackStep` is that step; it can also be moved to a box without forgetting its
template (:meth:`NanoTrackStep.recentre`), search a window centred anywhere
(:meth:`NanoTrackStep.search_at`, for re-detection), and say how alike a box is to the first
frame's target (:meth:`NanoTrackStep.likeness`). Its versions and their constants are the
NanoTrack sets of :data:`wmiltrack.networks.files.MODELS`; the two files are run by either
runtime (:mod:`wmiltrack.networks.backends`). :func:`nanotrack_step` builds it.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .backends import choose_runtime, load_backend, note_once, onnx_installed
from .files import MODELS, ModelFileUnreadable, nanotrack_files, nanotrack_versions, unreadable_message
from .siamese import Candidate, FloatBox, box_centre, context_side, crop

__all__ = ["EXEMPLAR", "INSTANCE", "NanoConstants", "NanoNetwork", "NanoTrackStep", "check_narrow",
           "nanotrack_constants", "nanotrack_step", "resize_head"]

EXEMPLAR = 127
INSTANCE = 255
STRIDE = 16
SEARCH_CELLS = (INSTANCE + 1) // STRIDE  # the published search map's side: 16 cells
MIN_SIDE = 10.0
BACKBONE_OUTPUTS = ("output",)
HEAD_OUTPUTS = ("output1", "output2")


@dataclass(frozen=True)
class NanoConstants:
    """The published post-processing constants of one NanoTrack version."""

    grid: int               # points per side of the head's answer
    window_influence: float
    penalty_k: float
    lr: float


def check_narrow(narrow: int) -> None:
    """``ValueError`` unless ``narrow`` is 0 (no narrow search) or a search crop the backbone
    maps onto whole cells, smaller than the published one and larger than the exemplar: ``16 k
    - 1`` px for ``k`` in 9..15 (143 to 239; 223 and 191 are the sizes measured)."""
    ok = (isinstance(narrow, int) and not isinstance(narrow, bool)
          and (narrow == 0 or (EXEMPLAR < narrow < INSTANCE and (narrow + 1) % STRIDE == 0)))
    if not ok:
        raise ValueError(f"narrow must be 0 or a crop side of 16 k - 1 px between {EXEMPLAR} and "
                         f"{INSTANCE} (143, 159, ..., 239), got {narrow!r}")


def resize_head(model: Any, cells: int) -> Any:
    """NanoTrack's head (an ``onnx.ModelProto``) rewritten to answer a search map of ``cells``
    x ``cells`` instead of the published 16 x 16; ``model`` is changed and returned.

    The head's layers (convolutions, the depth-wise correlation's matrix products) take any
    size, but its exported graph spells the map's size out: the reshapes back to a map are
    constants ``[1, c, 16, 16]`` and ``[1, c, 15, 15]`` (v3), ``[1, -1, 16, 16]`` (v2), and
    its inputs and outputs are declared at those sizes. Each such constant and declared size
    moves by ``cells - 16``; nothing else changes, so the weights are the published ones. A
    head whose sizes are free already (the tests' stand-ins) only has its declared sizes moved.
    """
    from onnx import TensorProto, numpy_helper

    shift = cells - SEARCH_CELLS
    graph = model.graph
    for tensor in graph.initializer:
        if tensor.data_type != TensorProto.INT64 or list(tensor.dims) != [4]:
            continue
        shape = numpy_helper.to_array(tensor)
        if shape[2] == shape[3] and shape[2] in (SEARCH_CELLS - 1, SEARCH_CELLS):
            moved = shape + np.array([0, 0, shift, shift], dtype=shape.dtype)
            tensor.CopyFrom(numpy_helper.from_array(moved, tensor.name))
    for value in [*graph.input[1:], *graph.output]:  # (input1, the template, keeps its size)
        dims = value.type.tensor_type.shape.dim
        for d in dims[2:4] if len(dims) == 4 else ():
            if d.HasField("dim_value"):
                d.dim_value += shift
    del graph.value_info[:]
    return model


def nanotrack_constants(version: str) -> NanoConstants:
    """NanoTrack ``version``'s constants, from its model set (``MODELS["nanotrack-v3"].step``);
    a version that is not one of :func:`~wmiltrack.networks.files.nanotrack_versions` is a
    ValueError."""
    if version not in nanotrack_versions():
        raise ValueError(f"unknown NanoTrack version {version!r}; choose one of "
                         f"{', '.join(nanotrack_versions())}")
    step = MODELS[f"nanotrack-{version}"].step
    return NanoConstants(grid=int(step["grid"]), window_influence=step["window_influence"],
                         penalty_k=step["penalty_k"], lr=step["lr"])


class NanoNetwork:
    """The backbone and head of one NanoTrack version, each run by a backend
    (:func:`~wmiltrack.networks.backends.load_backend`).

    ``features(crop)`` gives the backbone's map of a square BGR uint8 crop (127 or 255 px);
    ``head(template, search)`` the head's (scores, boxes): log-odds of the two classes
    ``(2, n, n)`` and the four side distances ``(4, n, n)``. ``version`` names the set in the
    message of a file that cannot be run; ``runtime`` is the runtime that runs both files
    (``"onnxruntime"`` or ``"opencv"``, ``"auto"`` resolved). With ``narrow`` (a crop side,
    :func:`check_narrow`) the head is also loaded rewritten for that crop's smaller search map
    (:func:`resize_head`, which needs the ``onnx`` package: without it the narrow search is
    off, said once in a logged note), and ``head`` answers either map.
    """

    def __init__(self, backbone: Path, head: Path, runtime: str = "auto", threads: int = 1, *,
                 version: str | None = None, narrow: int = 0) -> None:
        check_narrow(narrow)
        self.files = (Path(backbone), Path(head))
        self.runtime = choose_runtime(runtime, threads)
        if narrow and not onnx_installed():
            note_once("onnx", "wmiltrack: without the onnx package the network's narrow search "
                      "is off (every frame searches the published window): pip install onnx")
            narrow = 0
        self.narrow = narrow
        model = None if version is None else f"nanotrack-{version}"
        self._backbone = load_backend(self.files[0], self.runtime, threads, dynamic=True,
                                      role="backbone", model=model, outputs=BACKBONE_OUTPUTS)
        self._heads = {SEARCH_CELLS: load_backend(self.files[1], self.runtime, threads, role="head",
                                                  model=model, outputs=HEAD_OUTPUTS)}
        if narrow:
            cells = (narrow + 1) // STRIDE
            self._heads[cells] = load_backend(
                self.files[1], self.runtime, threads, role="head", model=model,
                outputs=HEAD_OUTPUTS, rewrite=functools.partial(resize_head, cells=cells),
                rewritten=f"rewritten for a {cells} x {cells} search map (narrow={narrow})")
            self._check_narrow(model)

    def _check_narrow(self, model: str | None) -> None:
        """The narrow head, run once on blank crops, answers on the grid the narrow crop
        should give (the published grid less as many points a side as the map has cells
        fewer); a head that
        does not (another export, whose sizes the rewrite did not find) is a
        :class:`~wmiltrack.networks.files.ModelFileUnreadable` naming the setting to change."""
        blank = np.zeros((EXEMPLAR, EXEMPLAR, 3), np.uint8)
        template = self.features(blank)
        published = self.head(template, self.features(np.zeros((INSTANCE, INSTANCE, 3), np.uint8)))
        narrow = self.head(template, self.features(np.zeros((self.narrow, self.narrow, 3), np.uint8)))
        want = published[0].shape[-1] - (INSTANCE - self.narrow) // STRIDE
        if narrow[0].shape[-1] != want or narrow[1].shape[-1] != want:
            raise ModelFileUnreadable(unreadable_message(
                self.files[1], "head", f"rewritten for the narrow search (narrow={self.narrow}) "
                f"it answers on a grid of {narrow[0].shape[-1]} points a side, not {want}; "
                "set narrow=0 (narrow_search=0 for a preset)", model))

    def features(self, crop: np.ndarray) -> np.ndarray:
        """The backbone's feature map ``(1, c, h, w)`` of a square BGR crop."""
        blob = np.ascontiguousarray(crop.transpose(2, 0, 1)[None], dtype=np.float32)
        return self._backbone.run({"input": blob})[0]

    def head(self, template: np.ndarray, search: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The head's log-odds ``(2, n, n)`` and side distances ``(4, n, n)``."""
        cls, loc = self._heads[search.shape[-1]].run({"input1": template, "input2": search},
                                                     HEAD_OUTPUTS)
        return cls[0], loc[0]


def nanotrack_step(version: str = "v3", *, backbone: str | Path | None = None,
                   head: str | Path | None = None, runtime: str = "auto",
                   threads: int = 1, narrow: int = 0) -> NanoTrackStep:
    """NanoTrack ``version``'s step, its files found by
    :func:`~wmiltrack.networks.files.nanotrack_files` (``backbone``, ``head``: paths that take
    precedence) and run by ``runtime`` on ``threads`` threads; ``narrow``: the crop side of its
    narrow search (0: none)."""
    constants = nanotrack_constants(version)
    files = nanotrack_files(version, backbone, head)
    return NanoTrackStep(NanoNetwork(files[0], files[1], runtime, threads, version=version,
                                     narrow=narrow), constants)


class NanoTrackStep:
    """NanoTrack's tracking step (see the module's docstring).

    ``network`` runs the two ONNX files; ``constants`` are the version's
    (:func:`nanotrack_constants`).
    The template is taken on the first frame and kept: :meth:`recentre` moves the state
    without touching it, so that an expert moved by the judge remembers what it learnt.
    """

    def __init__(self, network: NanoNetwork, constants: NanoConstants) -> None:
        self.network = network
        self.constants = constants
        n = constants.grid
        hann = np.hanning(n)
        ticks = -(n // 2) * STRIDE + STRIDE * np.arange(n, dtype=np.float64)
        # each search size's grid: the cosine window and the points' offsets from the crop's
        # centre; a narrow search's grid is the published one's centre
        self._grids = {INSTANCE: _grid(hann, ticks, 0)}
        narrow = getattr(network, "narrow", 0)
        if narrow:
            self._grids[narrow] = _grid(hann, ticks, (INSTANCE - narrow) // (2 * STRIDE))
        self.centre = (0.0, 0.0)
        self.size = (0.0, 0.0)
        self.frame_wh = (0, 0)

    def start(self, frame: np.ndarray, box: FloatBox) -> None:
        """Take the template from ``frame`` at ``box`` (the published centre convention:
        ``x + (w - 1) / 2``)."""
        x, y, w, h = (float(v) for v in box)
        self.centre = (x + (w - 1) / 2, y + (h - 1) / 2)
        self.size = (w, h)
        self.frame_wh = (frame.shape[1], frame.shape[0])
        # the mean colour, truncated as the published step stores it (in a uint8 image)
        self.fill = tuple(float(int(v)) for v in frame.reshape(-1, 3).mean(axis=0))
        side = round(context_side(w, h))
        exemplar = crop(frame, *self.centre, side, EXEMPLAR, self.fill)  # type: ignore[arg-type]
        self.template = self.network.features(exemplar)
        self.first_embedding = _unit(self.template)

    @property
    def box(self) -> FloatBox:
        """The current box ``(x, y, w, h)``."""
        (cx, cy), (w, h) = self.centre, self.size
        return cx - w / 2, cy - h / 2, w, h

    def recentre(self, box: FloatBox) -> None:
        """Move the state to ``box`` (the template is kept)."""
        self.centre, self.size = box_centre(box), (float(box[2]), float(box[3]))

    def locate(self, frame: np.ndarray, *, narrow: bool = False) -> Candidate:
        """One tracking step on ``frame`` from the current state; the state follows.
        ``narrow``: over the narrow search's window, where the network has one
        (``NanoNetwork.narrow``; else the published window)."""
        found = self.search_at(frame, self.centre, self.size, window=True, narrow=narrow)
        self.centre, self.size = box_centre(found.box), (found.box[2], found.box[3])
        return found

    def search_at(self, frame: np.ndarray, centre: tuple[float, float],
                  size: tuple[float, float], *, window: bool, narrow: bool = False) -> Candidate:
        """The step's choice in a search window centred at ``centre`` for a target of
        ``size`` (with ``window``, the cosine window as in tracking; without it, for
        re-detection, the penalties only; ``narrow``: the narrow search's window, where the
        network has one); the state does not change."""
        instance = (self.network.narrow or INSTANCE) if narrow else INSTANCE
        cosine, px, py = self._grids[instance]
        scores, boxes, scale = self._answer(frame, centre, size, instance, px, py)
        w, h = size
        penalty = self._penalty(boxes, w * scale, h * scale)
        pscore = penalty * scores
        if window:
            infl = self.constants.window_influence
            pscore = pscore * (1 - infl) + cosine * infl
        best = int(np.argmax(pscore))
        lr = float(penalty[best] * scores[best]) * self.constants.lr
        bx, by, bw, bh = boxes[:, best] / scale
        cx, cy = centre[0] + bx, centre[1] + by
        nw, nh = w * (1 - lr) + bw * lr, h * (1 - lr) + bh * lr
        fw, fh = self.frame_wh
        cx, cy = min(max(cx, 0.0), fw), min(max(cy, 0.0), fh)
        nw, nh = min(max(nw, MIN_SIDE), fw), min(max(nh, MIN_SIDE), fh)
        return Candidate((float(cx - nw / 2), float(cy - nh / 2), float(nw), float(nh)),
                         float(scores[best]), float(pscore[best]))

    def _answer(self, frame: np.ndarray, centre: tuple[float, float], size: tuple[float, float],
                instance: int, px: np.ndarray, py: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray, float]:
        """The head's scores (softmax) and boxes ``(cx, cy, w, h)`` relative to the search
        crop's centre, in crop pixels, over the grid of points ``(px, py)`` of an ``instance``
        px crop; and the crop's scale (the same for every crop size)."""
        side = context_side(*size)
        scale = EXEMPLAR / side
        search = crop(frame, centre[0], centre[1], side * instance / EXEMPLAR, instance,
                      self.fill)  # type: ignore[arg-type]
        logits, sides = self.network.head(self.template, self.network.features(search))
        logits = logits.reshape(2, -1).astype(np.float64)
        scores = 1.0 / (1.0 + np.exp(logits[0] - logits[1]))
        left, top, right, bottom = sides.reshape(4, -1).astype(np.float64)
        x1, y1 = px - left, py - top
        x2, y2 = px + right, py + bottom
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

    def search_side(self, size: tuple[float, float]) -> float:
        """The search crop's side in frame pixels for a target of ``size``."""
        return context_side(*size) * (INSTANCE / EXEMPLAR)

    def likeness(self, frame: np.ndarray, box: FloatBox) -> float:
        """How alike the exemplar crop at ``box`` is to the first frame's, by the backbone:
        the cosine of their feature maps (1: the same appearance). A memory of the target that
        the network's own score is not: its best point scores close to 1 on almost every
        frame, on the target or not, while this falls when the crop holds something else."""
        patch = crop(frame, *box_centre(box), context_side(box[2], box[3]), EXEMPLAR,
                     self.fill)  # type: ignore[arg-type]
        return float(np.dot(_unit(self.network.features(patch)), self.first_embedding))


def _grid(hann: np.ndarray, ticks: np.ndarray, trim: int
          ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The cosine window and the points' x and y offsets (each flat, row by row) of the
    published grid less ``trim`` points on every side."""
    hann, ticks = hann[trim:len(hann) - trim], ticks[trim:len(ticks) - trim]
    n = len(ticks)
    return np.outer(hann, hann).ravel(), np.tile(ticks, n), np.repeat(ticks, n)


def _unit(features: np.ndarray) -> np.ndarray:
    v = features.astype(np.float64).ravel()
    out: np.ndarray = v / max(float(np.linalg.norm(v)), 1e-12)
    return out


def _sz(w: np.ndarray, h: np.ndarray) -> np.ndarray:
    pad = (w + h) * 0.5
    out: np.ndarray = np.sqrt((w + pad) * (h + pad))
    return out
