"""Each part reads only its own settings: :func:`~wmiltrack.engine.tracker.compose` hands every
part the settings class that owns it (in the part's own module), never the whole ``Params``, and
the user's part factories get their own settings only.

The test records *every* read of a setting while every preset runs (any attribute read of
any settings object, ``Params`` included, by whatever code), finds which part made it (the
innermost calling method whose ``self`` is a part), and checks that each part read only fields
of its own kind's settings class, and never from a whole ``Params``. Reads by the tracker
itself (the composer) are checked against the fixed list of what it decides: which parts to
build and the search it runs."""

from __future__ import annotations

import dataclasses
import enum
import os
import sys
from typing import Any

import numpy as np
import pytest

import wmiltrack
from wmiltrack.data.synthetic import make_sequence
from wmiltrack.engine import (
    AppearanceSettings,
    ColourSettings,
    JudgeSettings,
    MotionSettings,
    RecoverySettings,
    ScaleSettings,
    ScoreSettings,
    TemplateSettings,
)
from wmiltrack.engine.appearance import HaarAppearance
from wmiltrack.engine.classifier import GaussianPool
from wmiltrack.engine.colour import ColourModel
from wmiltrack.engine.cues import ColourCue
from wmiltrack.engine.judge import FrameJudge
from wmiltrack.engine.motion import VelocityMotion
from wmiltrack.engine.params import PARTS, Params
from wmiltrack.engine.policy import ContrastScore, ReportedScore
from wmiltrack.engine.recovery import Redetector
from wmiltrack.engine.sampling import BagSampler
from wmiltrack.engine.scale import DSSTScale, HaarScale
from wmiltrack.engine.template import CorrelationTemplate

#: Each part class, with the settings class it may read.
OWNER = {
    HaarAppearance: AppearanceSettings, BagSampler: AppearanceSettings,
    GaussianPool: AppearanceSettings, HaarScale: ScaleSettings, DSSTScale: ScaleSettings,
    VelocityMotion: MotionSettings, ColourCue: ColourSettings, ColourModel: ColourSettings,
    CorrelationTemplate: TemplateSettings, ReportedScore: ScoreSettings,
    ContrastScore: ScoreSettings, Redetector: RecoverySettings, FrameJudge: JudgeSettings,
}

#: What the tracker itself reads: which parts to build, the search's grids and reach, the
#: confidence's offset and how the cues' maps merge.
COMPOSER_READS = {
    "variant", "coarse_radius", "coarse_step", "fine_radius", "fine_step", "colour_weight",
    "template_weight", "template_motion", "motion", "scale_steps", "scale_model", "redetect",
    "score_colour", "score_luma", "confidence_offset", "colour_relative", "stage_reach",
    "judge_memory", "network", "tracker_every",  # (which stages a frame walks: rests)
}

SETTINGS = {*PARTS, AppearanceSettings, Params}
_TRACKER_FILE = os.path.join("engine", "tracker.py")
_SETTINGS_FILE = os.path.join("engine", "settings.py")


def _reader(frame: Any) -> Any:
    """Who reads, from the frame that read: the innermost part (its class), the settings
    object itself (its own checks and properties), ``own`` (which copies exactly its class's
    fields), the tracker ("composer") or "other"."""
    while frame is not None:
        me = frame.f_locals.get("self")
        if type(me) in SETTINGS:
            return "settings"
        if frame.f_code.co_name == "own" and frame.f_code.co_filename.endswith(_SETTINGS_FILE):
            return "own"
        if type(me) in OWNER:
            return type(me)
        if frame.f_code.co_filename.endswith(_TRACKER_FILE):
            return "composer"
        frame = frame.f_back
    return "other"


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
@pytest.mark.usefixtures("nano_in_environment")  # (rcwmil-nano: real or stand-in network)
def test_each_part_reads_only_its_own_settings(
        monkeypatch: pytest.MonkeyPatch, sequence: tuple[list[np.ndarray], Any],
        preset: str, overrides: dict[str, Any]) -> None:
    reads: list[tuple[type[Any], str, Any]] = []
    fields = {cls: {f.name for f in dataclasses.fields(cls)} for cls in SETTINGS}

    def recorded(self: Any, name: str) -> Any:
        value = object.__getattribute__(self, name)
        if name in fields.get(type(self), ()):
            reads.append((type(self), name, _reader(sys._getframe(1))))
        return value

    for cls in SETTINGS:
        monkeypatch.setattr(cls, "__getattribute__", recorded)
    frames, box = sequence
    t = wmiltrack.Tracker(preset, seed=0, **overrides)
    t.init(frames[0], box)
    for frame in frames[1:]:
        t.update(frame)
    monkeypatch.undo()
    by_parts = [(cls, name, who) for cls, name, who in reads if isinstance(who, type)]
    assert by_parts, "no part read a setting: the recording sees nothing"
    strays = sorted({(who.__name__, cls.__name__, name) for cls, name, who in by_parts
                     if cls is not OWNER[who]})
    assert not strays, f"parts read settings they do not own (part, class, field): {strays}"
    unknown = sorted({(cls.__name__, name) for cls, name, who in reads if who == "other"})
    assert not unknown, f"settings read by code outside the parts and the tracker: {unknown}"
    composer = {name for cls, name, who in reads if who == "composer" and cls is Params}
    assert composer <= COMPOSER_READS, f"the tracker reads more: {composer - COMPOSER_READS}"
    # and no part keeps the whole Params
    parts = t.parts
    for part in (*parts.others(), parts.policy, parts.appearance, parts.appearance.pool):
        held = [k for k, v in vars(part).items() if isinstance(v, Params)]
        assert not held, f"{type(part).__name__} holds the whole Params in {held}"
    # no part can call back into the tracker: none holds it or one of its bound methods
    for part in (*parts.others(), parts.policy, parts.appearance):
        back = [k for k, v in vars(part).items()
                if v is t or getattr(v, "__self__", None) is t]
        assert not back, f"{type(part).__name__} holds the tracker in {back}"
    # and no part holds another part, or an object another part holds (its histograms, its
    # filter): each part's state is its own
    shared = _shared_objects(parts)
    assert not shared, f"parts that hold the same object (part, part, attribute): {shared}"


def _held(part: Any) -> dict[int, tuple[str, Any]]:
    """The objects a part holds that can change (not numbers, strings, tuples, enums or frozen
    settings), by identity: its attributes and theirs, one level down (a model's arrays)."""
    out: dict[int, tuple[str, Any]] = {}
    for name, value in vars(part).items():
        for sub_name, sub in [(name, value), *((f"{name}.{k}", v) for k, v in
                                               getattr(value, "__dict__", {}).items())]:
            if sub is None or isinstance(sub, (int, float, str, bytes, tuple, frozenset,
                                               type, enum.Enum)) or type(sub) in SETTINGS:
                continue
            if dataclasses.is_dataclass(sub) and type(sub).__dataclass_params__.frozen:  # type: ignore[attr-defined]
                continue
            out.setdefault(id(sub), (sub_name, sub))
    return out


def _shared_objects(parts: Any) -> list[tuple[str, str, str]]:
    """(part, other part, what) for each object two parts hold, or a part that holds another."""
    report = getattr(parts.policy, "report", None)
    own: list[Any] = []
    for part in (*parts.others(), parts.policy, *([report] if report is not None else []),
                 parts.appearance):
        if not any(part is seen for seen in own):
            own.append(part)
    found = []
    held = [_held(p) for p in own]
    for i, a in enumerate(own):
        for j, b in enumerate(own):
            if i == j or (a is parts.policy and b is report) or (b is parts.policy and a is report):
                continue  # (the reported score is the policy's own)
            if id(b) in held[i]:
                found.append((type(a).__name__, type(b).__name__, held[i][id(b)][0]))
            elif i < j:
                for key in held[i].keys() & held[j].keys():
                    if not isinstance(held[i][key][1], np.ndarray) or held[i][key][1].size:
                        found.append((type(a).__name__, type(b).__name__, held[i][key][0]))
    return found


def test_the_check_sees_a_part_that_holds_another_parts_object(
        sequence: tuple[list[np.ndarray], Any]) -> None:
    """A reported score that reads the colour cue's live histograms (as rcwmil-plus's did
    before the score kept its own) is caught: the check above would fail on it."""
    frames, box = sequence
    t = wmiltrack.Tracker("rcwmil-plus", seed=0, score_colour_model="current")
    t.init(frames[0], box)
    assert not _shared_objects(t.parts)
    colour = next(c for c in t.parts.cues if isinstance(c, ColourCue))
    t.parts.policy.report.colour = colour.model
    assert ("ColourCue", "ContrastScore", "model") in _shared_objects(t.parts)


def test_the_recording_sees_a_part_that_reads_another_parts_settings(
        monkeypatch: pytest.MonkeyPatch, sequence: tuple[list[np.ndarray], Any]) -> None:
    """A motion model that peeks at a whole Params (as a part given the tracker's parameters
    could) is caught: the check above would fail on it."""
    params = wmiltrack.Params.for_variant("rcwmil", motion="velocity")
    reads: list[tuple[type[Any], str, Any]] = []

    def recorded(self: Any, name: str) -> Any:
        value = object.__getattribute__(self, name)
        if not name.startswith("_"):
            reads.append((type(self), name, _reader(sys._getframe(1))))
        return value

    class Peeking(VelocityMotion):
        def follow(self, previous: Any, box: Any, tracked: bool) -> None:
            super().follow(previous, box, tracked and params.num_features > 0)

    monkeypatch.setitem(OWNER, Peeking, MotionSettings)
    for cls in SETTINGS:
        monkeypatch.setattr(cls, "__getattribute__", recorded)
    frames, box = sequence
    t = wmiltrack.Tracker(params=params, parts={"motion": lambda s, f, b: Peeking(s)})
    t.track(frames[:3], box)
    monkeypatch.undo()
    assert (Params, "num_features", Peeking) in reads
    assert (MotionSettings, "motion_smoothing", Peeking) in reads


def test_recovery_constants_are_settings() -> None:
    """The re-detection's constants are RecoverySettings fields whose defaults are the values
    the module once hard-coded (the boxes do not change)."""
    s = wmiltrack.Params()
    assert (s.recover_memory, s.recover_warmup, s.recover_template_rate,
            s.recover_template_area, s.recover_search_area) == (0.9, 10, 0.05, 1600.0, 256.0)
    with pytest.raises(ValueError, match="recover_memory"):
        wmiltrack.Params(recover_memory=1.0)


def test_each_settings_class_lives_beside_its_part() -> None:
    """Every settings class ``Params`` is made of is defined in a part's own module (not in
    ``engine/settings.py``, which holds only what they share), is listed in that module's
    ``__all__``, and is exported by ``wmiltrack.engine`` as the same class."""
    import importlib

    import wmiltrack.engine as engine
    from wmiltrack.engine import settings as shared

    for cls in {*PARTS, AppearanceSettings}:
        module = importlib.import_module(cls.__module__)
        assert module is not shared, f"{cls.__name__} is in engine/settings.py"
        assert cls.__name__ in module.__all__, f"{cls.__name__} missing from {cls.__module__}.__all__"
        assert getattr(engine, cls.__name__) is cls and cls.__name__ in engine.__all__
    assert not [n for n in shared.__all__ if n.endswith("Settings")]
    assert engine.Params is Params
    with pytest.raises(AttributeError, match="NoSuchSettings"):
        engine.NoSuchSettings  # noqa: B018
