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
from conftest import NANO_ENV, REPO_ROOT, write_generated_otb

from wmiltrack import Tracker, cli
from wmiltrack.compat import TrackerRCWMILNano
from wmiltrack.integrations.opencv_wheels import TrackerUnavailable
from wmiltrack.networks.files import ModelFilesMissing
from wmiltrack.trackers import make_tracker


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


# -- each tracker its own files -----------------------------------------------------------------
def test_labels_leave_the_model_files_out() -> None:
    from wmiltrack.trackers import tracker_labels

    specs = ["rcwmil-nano:backbone=/a/b.onnx:head=/a/h.onnx:like_low=0.4",
             "opencv:Nano:backbone=/m/x.onnx:neckhead=/m/y.onnx", "nanotrack:v2",
             "rcwmil-nano:backbone=/c/d.onnx", "rcwmil-nano:backbone=/e/d.onnx"]
    assert tracker_labels(specs) == {
        specs[0]: "rcwmil-nano:like_low=0.4", specs[1]: "opencv:Nano", specs[2]: "nanotrack:v2",
        specs[3]: specs[3], specs[4]: specs[4]}  # the same file names: the whole specs


def test_a_file_goes_to_the_trackers_of_its_version(
        nanotrack_models: dict[str, tuple[Path, Path]], no_models: Path, data: Path, tmp_path: Path,
        capsys: pytest.CaptureFixture[str]) -> None:
    """v2's files by option go to nanotrack:v2 only; rcwmil-nano (v3) takes its own by its spec;
    nanotrack:v3, given none, is skipped with its reason; labels and box folders are short."""
    (b2, h2), (b3, h3) = nanotrack_models["v2"], nanotrack_models["v3"]
    out = tmp_path / "out"
    status = cli.main(["eval", str(data), "--trackers",
                       f"rcwmil-nano:backbone={b3}:head={h3},nanotrack:v2,nanotrack:v3",
                       "--nano-backbone", str(b2), "--nano-head", str(h2), "--out", str(out),
                       "--no-progress"])
    text = capsys.readouterr()
    assert status == 0, text.err
    table = (out / "eval_ope.md").read_text()
    assert re.search(r"^\| \*\*mean \(1 seq\)\*\* \| rcwmil-nano \| 8 \|", table, re.M), table
    assert "| nanotrack:v2 |" in table and "- skipped nanotrack:v3: NanoTrack v3's" in table
    assert sorted(p.name for p in (out / "boxes").iterdir()) == ["nanotrack_v2", "rcwmil-nano"]
    assert (out / "eval_ope.json").is_file() and (out / "success_ope.png").is_file()


@pytest.mark.parametrize(("tracker", "fix"), [
    ("rcwmil-nano", "add --set network=nanotrack-v2"), ("nanotrack:v3", "use -t nanotrack:v2")])
def test_another_versions_file_names_the_fix(
        nanotrack_models: dict[str, tuple[Path, Path]], no_models: Path, data: Path, tracker: str,
        fix: str, capsys: pytest.CaptureFixture[str]) -> None:
    b2, h2 = nanotrack_models["v2"]
    status = cli.main(["track", str(data / "Seq"), "-t", tracker, "--nano-backbone", str(b2),
                       "--nano-head", str(h2), "-q"])
    err = capsys.readouterr().err
    assert status == 2 and len(err.splitlines()) == 1
    assert f"--nano-backbone {b2} is NanoTrack v2's backbone, but {tracker} runs NanoTrack v3" in err
    assert fix in err and "WMILTRACK_NANO" not in err


def test_v2_files_run_rcwmil_nano_with_its_network_set(
        nanotrack_models: dict[str, tuple[Path, Path]], no_models: Path, data: Path,
        capsys: pytest.CaptureFixture[str]) -> None:
    b2, h2 = nanotrack_models["v2"]
    status = cli.main(["track", str(data / "Seq"), "-t", "rcwmil-nano", "--set",
                       "network=nanotrack-v2", "--nano-backbone", str(b2), "--nano-head", str(h2), "-q"])
    assert status == 0 and len(capsys.readouterr().out.splitlines()) == 8


def test_python_names_the_network_that_fits(nanotrack_models: dict[str, tuple[Path, Path]],
                                            no_models: Path) -> None:
    b2, h2 = nanotrack_models["v2"]
    with pytest.raises(ModelFilesMissing, match="network='nanotrack-v2' for a preset"):
        Tracker("rcwmil-nano", backbone=str(b2), head=str(h2))


# -- no output touched before the tracker starts -------------------------------------------------
def test_track_video_example_leaves_an_existing_output(no_models: Path, tmp_path: Path) -> None:
    existing = tmp_path / "existing.mp4"
    existing.write_bytes(b"my video")
    env = {k: v for k, v in os.environ.items() if k not in NANO_ENV}
    r = subprocess.run([sys.executable, str(REPO_ROOT / "examples" / "track_video.py"), "-t",
                        "rcwmil-nano", "-o", str(existing)], capture_output=True, text=True,
                       timeout=120, check=False, cwd=tmp_path, env=env)
    assert r.returncode != 0 and "Traceback" not in r.stderr
    assert "NanoTrack v3's model files are missing" in r.stderr
    assert existing.read_bytes() == b"my video"


def test_eval_makes_no_output_folder_when_no_tracker_can_start(
        no_models: Path, data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "out"
    assert cli.main(["eval", str(data), "--trackers", "rcwmil-nano", "--out", str(out),
                     "--no-progress"]) == 1
    assert "no tracker left to run" in capsys.readouterr().err
    assert not out.exists()


# -- smaller points --------------------------------------------------------------------------------
def test_an_unknown_network_lists_the_choices() -> None:
    with pytest.raises(ValueError, match=r"network must be one of '', 'nanotrack-v2', 'nanotrack-v3'; "
                                         r"got 'nanotrack-v4'"):
        Tracker("rcwmil-nano", network="nanotrack-v4")


def test_rcwmil_nano_reports_plain_floats(nanotrack_models: dict[str, tuple[Path, Path]]) -> None:
    from wmiltrack.data.synthetic import make_sequence

    seq = make_sequence(4, seed=2)
    frames, gt = seq.load(), seq.groundtruth
    assert gt is not None
    b3, h3 = nanotrack_models["v3"]
    for tracker in (Tracker("rcwmil-nano", backbone=str(b3), head=str(h3)),
                    make_tracker("nanotrack:v3", backbone=str(b3), head=str(h3))):
        tracker.init(frames[0], gt[0])
        for frame in frames[1:]:
            box = tracker.update(frame).box
            assert all(type(v) is float for v in box), [type(v) for v in box]


def test_inspect_takes_the_model_options(nanotrack_models: dict[str, tuple[Path, Path]],
                                         no_models: Path, data: Path, tmp_path: Path) -> None:
    b3, h3 = nanotrack_models["v3"]
    out = tmp_path / "s.png"
    assert cli.main(["inspect", str(data / "Seq"), "-t", "rcwmil-nano", "--nano-backbone", str(b3),
                     "--nano-head", str(h3), "-o", str(out)]) == 0
    assert out.is_file()


def test_the_model_options_help_names_each_versions_files(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        cli.main(["eval", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    for name in ("nanotrack_backbone_sim.onnx", "nanotrack_backbone.onnx", "nanotrack_head_sim.onnx",
                 "nanotrack_head.onnx"):
        assert name in text
    assert not re.search(r"rcwmil-nano[^.;]*\(nanotrack_backbone_sim\.onnx\)", text)
    assert "nanotrack:v2 or nanotrack:v3" in text  # --trackers lists them


def test_nanotrack_is_named_where_trackers_are_listed(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(ValueError, match=r"nanotrack:v2 or nanotrack:v3"):
        make_tracker("nanotrak:v3")
    assert cli.main(["variants"]) == 0
    out = capsys.readouterr().out
    assert "nanotrack:v2, nanotrack:v3" in out
    rows = {line.split("|")[1].strip(): line.split("|")[2:] for line in out.splitlines()
            if line.startswith("| **")}
    assert rows["**rcwmil-nano**"] != rows["**rcwmil-cf**"]
    assert "NanoTrack v3's network" in rows["**rcwmil-nano**"][-2]
