"""NanoTrack's step (wmiltrack/networks/nanotrack.py) against a plain numpy transcription of the
step NanoTrack's authors publish (HonglinChu/SiamTrackers, ``NanoTrack/nanotrack/tracker/
nano_tracker.py`` and ``base_tracker.py``'s ``get_subwindow``), both run on the stand-in
networks the tests write (``stand_in_networks``), so that it runs everywhere.

The transcription below is written from the published code, not from the project's: its crop
pads the frame with the first frame's mean colour (stored in a uint8 image, as published),
takes the integer window and resizes it with ``cv2.resize``; the project's crop takes the same
window and pads only what leaves the frame. The network is not under test: both
sides run the same ONNX files through OpenCV's dnn (the transcription calls ``cv2.dnn`` itself).

Every search is compared from the SAME state (the transcription's, and four others that reach
the frame's edges and the least size), so that no difference builds up along the sequence:

* with the same crop (the one the project's step gave the network): box, score and penalised
  score equal to 1e-9 (float64 in another order): softmax, points, penalty, window, size
  smoothing and clipping;
* the crops themselves, pixel by pixel: equal;
* end to end, each side with its own crop: the same boxes and scores.
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from wmiltrack.data.synthetic import make_sequence
from wmiltrack.networks.nanotrack import NanoNetwork, NanoTrackStep, nanotrack_constants

#: The published configurations (``models/config/configv2.yaml``, ``configv3.yaml``):
#: head grid (OUTPUT_SIZE; v2's from its sizes, (255 - 127) // 16 + 1 + 7), WINDOW_INFLUENCE,
#: PENALTY_K, LR. Written here again on purpose: the project's copy (networks/files.py)
#: is what is checked.
PUBLISHED = {"v2": (16, 0.490, 0.150, 0.385), "v3": (15, 0.455, 0.138, 0.348)}
EXEMPLAR_SIZE, INSTANCE_SIZE, STRIDE, CONTEXT_AMOUNT = 127, 255, 16, 0.5


def _subwindow(im: np.ndarray, pos: np.ndarray, model_sz: int, original_sz: int,
               avg_chans: np.ndarray) -> np.ndarray:
    """``SiameseTracker.get_subwindow``: the ``original_sz`` square at ``pos`` (mean colour
    beyond the frame), resized to ``model_sz``; as (1, 3, n, n) float32 BGR."""
    sz = original_sz
    c = (original_sz + 1) / 2
    xmin = np.floor(pos[0] - c + 0.5)
    ymin = np.floor(pos[1] - c + 0.5)
    xmax, ymax = xmin + sz - 1, ymin + sz - 1
    left, top = int(max(0.0, -xmin)), int(max(0.0, -ymin))
    right, bottom = int(max(0.0, xmax - im.shape[1] + 1)), int(max(0.0, ymax - im.shape[0] + 1))
    xmin, xmax, ymin, ymax = xmin + left, xmax + left, ymin + top, ymax + top
    r, cols, k = im.shape
    padded = np.zeros((r + top + bottom, cols + left + right, k), np.uint8)
    padded[top:top + r, left:left + cols] = im
    padded[:top, left:left + cols] = avg_chans
    padded[r + top:, left:left + cols] = avg_chans
    padded[:, :left] = avg_chans
    padded[:, cols + left:] = avg_chans
    patch = padded[int(ymin):int(ymax + 1), int(xmin):int(xmax + 1)]
    if model_sz != original_sz:
        patch = cv2.resize(patch, (model_sz, model_sz))
    return _blob(patch)


def _blob(patch: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(patch.transpose(2, 0, 1)[None], dtype=np.float32)


class _Published:
    """``NanoTracker``'s ``init`` and ``track``, transcribed; the two ONNX files run by
    ``cv2.dnn``. ``window_influence=None`` keeps the published one."""

    def __init__(self, files: tuple[Path, Path], version: str) -> None:
        self.backbone, self.head = (cv2.dnn.readNet(str(p)) for p in files)
        self.score_size, self.window_influence, self.penalty_k, self.lr = PUBLISHED[version]
        hanning = np.hanning(self.score_size)
        self.window = np.outer(hanning, hanning).flatten()
        ori = -(self.score_size // 2) * STRIDE
        ticks = [ori + STRIDE * d for d in np.arange(0, self.score_size)]
        x, y = np.meshgrid(ticks, ticks)
        self.points = np.stack([x.flatten(), y.flatten()], axis=1).astype(np.float32)

    def _features(self, blob: np.ndarray) -> np.ndarray:
        self.backbone.setInput(blob)
        return np.asarray(self.backbone.forward())

    def init(self, img: np.ndarray, bbox: tuple[float, ...], z_crop: np.ndarray | None = None
             ) -> None:
        """``init``; ``z_crop`` (H x W x 3 uint8): the exemplar crop to use instead of its own."""
        self.center_pos = np.array([bbox[0] + (bbox[2] - 1) / 2, bbox[1] + (bbox[3] - 1) / 2])
        self.size = np.array([bbox[2], bbox[3]])
        w_z = self.size[0] + CONTEXT_AMOUNT * np.sum(self.size)
        h_z = self.size[1] + CONTEXT_AMOUNT * np.sum(self.size)
        s_z = round(np.sqrt(w_z * h_z))
        self.channel_average = np.mean(img, axis=(0, 1))
        own = _subwindow(img, self.center_pos, EXEMPLAR_SIZE, s_z, self.channel_average)
        self.zf = self._features(own if z_crop is None else _blob(z_crop))

    def _outputs(self, x_crop: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The softmax's second class and the boxes (cx, cy, w, h) on the points."""
        self.head.setInput(self.zf, "input1")
        self.head.setInput(self._features(x_crop), "input2")
        cls, loc = self.head.forward(["output1", "output2"])
        logits = cls.reshape(2, -1).T.astype(np.float64)
        e = np.exp(logits - logits.max(axis=1, keepdims=True))
        score = (e / e.sum(axis=1, keepdims=True))[:, 1]
        delta = loc.reshape(4, -1).astype(np.float64)
        x1, y1 = self.points[:, 0] - delta[0], self.points[:, 1] - delta[1]
        x2, y2 = self.points[:, 0] + delta[2], self.points[:, 1] + delta[3]
        return score, np.stack([(x1 + x2) * 0.5, (y1 + y2) * 0.5, x2 - x1, y2 - y1])

    def track(self, img: np.ndarray, x_crop: np.ndarray | None = None,
              window_influence: float | None = None) -> tuple[list[float], float, float]:
        """``track``: the box ``[x, y, w, h]``, the best point's score and penalised score;
        ``x_crop``: the search crop to use instead of its own; ``self.clipped``: whether the
        clipping changed the box."""
        w_z = self.size[0] + CONTEXT_AMOUNT * np.sum(self.size)
        h_z = self.size[1] + CONTEXT_AMOUNT * np.sum(self.size)
        s_z = np.sqrt(w_z * h_z)
        scale_z = EXEMPLAR_SIZE / s_z
        s_x = s_z * (INSTANCE_SIZE / EXEMPLAR_SIZE)
        own = _subwindow(img, self.center_pos, INSTANCE_SIZE, round(s_x), self.channel_average)
        score, pred_bbox = self._outputs(own if x_crop is None else _blob(x_crop))

        def change(r: np.ndarray) -> np.ndarray:
            return np.maximum(r, 1.0 / r)

        def sz(w: np.ndarray, h: np.ndarray) -> np.ndarray:
            pad = (w + h) * 0.5
            return np.sqrt((w + pad) * (h + pad))

        s_c = change(sz(pred_bbox[2], pred_bbox[3]) / sz(self.size[0] * scale_z, self.size[1] * scale_z))
        r_c = change((self.size[0] / self.size[1]) / (pred_bbox[2] / pred_bbox[3]))
        penalty = np.exp(-(r_c * s_c - 1) * self.penalty_k)
        pscore = penalty * score
        infl = self.window_influence if window_influence is None else window_influence
        pscore = pscore * (1 - infl) + self.window * infl
        best_idx = int(np.argmax(pscore))
        self.pscore = pscore
        bbox = pred_bbox[:, best_idx] / scale_z
        lr = penalty[best_idx] * score[best_idx] * self.lr
        cx, cy = bbox[0] + self.center_pos[0], bbox[1] + self.center_pos[1]
        width = self.size[0] * (1 - lr) + bbox[2] * lr
        height = self.size[1] * (1 - lr) + bbox[3] * lr
        boundary = img.shape[:2]
        before = (cx, cy, width, height)
        cx, cy = max(0, min(cx, boundary[1])), max(0, min(cy, boundary[0]))
        width, height = max(10, min(width, boundary[1])), max(10, min(height, boundary[0]))
        self.clipped = before != (cx, cy, width, height)
        self.center_pos, self.size = np.array([cx, cy]), np.array([width, height])
        return ([cx - width / 2, cy - height / 2, width, height], float(score[best_idx]),
                float(pscore[best_idx]))


class _Spy:
    """The project's network, keeping every crop the step gives it (H x W x 3 uint8)."""

    def __init__(self, network: NanoNetwork) -> None:
        self.network, self.crops = network, []  # type: list[np.ndarray]

    def features(self, crop: np.ndarray) -> np.ndarray:
        self.crops.append(crop.copy())
        return self.network.features(crop)

    def head(self, template: np.ndarray, search: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return self.network.head(template, search)


def _pair(files: tuple[Path, Path], version: str) -> tuple[NanoTrackStep, _Spy, _Published]:
    spy = _Spy(NanoNetwork(*files, "opencv"))
    step = NanoTrackStep(spy, nanotrack_constants(version))  # type: ignore[arg-type]
    return step, spy, _Published(files, version)


def _states(ref: _Published, frame: np.ndarray) -> list[tuple[float, float, float, float]]:
    """The states (cx, cy, w, h) each frame is searched from: others first, the transcription's
    own tracking state last (so that it goes on from there): shifted and reshaped, at a corner
    and beyond the right edge (clipping of the centre, padding), and a target smaller than
    the least side (clipping of the size)."""
    (cx, cy), (w, h) = ref.center_pos, ref.size
    fh, fw = frame.shape[:2]
    return [(cx + 9.5, cy - 7.25, w * 1.3, h * 0.8), (2.0, 3.0, w, h), (fw + 15.0, fh - 1.0, w, h),
            (cx, cy, 7.0, 6.0), (cx, cy, w, h)]


def _put(state: tuple[float, float, float, float], ref: _Published, step: NanoTrackStep) -> None:
    ref.center_pos, ref.size = np.array(state[:2]), np.array(state[2:])
    step.centre, step.size = (float(state[0]), float(state[1])), (float(state[2]), float(state[3]))


def _sequence(version: str) -> tuple[list[np.ndarray], list[tuple[float, ...]]]:
    """A generated sequence with occlusion, clutter and the target out of view for a while."""
    seq = make_sequence(36, seed=3 if version == "v2" else 4, out_of_view=(24, 5))
    return seq.load(), [tuple(map(float, b)) for b in seq.groundtruth]


def test_the_versions_constants_are_the_published_ones() -> None:
    for version, (grid, window_influence, penalty_k, lr) in PUBLISHED.items():
        c = nanotrack_constants(version)
        assert (c.grid, c.window_influence, c.penalty_k, c.lr) == (grid, window_influence, penalty_k, lr)


@pytest.mark.parametrize("version", ["v2", "v3"])
def test_each_step_is_the_published_one_on_the_same_crop(
        version: str, stand_in_networks: dict[str, tuple[Path, Path]]) -> None:
    """From the same state and the same crop (the one the project's step gave the network, so
    that the network's answer is the same to the bit), the project's step chooses the
    published box, score and penalised score on every frame and from every state of
    :func:`_states`, with the cosine window (``locate``) and without it (``search_at``): the
    softmax, the points, the penalty, the window, the size smoothing and the clipping are the
    published ones. Float64 arithmetic in another order: 1e-9."""
    frames, gt = _sequence(version)
    step, spy, ref = _pair(stand_in_networks[version], version)
    step.start(frames[0], gt[0])
    ref.init(frames[0], gt[0], z_crop=spy.crops[0])
    assert step.centre == tuple(ref.center_pos) and step.size == tuple(ref.size)
    clipped = []
    for frame in frames[1:]:
        for state in _states(ref, frame):
            _put(state, ref, step)
            alone = step.search_at(frame, step.centre, step.size, window=False)
            expected = ref.track(frame, x_crop=spy.crops[-1], window_influence=0.0)
            np.testing.assert_allclose([*alone.box, alone.score, alone.pscore],
                                       [*expected[0], *expected[1:]], rtol=0, atol=1e-9)
            _put(state, ref, step)
            found = step.locate(frame)
            expected = ref.track(frame, x_crop=spy.crops[-1])
            np.testing.assert_allclose([*found.box, found.score, found.pscore],
                                       [*expected[0], *expected[1:]], rtol=0, atol=1e-9)
            np.testing.assert_allclose([*step.centre, *step.size], [*ref.center_pos, *ref.size],
                                       rtol=0, atol=1e-9)
            clipped.append(ref.clipped)
    assert any(clipped) and not all(clipped)


def _published_sides(size: np.ndarray) -> tuple[float, float]:
    """The published exemplar and search crops' sides (``s_z``, ``s_x``) for a target of ``size``."""
    w_z = size[0] + CONTEXT_AMOUNT * np.sum(size)
    h_z = size[1] + CONTEXT_AMOUNT * np.sum(size)
    s_z = float(np.sqrt(w_z * h_z))
    return s_z, s_z * (INSTANCE_SIZE / EXEMPLAR_SIZE)


def _assert_same_pixels(got: np.ndarray, side: int, expected: np.ndarray) -> float:
    """``got`` (the project's crop) against the published subwindow ``expected`` (1, 3, n, n)
    of an integer window of ``side`` px; returns the mean absolute difference. Both take the
    same integer window, fill what leaves the frame with the same truncated mean colour and
    resize it with ``cv2.resize``: the same pixels."""
    diff = np.abs(got.astype(np.float64) - expected[0].transpose(1, 2, 0))
    assert diff.max() == 0.0
    return float(diff.mean())


@pytest.mark.parametrize("version", ["v2", "v3"])
def test_the_crops_are_the_published_subwindows(
        version: str, stand_in_networks: dict[str, tuple[Path, Path]]) -> None:
    """The exemplar crop (at the published centre ``x + (w - 1) / 2``, its side rounded) and
    every search crop (255 / 127 times as wide, from every state of :func:`_states`, mean
    colour beyond the frame) are the published ``get_subwindow``'s, pixel for pixel
    (:func:`_assert_same_pixels`)."""
    frames, gt = _sequence(version)
    step, spy, ref = _pair(stand_in_networks[version], version)
    step.start(frames[0], gt[0])
    ref.init(frames[0], gt[0])
    s_z = round(_published_sides(ref.size)[0])
    means = [_assert_same_pixels(spy.crops[0], s_z, _subwindow(
        frames[0], ref.center_pos, EXEMPLAR_SIZE, s_z, ref.channel_average))]
    for frame in frames[1:]:
        for state in _states(ref, frame):
            _put(state, ref, step)
            step.locate(frame)
            s_x = round(_published_sides(ref.size)[1])
            means.append(_assert_same_pixels(spy.crops[-1], s_x, _subwindow(
                frame, ref.center_pos, INSTANCE_SIZE, s_x, ref.channel_average)))
            ref.track(frame)
    assert max(means) == 0.0


@pytest.mark.parametrize("version", ["v2", "v3"])
def test_each_step_with_its_own_crop_is_the_published_one(
        version: str, stand_in_networks: dict[str, tuple[Path, Path]]) -> None:
    """End to end, each side with its own crop, from the same state (every state of
    :func:`_states`) on every frame: the crops are the same pixels, so the box and the best
    penalised score are the published ones to 1e-9 (float64 in another order)."""
    frames, gt = _sequence(version)
    step, _, ref = _pair(stand_in_networks[version], version)
    step.start(frames[0], gt[0])
    ref.init(frames[0], gt[0])
    for frame in frames[1:]:
        for state in _states(ref, frame):
            _put(state, ref, step)
            found = step.locate(frame)
            box, _, pscore = ref.track(frame)
            assert found.pscore == pytest.approx(pscore, abs=1e-9)
            assert np.allclose(found.box, box, rtol=0, atol=1e-9)
