"""Each part reads only its own settings: :func:`~wmiltrack.engine.tracker.compose` hands every
part the settings class that owns it (``engine/settings.py``), never the whole ``Params``.

The test hands each part a recording stand-in for the *whole* ``Params`` instead (so a read of
another part's field would succeed and be seen), runs every preset, and checks that every field
read belongs to the class the part was built with."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import pytest

import wmiltrack
from wmiltrack.data.synthetic import make_sequence
from wmiltrack.engine import tracker as tracker_module
from wmiltrack.engine.params import Params


class Recording:
    """Reads ``params`` as a ``cls`` would be read, recording every attribute asked for."""

    __slots__ = ("_params", "_cls", "_reads")

    def __init__(self, params: Params, cls: type[Any], reads: list[tuple[type[Any], str]]
                 ) -> None:
        self._params = params
        self._cls = cls
        self._reads = reads

    def __getattr__(self, name: str) -> Any:
        self._reads.append((self._cls, name))
        return getattr(self._params, name)


#: Every preset, plus the part choices no preset makes (DSST as the scale model, the template as
#: the motion model, velocity motion without the template).
CASES = [(name, {}) for name in wmiltrack.variants()] + [
    ("rcwmil-cf", {"scale_model": "dsst", "scale_dsst": 0.0}),
    ("rcwmil-cf", {"template_motion": True}),
    ("rcwmil", {"motion": "velocity", "redetect": True}),
    ("rcwmil", {"channels": ("luma", "grad")}),
]


@pytest.fixture(scope="module")
def sequence() -> tuple[list[np.ndarray], tuple[int, int, int, int]]:
    seq = make_sequence(40, seed=2, out_of_view=(15, 10))
    box = tuple(int(v) for v in seq.groundtruth[0])
    return seq.load(), box  # type: ignore[return-value]


@pytest.mark.parametrize(("preset", "overrides"), CASES,
                         ids=[f"{p}-{'-'.join(o) or 'preset'}" for p, o in CASES])
def test_each_part_reads_only_its_own_settings(
        monkeypatch: pytest.MonkeyPatch, sequence: tuple[list[np.ndarray], Any],
        preset: str, overrides: dict[str, Any]) -> None:
    reads: list[tuple[type[Any], str]] = []
    monkeypatch.setattr(tracker_module, "own",
                        lambda cls, params: Recording(params, cls, reads))
    frames, box = sequence
    t = wmiltrack.Tracker(preset, seed=0, **overrides)
    t.init(frames[0], box)
    for frame in frames[1:]:
        t.update(frame)
    assert reads
    strays = sorted({(cls.__name__, name) for cls, name in reads
                     if name not in {f.name for f in dataclasses.fields(cls)}})
    assert not strays, f"parts read settings they do not own: {strays}"
    # and no part keeps the whole Params
    parts = t._parts
    assert parts is not None
    for part in (*parts.others(), parts.policy, parts.judge, parts.appearance,
                 parts.appearance.pool):
        if part is None:
            continue
        held = [k for k, v in vars(part).items() if isinstance(v, Params)]
        assert not held, f"{type(part).__name__} holds the whole Params in {held}"
    # no part can call back into the tracker: none holds it or one of its bound methods
    for part in (*parts.others(), parts.policy, parts.judge, parts.appearance):
        if part is None:
            continue
        back = [k for k, v in vars(part).items()
                if v is t or getattr(v, "__self__", None) is t]
        assert not back, f"{type(part).__name__} holds the tracker in {back}"


def test_recovery_constants_are_settings() -> None:
    """The re-detection's constants are RecoverySettings fields whose defaults are the values
    the module once hard-coded (the boxes do not change)."""
    s = wmiltrack.Params()
    assert (s.recover_memory, s.recover_warmup, s.recover_template_rate,
            s.recover_template_area, s.recover_search_area) == (0.9, 10, 0.05, 1600.0, 256.0)
    with pytest.raises(ValueError, match="recover_memory"):
        wmiltrack.Params(recover_memory=1.0)
