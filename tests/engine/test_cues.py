"""A new cue is one class: this file defines one, composes it into trackers and sees it act,
without touching the package."""

from __future__ import annotations

import numpy as np
import pytest

import wmiltrack
from wmiltrack.data.synthetic import make_preset
from wmiltrack.engine.cues import Cue


class NearPoint:
    """Prefers boxes near a fixed point of the frame: its map is a Gaussian bump there."""

    def __init__(self, point: tuple[float, float], sigma: float, weight: float) -> None:
        self.point, self.sigma, self.weight = point, sigma, weight
        self.started = 0
        self.learnt: list[tuple[int, int, int, int]] = []
        self.regions: list[tuple[int, int, int, int]] = []

    def start(self, frame: np.ndarray, box: tuple[int, int, int, int]) -> None:
        self.started += 1

    def table(self, frame: np.ndarray, region: tuple[int, int, int, int]
              ) -> tuple[np.ndarray, int, int]:
        self.regions.append(region)
        fh, fw = frame.shape[:2]
        x0, y0 = max(region[0], 0), max(region[1], 0)
        x1, y1 = min(region[2], fw), min(region[3], fh)
        ys, xs = np.mgrid[y0:y1, x0:x1].astype(np.float64)
        bump = np.exp(-((xs - self.point[0]) ** 2 + (ys - self.point[1]) ** 2) / (2 * self.sigma**2))
        table = np.zeros((y1 - y0 + 1, x1 - x0 + 1))
        table[1:, 1:] = bump.cumsum(0).cumsum(1)
        return table, x0, y0

    def learn(self, frame: np.ndarray, box: tuple[int, int, int, int]) -> None:
        self.learnt.append(box)


@pytest.fixture(scope="module")
def sequence() -> tuple[list[np.ndarray], np.ndarray]:
    seq = make_preset("easy", seed=3, n_frames=25)
    return seq.load(), np.asarray(seq.groundtruth, dtype=np.float64)


def _centre(box: tuple[float, float, float, float]) -> np.ndarray:
    return np.array([box[0] + box[2] / 2.0, box[1] + box[3] / 2.0])


def _track(frames: list[np.ndarray], box: np.ndarray, variant: str,
           cues: tuple[NearPoint, ...] = (), **overrides: object) -> np.ndarray:
    t = wmiltrack.Tracker(variant, seed=0, cues=cues, **overrides)
    return t.track(frames, box)


@pytest.mark.parametrize("variant,weight,overrides", [
    ("rcwmil", 0.9, {}),
    ("rcwmil-plus", 0.8, {"colour_weight": 0.1}),  # beside the colour cue: two cues merged
])
def test_a_cue_defined_here_pulls_the_boxes_to_its_point(sequence, variant: str, weight: float,
                                                           overrides: dict[str, object]) -> None:
    """Composed into a paper preset (then the only cue) or into rcwmil-plus (beside its colour
    cue, two cues merged in the core's search), the cue is started, asked for its map over the
    search region every frame and told every new box, and with most of the weight it takes
    the boxes to its point, 72 px from the target's start (they stay on the target without
    it)."""
    frames, gt = sequence
    start = _centre(tuple(gt[0]))
    point = (float(start[0] + 60.0), float(start[1] + 40.0))
    cue = NearPoint(point, sigma=40.0, weight=weight)
    assert isinstance(cue, Cue)
    plain = _track(frames, gt[0], variant, **overrides)
    pulled = _track(frames, gt[0], variant, (cue,), **overrides)
    assert cue.started == 1 and len(cue.learnt) == len(frames) - 1 == len(cue.regions)
    assert [tuple(b) for b in pulled[1:]] == [tuple(float(v) for v in b) for b in cue.learnt]
    assert not np.array_equal(plain, pulled)
    to_point = lambda boxes: np.hypot(*(np.array([_centre(b) for b in boxes]) - point).T)  # noqa: E731
    assert to_point(plain[-5:]).mean() > 50.0 and to_point(pulled[-5:]).mean() < 10.0


def test_a_cue_of_weight_zero_changes_nothing_but_the_path(sequence) -> None:
    """With weight 0 the merged choice is the classifier's own: the same boxes as without the
    cue, though the tracker now runs the search and the learning as two core calls."""
    frames, gt = sequence
    np.testing.assert_array_equal(_track(frames[:10], gt[0], "rcwmil"),
                                  _track(frames[:10], gt[0], "rcwmil", (NearPoint((5, 5), 30, 0.0),)))


def test_cues_are_checked_when_the_tracker_is_made() -> None:
    with pytest.raises(ValueError, match="add up to more than 1"):
        wmiltrack.Tracker("rcwmil-plus", cues=[NearPoint((0, 0), 10, 0.5)])  # colour is 0.7
    with pytest.raises(ValueError, match=r"weight must be in \[0, 1\]"):
        wmiltrack.Tracker("rcwmil", cues=[NearPoint((0, 0), 10, 1.5)])
    with pytest.raises(TypeError, match="weight, start, table and learn"):
        wmiltrack.Tracker("rcwmil", cues=[object()])  # type: ignore[list-item]


# Every way of adding cues, each with cue weights that add up to more than 1 (rcwmil-cf's own
# cues: colour 0.65 + correlation filter 0.2; one more of 0.3 makes 1.15).
_TOO_MUCH = [
    ("Params", lambda cue: wmiltrack.Params(colour_weight=0.7, template_weight=0.4)),
    ("Params.replace", lambda cue: wmiltrack.variants()["rcwmil-cf"].replace(template_weight=0.4)),
    ("Tracker override", lambda cue: wmiltrack.Tracker("rcwmil-cf", template_weight=0.4)),
    ("Tracker cues", lambda cue: wmiltrack.Tracker("rcwmil-cf", cues=[cue])),
    ("Tracker params + cues", lambda cue: wmiltrack.Tracker(
        params=wmiltrack.variants()["rcwmil-plus"], cues=[cue, NearPoint((0, 0), 10, 0.1)])),
    ("spec", lambda cue: wmiltrack.trackers.make_tracker("rcwmil-cf:template_weight=0.4")),
    ("make_tracker cues", lambda cue: wmiltrack.trackers.make_tracker("rcwmil-cf", cues=[cue])),
    ("MultiTracker", lambda cue: wmiltrack.MultiTracker("rcwmil-plus", colour_weight=0.9,
                                                        template_weight=0.2)),
    ("compat mapping", lambda cue: wmiltrack.compat.TrackerCompat("rcwmil-cf", {"cues": [cue]})),
    ("compat create", lambda cue: wmiltrack.compat.TrackerCompat.create({"colour_weight": 0.9,
                                                                         "template_weight": 0.2})),
]


@pytest.mark.parametrize("how,make", _TOO_MUCH, ids=[h for h, _ in _TOO_MUCH])
def test_cue_weights_above_1_are_refused_every_way(how: str, make) -> None:
    """One rule (``check_cue_weights``): colour_weight + template_weight + every added cue's
    weight <= 1, whichever way the cues come in (the classifier's share would be negative)."""
    import wmiltrack.compat  # noqa: F401
    import wmiltrack.trackers  # noqa: F401

    with pytest.raises(ValueError, match="add up to more than 1"):
        make(NearPoint((0, 0), 10, 0.3))


def test_cue_weights_up_to_1_are_accepted() -> None:
    t = wmiltrack.Tracker("rcwmil-cf", cues=[NearPoint((0, 0), 10, 0.15)])  # 0.65 + 0.2 + 0.15
    assert t.params.template_weight == 0.2
    with pytest.raises(TypeError, match="a cue needs"):
        wmiltrack.Tracker("rcwmil", cues=[object()])
