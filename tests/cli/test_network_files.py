"""The network trackers' model files as the user meets them: checked when a tracker is made
(not at its first frame), a tracker without them skipped with its reason by ``eval``,
``demo`` and ``fps_compare.py``, each tracker of an ``eval`` given its own files, and errors
that name what the user did."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import REPO_ROOT, write_generated_otb

from wmiltrack import Tracker, cli
from wmiltrack.compat import TrackerRCWMILNano
from wmiltrack.models import ModelFilesMissing
from wmiltrack.trackers import TrackerUnavailable, make_tracker

NANO_ENV = ("WMILTRACK_NANO_BACKBONE", "WMILTRACK_NANO_HEAD")


@pytest.fixture()
def no_models(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """An empty models folder and no model file in the environment."""
    for name in NANO_ENV:
        monkeypatch.delenv(name, raising=False)
    folder = tmp_path / "no-models"
    folder.mkdir()
    monkeypatch.setenv("WMILTRACK_MODELS", str(folder))
    return folder


@pytest.fixture()
def data(tmp_path: Path) -> Path:
    write_generated_otb(tmp_path / "data", "Seq", seed=3, n=8)
    return tmp_path / "data"


def test_a_preset_checks_its_model_files_when_it_is_made(no_models: Path, tmp_path: Path) -> None:
    with pytest.raises(ModelFilesMissing, match="nanotrack_backbone.onnx is not in"):
        Tracker("rcwmil-nano")
    with pytest.raises(ModelFilesMissing, match=r"backbone=/missing\.onnx is not a file"):
        Tracker("rcwmil-nano", backbone="/missing.onnx")
    with pytest.raises(ModelFilesMissing):
        TrackerRCWMILNano.create()
    with pytest.raises(TrackerUnavailable):  # what eval and demo skip
        make_tracker("rcwmil-nano")
    Tracker("rcwmil-cf")  # the presets without a network need no file


def test_eval_skips_every_tracker_without_its_files(no_models: Path, data: Path, tmp_path: Path,
                                                    capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "out"
    status = cli.main(["eval", str(data), "--trackers", "rcwmil-nano,nanotrack:v3,rcwmil",
                       "--out", str(out), "--no-plots", "--no-progress"])
    text = capsys.readouterr()
    assert status == 0, text.err
    table = (out / "eval_ope.md").read_text()
    for name in ("rcwmil-nano", "nanotrack:v3"):
        assert re.search(rf"^- skipped {name}: NanoTrack v3's model files are missing", table, re.M)
        assert f"| {name} |" not in table
    assert "| rcwmil |" in table and "failed" not in text.err


def test_demo_skips_a_tracker_without_its_files(no_models: Path,
                                                capsys: pytest.CaptureFixture[str]) -> None:
    status = cli.main(["demo", "--trackers", "rcwmil-nano,nanotrack:v2,rcwmil", "--frames", "12"])
    text = capsys.readouterr()
    assert status == 0
    assert re.search(r"^rcwmil-nano +skipped: NanoTrack v3's model files", text.out, re.M)
    assert re.search(r"^nanotrack:v2 +skipped: NanoTrack v2's model files", text.out, re.M)
    assert re.search(r"^rcwmil +\d\.\d{3}", text.out, re.M)
    assert "Warning" not in text.err and "warn(" not in text.err


def test_track_without_files_says_so_and_counts_no_frames(
        no_models: Path, data: Path, capsys: pytest.CaptureFixture[str]) -> None:
    for quiet in ([], ["-q"]):
        status = cli.main(["track", str(data / "Seq"), "-t", "rcwmil-nano", *quiet])
        err = capsys.readouterr().err
        assert status == 1
        assert err.startswith("wmiltrack: error: NanoTrack v3's model files are missing"), err
        assert "cannot write" not in err and "0 frames" not in err and len(err.splitlines()) == 1


def test_fps_compare_skips_a_tracker_without_its_files(no_models: Path) -> None:
    env = {k: v for k, v in os.environ.items() if k not in NANO_ENV}
    r = subprocess.run([sys.executable, str(REPO_ROOT / "benchmarks" / "fps_compare.py"), "--sizes",
                        "128x96", "--boxes", "24", "--frames", "6", "--repeats", "1",
                        "--trackers", "rcwmil-nano,nanotrack:v3,rcwmil"],
                       capture_output=True, text=True, timeout=120, check=False, cwd=REPO_ROOT,
                       env=dict(env, WMILTRACK_NO_PROGRESS="1"))
    assert r.returncode == 0, r.stderr
    assert "Traceback" not in r.stderr
    for name in ("rcwmil-nano", "nanotrack:v3"):
        assert re.search(rf"^note: {name} skipped \(NanoTrack v3's model files", r.stderr, re.M)
    assert re.search(r"^\| rcwmil \| \d+", r.stdout, re.M)
