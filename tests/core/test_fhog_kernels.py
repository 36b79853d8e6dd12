"""The correlation filters' patch resampling and fHOG kernels (cpp/src/fhog.cpp) beyond
tests/core/test_correlation.py: the resampling against a numpy reference on awkward sizes (output rows
not a multiple of the kernel's 4-row blocks, enlarging, shrinking, regions leaving the
frame, 1/3/4 channels, strided frames), fHOG against its numpy reference at cell sizes other
than 4 and sizes that are not whole cells, and the AVX2 and SSE2 copies giving the same bits
on real frames."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import numpy.typing as npt
import pytest
from test_correlation import fhog_reference, texture

from wmiltrack import _core

F64 = npt.NDArray[np.float64]
U8 = npt.NDArray[np.uint8]


def lattice_stride(step: float) -> int:
    """Every pixel up to a step of 4 frame pixels per output sample, then every
    floor(step / 2)-th (fhog.hpp)."""
    return 1 if step < 4.0 else math.floor(step / 2.0)


def tent_weights(start: float, step: float, n: int, limit: int, stride: int = 1) -> F64:
    """(n, limit) matrix: output sample j's normalised tent weights over the frame's pixels
    along one axis (fhog.hpp: radius max(1, step) around start + (j + 0.5) step - 0.5, on
    every stride-th pixel, the lattice's edge points repeated outside the frame)."""
    w = np.zeros((n, limit))
    radius = max(1.0, step)
    last = (limit - 1) // stride
    for j in range(n):
        centre = start + (j + 0.5) * step - 0.5
        for i in range(math.floor((centre - radius) / stride) + 1,
                       math.ceil((centre + radius) / stride)):
            t = 1.0 - abs(i * stride - centre) / radius
            if t > 0:
                w[j, min(max(i, 0), last) * stride] += t
        w[j] /= w[j].sum()
    return w


def luma(frame: U8) -> F64:
    """OpenCV's 8-bit BGR2GRAY (fixed point, rounded) of a BGR(A) frame; a gray frame as is."""
    if frame.ndim == 2:
        return frame.astype(np.float64)
    b, g, r = (frame[..., k].astype(np.int64) for k in range(3))
    return ((b * 3735 + g * 19235 + r * 9798 + (1 << 14)) >> 15).astype(np.float64)


def gray_patch_reference(frame: U8, centre: tuple[float, float], size: tuple[float, float],
                         out_size: tuple[int, int]) -> F64:
    (cx, cy), (w, h), (ow, oh) = centre, size, out_size
    wy = tent_weights(cy - h / 2, h / oh, oh, frame.shape[0], lattice_stride(h / oh))
    wx = tent_weights(cx - w / 2, w / ow, ow, frame.shape[1], lattice_stride(w / ow))
    return np.asarray(wy @ luma(frame) @ wx.T / 255.0)


CASES = [  # centre, size, out_size (w, h)
    ((40.0, 30.0), (48.0, 36.0), (37, 1)),     # one output row
    ((40.0, 30.0), (48.0, 36.0), (23, 2)),
    ((40.3, 29.6), (19.0, 13.0), (41, 23)),    # enlarging, rows not a multiple of 4
    ((35.5, 31.2), (70.0, 55.0), (17, 13)),    # shrinking about 4x (every 2nd pixel read)
    ((37.5, 29.2), (75.0, 50.0), (9, 13)),     # 8x across (every 4th), 4x down (every 2nd)
    ((40.0, 30.0), (47.0, 37.0), (12, 10)),    # just under 4x: every pixel
    ((3.0, 2.0), (30.0, 22.0), (16, 11)),      # leaves the frame at the top left
    ((77.0, 58.0), (33.0, 40.0), (12, 9)),     # and at the bottom right
    ((40.0, 30.0), (500.0, 400.0), (9, 7)),    # far larger than the frame
    ((40.0, 30.0), (2.5, 1.5), (5, 3)),        # a few pixels
]


@pytest.mark.parametrize("layout", ["gray", "bgr", "bgra", "strided"])
@pytest.mark.parametrize(("centre", "size", "out_size"), CASES)
def test_gray_patch_matches_numpy_reference(layout: str, centre: tuple[float, float],
                                            size: tuple[float, float],
                                            out_size: tuple[int, int]) -> None:
    rng = np.random.default_rng(5)
    bgr = np.stack([texture(60, 80, seed) for seed in (1, 2, 3)], axis=2)
    frames = {"gray": bgr[..., 1].copy(), "bgr": bgr,
              "bgra": np.concatenate([bgr, rng.integers(0, 256, (60, 80, 1), dtype=np.uint8)], 2),
              "strided": bgr[::-1, :, :]}   # a view: negative row stride
    frame = frames[layout]
    got = _core.cf_gray_patch(frame, centre, size, out_size)
    assert got.shape == (out_size[1], out_size[0]) and got.dtype == np.float32
    np.testing.assert_allclose(got, gray_patch_reference(frame, centre, size, out_size),
                               atol=2e-6, rtol=0)


@pytest.mark.parametrize("cell", [1, 2, 3, 5, 6])
def test_fhog_matches_numpy_reference_at_other_cells(cell: int) -> None:
    # 23 x 37: no side a whole number of cells (for cell > 1), so the partial cells' pixels
    # vote into the dropped border; cell 1 puts every pixel's two cells side by side.
    patch = texture(23, 37, seed=cell).astype(np.float32) / 255.0
    got = _core.fhog(patch, cell)
    assert got.shape == (31, 23 // cell, 37 // cell)
    np.testing.assert_allclose(got, fhog_reference(patch.astype(np.float64), cell), atol=2e-5)


def _otb_frames(otb_root: Path) -> list[U8]:
    cv2 = pytest.importorskip("cv2")
    frames = []
    for name in ("Car4", "David", "MotorRolling"):
        files = sorted((otb_root / name / "img").glob("*.jpg"))
        if not files:
            pytest.fail(f"no frames in {otb_root / name / 'img'}")
        for path in (files[0], files[len(files) // 2]):
            frames.append(cv2.imread(str(path), cv2.IMREAD_UNCHANGED))
    return frames


def _features(frames: list[U8]) -> list[npt.NDArray[np.float32]]:
    out = []
    for frame in frames:
        h, w = frame.shape[:2]
        for centre, size, out_size in [((w / 2, h / 2), (192.0, 192.0), (160, 160)),
                                       ((w / 3 + 0.4, h / 2 - 0.3), (90.0, 70.0), (101, 77)),
                                       ((5.0, h - 3.0), (400.0, 250.0), (96, 64))]:
            out.append(_core.cf_gray_patch(frame, centre, size, out_size))
            out.append(_core.fhog_region(frame, centre, size, out_size, 4))
            out.append(_core.scale_samples(frame, centre, size, [0.97, 1.0, 1.03], (64, 48), 4))
    return out


def test_avx2_and_sse2_copies_agree_bit_for_bit_on_real_frames(otb_root: Path) -> None:
    if _core.simd_path() != "avx2":
        pytest.skip(f"this CPU runs the {_core.simd_path()} copy only: nothing to compare")
    frames = _otb_frames(otb_root)
    native = _features(frames)
    _core.set_simd_portable(True)
    try:
        assert _core.simd_path() == "sse2"
        portable = _features(frames)
    finally:
        _core.set_simd_portable(False)
    for a, b in zip(native, portable, strict=True):
        assert a.shape == b.shape
        assert a.tobytes() == b.tobytes()
