"""The stand-in networks the tests write (tests/stand_in_networks.py) and NanoTrack's step
(wmiltrack/networks/nanotrack.py) on them, in both runtimes: the shapes NanoTrack's files have,
and the step's state (its template kept when it is moved, copies going on alike). They run
everywhere, without NanoTrack's files; the step's arithmetic against the published one is
test_published_step.py's.
"""

from __future__ import annotations

import copy
import importlib.util
from pathlib import Path

import numpy as np
import pytest

from wmiltrack.data.synthetic import make_sequence
from wmiltrack.networks.nanotrack import NanoNetwork, NanoTrackStep, nanotrack_constants


def _runtimes() -> list[str]:
    return ["opencv", *(["onnxruntime"] if importlib.util.find_spec("onnxruntime") else [])]


@pytest.mark.parametrize("runtime", _runtimes())
def test_stand_ins_have_nanotracks_shapes_in_both_runtimes(
        runtime: str, stand_in_networks: dict[str, tuple[Path, Path]]) -> None:
    """The stand-in networks load in the runtime and answer with NanoTrack's shapes: 8 and 16
    cells for the 127 and 255 px crops, a grid of 16 (v2) or 15 (v3) points, positive side
    distances; the same input gives the same output."""
    rng = np.random.default_rng(0)
    z, x = (rng.integers(0, 256, (n, n, 3), dtype=np.uint8) for n in (127, 255))
    for version, files in stand_in_networks.items():
        net = NanoNetwork(*files, runtime)
        fz, fx = net.features(z), net.features(x)
        assert fz.shape == (1, 96 if version == "v3" else 48, 8, 8) and fx.shape[-2:] == (16, 16)
        cls, loc = net.head(fz, fx)
        n = 16 if version == "v2" else 15
        assert cls.shape == (2, n, n) and loc.shape == (4, n, n) and np.all(loc > 0)
        np.testing.assert_array_equal(net.head(fz, net.features(x))[0], cls)


@pytest.mark.parametrize("runtime", _runtimes())
def test_the_step_on_a_stand_in_keeps_its_template(
        runtime: str, stand_in_networks: dict[str, tuple[Path, Path]]) -> None:
    """NanoTrack's step on a stand-in: the first box is its own likeness 1; ``search_at`` leaves
    the state; ``recentre`` moves it and keeps the template; a copy goes on as the original."""
    seq = make_sequence(12, seed=1, occlusion=False)
    frames, gt = seq.load(), [tuple(map(float, b)) for b in seq.groundtruth]
    loc = NanoTrackStep(NanoNetwork(*stand_in_networks["v3"], runtime), nanotrack_constants("v3"))
    loc.start(frames[0], gt[0])
    assert loc.likeness(frames[0], gt[0]) == pytest.approx(1.0)
    template, state = loc.template.copy(), (loc.centre, loc.size)
    found = loc.search_at(frames[1], (60.0, 60.0), loc.size, window=False)
    assert (loc.centre, loc.size) == state and 0.0 <= found.score <= 1.0
    loc.recentre((100.0, 80.0, 30.0, 20.0))
    assert loc.centre == (115.0, 90.0) and loc.size == (30.0, 20.0)
    np.testing.assert_array_equal(loc.template, template)
    fork = copy.deepcopy(loc)
    assert [loc.locate(f) for f in frames[2:6]] == [fork.locate(f) for f in frames[2:6]]
