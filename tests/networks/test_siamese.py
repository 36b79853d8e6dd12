"""The Siamese networks' crop (wmiltrack/networks/siamese.py): the published step's window, with
the fill only where the window leaves the frame. The published step's own pixels are checked in
test_published_step.py; these are the crop's edge cases, without a network."""

from __future__ import annotations

import numpy as np
import pytest

from wmiltrack.networks.siamese import crop

_FILL = (10.0, 20.0, 30.0)


def _frame() -> np.ndarray:
    rng = np.random.default_rng(0)
    return rng.integers(0, 256, (60, 80, 3), dtype=np.uint8)


def test_a_window_inside_the_frame_of_the_output_size_is_its_pixels() -> None:
    """Side = output size: the integer window itself (a copy: writing to it leaves the frame)."""
    frame = _frame()
    out = crop(frame, 40.0, 30.0, 21, 21, _FILL)
    x0, y0 = 40 - 11, 30 - 11  # floor(c - (n + 1) / 2 + 0.5)
    np.testing.assert_array_equal(out, frame[y0:y0 + 21, x0:x0 + 21])
    out[:] = 0
    assert frame.any()


@pytest.mark.parametrize(("cx", "cy"), [(2.0, 30.0), (78.0, 30.0), (40.0, 1.0), (40.0, 59.0),
                                        (0.0, 0.0), (80.0, 60.0)])
def test_a_window_leaving_the_frame_is_filled_only_outside(cx: float, cy: float) -> None:
    """Past an edge or a corner: the part inside is the frame's pixels, the rest the fill (the
    fill's channels as given, BGR)."""
    frame = _frame()
    n = 21
    out = crop(frame, cx, cy, n, n, _FILL)
    x0, y0 = int(np.floor(cx - (n + 1) / 2 + 0.5)), int(np.floor(cy - (n + 1) / 2 + 0.5))
    padded = np.empty((60 + 2 * n, 80 + 2 * n, 3), dtype=np.uint8)
    padded[:] = np.array(_FILL, dtype=np.uint8)
    padded[n:n + 60, n:n + 80] = frame
    np.testing.assert_array_equal(out, padded[y0 + n:y0 + 2 * n, x0 + n:x0 + 2 * n])
    assert (out == np.array(_FILL, dtype=np.uint8)).all(axis=2).any()


def test_a_window_wholly_outside_the_frame_is_all_fill() -> None:
    out = crop(_frame(), -100.0, -100.0, 30, 15, _FILL)
    assert out.shape == (15, 15, 3) and out.dtype == np.uint8
    assert (out == np.array(_FILL, dtype=np.uint8)).all()


def test_a_resized_window_keeps_a_flat_frame_flat() -> None:
    """Resizing (up or down) a window of one colour gives that colour: no border sampled in."""
    frame = np.full((60, 80, 3), 77, dtype=np.uint8)
    for side in (9, 40, 55):
        out = crop(frame, 40.0, 30.0, side, 25, _FILL)
        assert out.shape == (25, 25, 3) and (out == 77).all()
