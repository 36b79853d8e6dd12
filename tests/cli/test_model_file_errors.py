"""The bad-input matrix's model-file cases: a model file that is corrupt, truncated, empty,
another role's, another version's, missing, or a folder is one line naming the file, its role
and the fix, in Python (a :class:`ModelFilesMissing`, so a tracker that cannot start) and from
every command (``track``, ``inspect``: exit status 1 or 2 and no traceback; ``eval``, ``demo``:
the tracker skipped with that line), whichever runtime reads it. And onnxruntime installed
without ``onnx`` (what ``pip install onnxruntime`` gives) runs the networks on OpenCV's dnn
after one note.

The right-shaped files are the stand-in networks (``stand_in_networks.py``); the wrong-version
case needs NanoTrack's real files (skipped without them)."""

from __future__ import annotations

import logging
import os
import re
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest
from conftest import write_generated_otb

from wmiltrack import Tracker, cli
from wmiltrack.integrations.opencv_wheels import TrackerUnavailable
from wmiltrack.networks import backends
from wmiltrack.networks.files import ModelFilesMissing, ModelFileUnreadable
from wmiltrack.networks.nanotrack import NanoNetwork
from wmiltrack.trackers import make_tracker

#: Both runtimes; onnxruntime's cases need the nano extra (skipped without it, a failure
#: under WMILTRACK_REQUIRE_EXTRAS, where .ci/run installs it).
RUNTIMES = (pytest.param("onnxruntime", marks=pytest.mark.extras("onnxruntime", "onnx")), "opencv")


def _corrupt(right: Path, to: Path) -> Path:
    to.write_bytes(bytes(range(256)) * 8)
    return to


def _truncated(right: Path, to: Path) -> Path:
    to.write_bytes(right.read_bytes()[: right.stat().st_size // 2])
    return to


def _empty(right: Path, to: Path) -> Path:
    to.write_bytes(b"")
    return to


def _folder(right: Path, to: Path) -> Path:
    to.mkdir()
    return to


def _missing(right: Path, to: Path) -> Path:
    return to


#: Each case: how to make the bad backbone from the right one, and what the line says is wrong.
BAD_BACKBONES: dict[str, tuple[Callable[[Path, Path], Path], str]] = {
    "corrupt": (_corrupt, "cannot read it as an ONNX network"),
    "truncated": (_truncated, "cannot read it as an ONNX network"),
    "empty": (_empty, "it is empty"),
    "folder": (_folder, "is not a file"),
    "missing": (_missing, "is not a file"),
}
#: The fix each line gives: another file by its option, or the set fetched again.
FIX = re.compile(r"--nano-backbone|wmiltrack models fetch nanotrack-v3")


@pytest.fixture()
def data(tmp_path: Path) -> Path:
    write_generated_otb(tmp_path / "data", "Seq", seed=3, n=6)
    return tmp_path / "data"


def bad_backbone(case: str, stand_in_networks: dict[str, tuple[Path, Path]], folder: Path) -> Path:
    """The backbone of ``case``: made from the stand-in's, or the stand-in head (wrong role)."""
    if case == "wrong role":
        return stand_in_networks["v3"][1]
    make, _ = BAD_BACKBONES[case]
    return make(stand_in_networks["v3"][0], folder / f"{case.replace(' ', '_')}.onnx")


def reason(case: str) -> str:
    return "where a backbone gives output" if case == "wrong role" else BAD_BACKBONES[case][1]


CASES = [*BAD_BACKBONES, "wrong role"]


def one_line(err: str, path: Path, case: str) -> None:
    """``err`` is one line naming ``path``, the backbone, what is wrong and the fix."""
    assert len(err.strip().splitlines()) == 1, err
    assert "Traceback" not in err and str(path) in err and "backbone" in err, err
    assert reason(case) in err and FIX.search(err), err


@pytest.mark.parametrize("runtime", RUNTIMES)
@pytest.mark.parametrize("case", CASES)
def test_python_says_it_when_the_tracker_is_made(
        case: str, runtime: str, stand_in_networks: dict[str, tuple[Path, Path]], no_models: Path,
        tmp_path: Path) -> None:
    backbone, head = bad_backbone(case, stand_in_networks, tmp_path), stand_in_networks["v3"][1]
    makers = [lambda: Tracker("rcwmil-nano", backbone=str(backbone), head=str(head),
                              network_runtime=runtime),
              lambda: make_tracker("nanotrack:v3", backbone=str(backbone), head=str(head),
                                   runtime=runtime)]
    for make in makers:
        with pytest.raises(ModelFilesMissing) as info:  # a TrackerUnavailable: eval skips it
            make()
        assert isinstance(info.value, TrackerUnavailable)
        message = str(info.value)
        assert str(backbone) in message and reason(case) in message, message
    if case not in ("missing", "folder"):  # the lookup has no say: the file is loaded as given
        with pytest.raises(ModelFileUnreadable, match=re.escape(str(backbone))):
            NanoNetwork(backbone, head, runtime, version="v3")


@pytest.mark.parametrize("runtime", RUNTIMES)
@pytest.mark.parametrize("case", CASES)
@pytest.mark.parametrize("command", ["track", "inspect"])
def test_track_and_inspect_say_it_in_one_line(
        command: str, case: str, runtime: str, stand_in_networks: dict[str, tuple[Path, Path]],
        no_models: Path, data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    backbone, head = bad_backbone(case, stand_in_networks, tmp_path), stand_in_networks["v3"][1]
    out = tmp_path / ("out.txt" if command == "track" else "out.png")
    status = cli.main([command, str(data / "Seq"), "-t", "rcwmil-nano", "--set",
                       f"network_runtime={runtime}", "--nano-backbone", str(backbone),
                       "--nano-head", str(head), "-o", str(out)])
    err = capsys.readouterr().err
    assert status in (1, 2)
    one_line(err, backbone, case)
    assert not out.exists()


@pytest.mark.parametrize("case", CASES)
def test_eval_skips_the_tracker_with_the_line(
        case: str, stand_in_networks: dict[str, tuple[Path, Path]], no_models: Path, data: Path,
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    backbone, head = bad_backbone(case, stand_in_networks, tmp_path), stand_in_networks["v3"][1]
    specs = [f"rcwmil-nano:backbone={backbone}:head={head}:network_runtime=opencv",
             f"nanotrack:v3:backbone={backbone}:head={head}:runtime=opencv", "rcwmil"]
    out = tmp_path / "out"
    status = cli.main(["eval", str(data), "--trackers", ",".join(specs), "--out", str(out),
                       "--no-plots", "--no-progress"])
    text = capsys.readouterr()
    assert status == 0, text.err
    assert "Traceback" not in text.err and "failed" not in text.err
    table = (out / "eval_ope.md").read_text()
    skipped = [line for line in table.splitlines() if line.startswith("- skipped ")]
    assert len(skipped) == 2, table
    for line in skipped:
        assert str(backbone) in line and reason(case) in line and FIX.search(line), line
    assert "| rcwmil |" in table


@pytest.mark.parametrize("case", ["corrupt", "wrong role"])
def test_demo_skips_the_tracker_with_the_line(
        case: str, stand_in_networks: dict[str, tuple[Path, Path]], no_models: Path,
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    backbone = bad_backbone(case, stand_in_networks, tmp_path)
    monkeypatch.setenv("WMILTRACK_NANO_BACKBONE", str(backbone))
    monkeypatch.setenv("WMILTRACK_NANO_HEAD", str(stand_in_networks["v3"][1]))
    status = cli.main(["demo", "--trackers", "rcwmil-nano,rcwmil", "--frames", "8"])
    text = capsys.readouterr()
    assert status == 0 and "Traceback" not in text.err
    line = next(x for x in text.out.splitlines() if x.startswith("rcwmil-nano"))
    assert re.match(r"rcwmil-nano +skipped: NanoTrack v3's backbone", line), line
    assert str(backbone) in line and reason(case) in line


@pytest.mark.parametrize("tracker", ["rcwmil-nano", "nanotrack:v3"])
def test_another_versions_file_is_one_line(
        tracker: str, nanotrack_models: dict[str, tuple[Path, Path]], no_models: Path, data: Path,
        capsys: pytest.CaptureFixture[str]) -> None:
    b2 = nanotrack_models["v2"][0]
    status = cli.main(["track", str(data / "Seq"), "-t", tracker, "--nano-backbone", str(b2),
                       "--nano-head", str(nanotrack_models["v3"][1]), "-q"])
    err = capsys.readouterr().err
    assert status in (1, 2) and len(err.splitlines()) == 1 and "Traceback" not in err
    assert str(b2) in err and "NanoTrack v2's backbone" in err and "nanotrack-v2" in err.replace(
        "nanotrack:v2", "nanotrack-v2")


# -- onnxruntime without onnx ----------------------------------------------------------------------
@pytest.fixture()
def onnx_hidden(monkeypatch: pytest.MonkeyPatch) -> None:
    """``onnx`` not importable (as after ``pip install onnxruntime``), the note not yet said."""
    monkeypatch.setitem(sys.modules, "onnx", None)
    monkeypatch.setattr(backends, "_NOTED", set())


@pytest.mark.extras("onnxruntime")
def test_without_onnx_auto_runs_on_opencv_after_one_note(
        stand_in_networks: dict[str, tuple[Path, Path]], onnx_hidden: None,
        caplog: pytest.LogCaptureFixture) -> None:
    files = stand_in_networks["v3"]
    with caplog.at_level(logging.WARNING, logger="wmiltrack"):
        networks = [NanoNetwork(*files, "auto", version="v3") for _ in range(2)]
        tracker = Tracker("rcwmil-nano", backbone=str(files[0]), head=str(files[1]))
    assert [n.runtime for n in networks] == ["opencv", "opencv"]
    assert tracker is not None
    notes = [r.getMessage() for r in caplog.records if r.name == "wmiltrack"]
    assert len(notes) == 1 and "without the onnx package" in notes[0], notes
    assert "OpenCV's dnn" in notes[0] and "pip install onnx" in notes[0]


@pytest.mark.extras("onnxruntime")
def test_without_onnx_asking_for_onnxruntime_says_what_to_install(
        stand_in_networks: dict[str, tuple[Path, Path]], onnx_hidden: None, no_models: Path) -> None:
    files = stand_in_networks["v3"]
    with pytest.raises(TrackerUnavailable, match=r"needs the onnx package.*pip install onnx"):
        NanoNetwork(*files, "onnxruntime", version="v3")
    with pytest.raises(TrackerUnavailable, match="network_runtime=opencv"):
        Tracker("rcwmil-nano", backbone=str(files[0]), head=str(files[1]),
                network_runtime="onnxruntime")


@pytest.mark.extras("onnxruntime")
def test_without_onnx_the_command_line_tracks_after_one_note(
        stand_in_networks: dict[str, tuple[Path, Path]], no_models: Path, data: Path) -> None:
    files = stand_in_networks["v3"]
    code = ("import sys; sys.modules['onnx'] = None; from wmiltrack.cli import main; "
            "sys.exit(main(sys.argv[1:]))")
    env = dict(os.environ, WMILTRACK_NANO_BACKBONE=str(files[0]), WMILTRACK_NANO_HEAD=str(files[1]))
    r = subprocess.run([sys.executable, "-c", code, "track", str(data / "Seq"), "-t", "rcwmil-nano",
                        "-q"], capture_output=True, text=True, timeout=120, check=False, env=env)
    assert r.returncode == 0, r.stderr
    assert len(r.stdout.splitlines()) == 6
    assert len(r.stderr.splitlines()) == 1 and "without the onnx package" in r.stderr, r.stderr


def test_asking_for_onnxruntime_where_it_is_not_installed_says_what_to_install(
        stand_in_networks: dict[str, tuple[Path, Path]], no_models: Path,
        monkeypatch: pytest.MonkeyPatch) -> None:
    """``network_runtime=onnxruntime`` without onnxruntime: one line naming the package and the
    other runtime, when the tracker is made (was a ModuleNotFoundError traceback)."""
    monkeypatch.setitem(sys.modules, "onnxruntime", None)
    files = stand_in_networks["v3"]
    with pytest.raises(TrackerUnavailable, match=r"onnxruntime is not installed.*pip install onnxruntime") as info:
        Tracker("rcwmil-nano", backbone=str(files[0]), head=str(files[1]), network_runtime="onnxruntime")
    assert "network_runtime=opencv" in str(info.value) and "\n" not in str(info.value)
    with pytest.raises(TrackerUnavailable, match="not installed"):
        make_tracker("nanotrack:v3", backbone=str(files[0]), head=str(files[1]), runtime="onnxruntime")


# -- which runtime ran ---------------------------------------------------------------------------
def test_eval_records_the_runtime_of_each_network_tracker(
        stand_in_networks: dict[str, tuple[Path, Path]], no_models: Path, data: Path,
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    import json

    import cv2

    backbone, head = stand_in_networks["v3"]
    files = f"backbone={backbone}:head={head}"
    specs = [f"rcwmil-nano:{files}:network_runtime=opencv", f"nanotrack:v3:{files}", "rcwmil"]
    out = tmp_path / "out"
    assert cli.main(["eval", str(data), "--trackers", ",".join(specs), "--out", str(out),
                     "--no-plots", "--no-progress"]) == 0, capsys.readouterr().err
    doc = json.loads((out / "eval_ope.json").read_text())
    auto = backends.choose_runtime("auto")
    version = {"opencv": cv2.__version__}.get(auto) or __import__("onnxruntime").__version__
    assert doc["runtimes"] == {
        "rcwmil-nano:network_runtime=opencv": {"runtime": "opencv", "version": cv2.__version__},
        "nanotrack:v3": {"runtime": auto, "version": version}}


def test_variants_says_which_runtime_would_run(capsys: pytest.CaptureFixture[str],
                                               monkeypatch: pytest.MonkeyPatch) -> None:
    assert cli.main(["variants"]) == 0
    out = " ".join(capsys.readouterr().out.split())
    name = {"onnxruntime": "onnxruntime", "opencv": "OpenCV's dnn"}[backends.choose_runtime("auto")]
    assert f"The networks (rcwmil-nano, nanotrack:VERSION) run on {name} " in out
    assert "same for the same runtime and version only" in out
    monkeypatch.setitem(sys.modules, "onnxruntime", None)  # not installed: OpenCV's dnn
    assert cli.main(["variants"]) == 0
    assert "run on OpenCV's dnn" in " ".join(capsys.readouterr().out.split())
