"""Two OpenCV wheels installed together (wmiltrack.opencv_check), on faked distribution lists."""

from __future__ import annotations

import os
import subprocess
import sys
import warnings
from importlib import metadata
from pathlib import Path

import pytest

from wmiltrack import opencv_check
from wmiltrack.opencv_check import (
    OpenCVConflictWarning,
    installed_opencv_distributions,
    opencv_conflict_message,
    warn_if_opencv_conflict,
)


def _fake_installed(monkeypatch: pytest.MonkeyPatch, names: set[str]) -> None:
    """Make importlib.metadata report exactly ``names`` among the OpenCV wheels installed."""
    real = metadata.version

    def version(name: str) -> str:
        if name in opencv_check.OPENCV_DISTRIBUTIONS:
            if name in names:
                return "4.10.0.84"
            raise metadata.PackageNotFoundError(name)
        return real(name)

    monkeypatch.setattr(metadata, "version", version)


@pytest.mark.parametrize(
    ("installed", "keep"),
    [
        (["opencv-python", "opencv-python-headless"], "opencv-python"),
        (["opencv-python-headless", "opencv-contrib-python"], "opencv-contrib-python"),
        (["opencv-python-headless", "opencv-contrib-python-headless"], "opencv-contrib-python-headless"),
        (["opencv-python", "opencv-contrib-python-headless"], "opencv-contrib-python"),
        (list(opencv_check.OPENCV_DISTRIBUTIONS), "opencv-contrib-python"),
    ],
)
def test_conflict_is_detected_and_the_fix_is_one_line(
    monkeypatch: pytest.MonkeyPatch, installed: list[str], keep: str
) -> None:
    _fake_installed(monkeypatch, set(installed))
    assert installed_opencv_distributions() == [n for n in opencv_check.OPENCV_DISTRIBUTIONS if n in installed]
    with pytest.warns(OpenCVConflictWarning) as record:
        message = warn_if_opencv_conflict()
    assert len(record) == 1 and str(record[0].message) == message
    assert message is not None and "\n" not in message
    fix = message.split("fix: ", 1)[1]
    # every installed wheel is removed, then the one that covers them all is installed
    # ... at the installed version, so that the fix does not upgrade OpenCV too
    assert fix == f"pip uninstall -y {' '.join(installed_opencv_distributions())} && pip install {keep}==4.10.0.84"
    assert record[0].filename == __file__  # points at the caller, not at wmiltrack's internals


@pytest.mark.parametrize("installed", [set(), {"opencv-python-headless"}, {"opencv-contrib-python"}])
def test_one_opencv_wheel_warns_nothing(monkeypatch: pytest.MonkeyPatch, installed: set[str]) -> None:
    _fake_installed(monkeypatch, installed)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # as the test suite's filterwarnings=error
        assert warn_if_opencv_conflict() is None
    assert opencv_conflict_message(sorted(installed)) is None


def test_this_environment_imports_cleanly_and_a_second_wheel_is_reported(tmp_path: Path) -> None:
    """End to end in fresh interpreters: ``import wmiltrack`` with warnings as errors passes here
    (one OpenCV wheel), and warns once a second wheel's metadata is on the path (a fake
    ``opencv_python-*.dist-info`` folder: nothing is installed)."""
    installed = installed_opencv_distributions()
    assert len(installed) == 1, f"the test environment itself has {installed}"
    env = {**os.environ, "PYTHONWARNINGS": "error"}
    clean = subprocess.run([sys.executable, "-c", "import wmiltrack"], capture_output=True, text=True, env=env)
    assert clean.returncode == 0, clean.stderr

    extra = "opencv-contrib-python" if installed[0] != "opencv-contrib-python" else "opencv-python"
    info = tmp_path / f"{extra.replace('-', '_')}-4.10.0.84.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {extra}\nVersion: 4.10.0.84\n")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(tmp_path), os.environ.get("PYTHONPATH", "")])}
    env.pop("PYTHONWARNINGS", None)
    run = subprocess.run([sys.executable, "-c", "import wmiltrack"], capture_output=True, text=True, env=env)
    assert run.returncode == 0, run.stderr
    assert "OpenCVConflictWarning" in run.stderr
    assert f"fix: pip uninstall -y {' '.join(sorted([installed[0], extra], key=opencv_check.OPENCV_DISTRIBUTIONS.index))}" in run.stderr


def test_the_fix_pins_the_kept_wheel_or_its_kind() -> None:
    names = ["opencv-python-headless", "opencv-contrib-python-headless"]
    msg = opencv_conflict_message(names, {"opencv-python-headless": "5.0.0.93",
                                          "opencv-contrib-python-headless": "4.12.0.88"})
    assert msg is not None and msg.endswith("pip install opencv-contrib-python-headless==4.12.0.88")
    msg = opencv_conflict_message(["opencv-python", "opencv-contrib-python-headless"],
                                  {"opencv-python": "5.0.0.93", "opencv-contrib-python-headless": "5.0.0.93"})
    assert msg is not None and msg.endswith("pip install opencv-contrib-python==5.0.0.93")
    assert opencv_conflict_message(names) is not None  # no versions known: no pin


def test_every_command_shows_the_conflict_as_one_line(tmp_path: Path) -> None:
    """``wmiltrack --help`` (and every other command) printed the warning and then the line of
    wmiltrack's code that raised it; now it is one line, with a pinned fix."""
    installed = installed_opencv_distributions()
    extra = "opencv-contrib-python-headless" if "contrib" not in installed[0] else "opencv-python"
    info = tmp_path / f"{extra.replace('-', '_')}-4.10.0.84.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {extra}\nVersion: 4.10.0.84\n")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(tmp_path), os.environ.get("PYTHONPATH", "")])}
    env.pop("PYTHONWARNINGS", None)
    for args in (["--help"], ["variants", "--json"]):
        run = subprocess.run([sys.executable, "-m", "wmiltrack", *args], capture_output=True, text=True, env=env)
        assert run.returncode == 0, run.stderr
        lines = run.stderr.splitlines()
        assert len(lines) == 1 and "OpenCVConflictWarning" in lines[0], run.stderr
        assert "warn_" not in run.stderr and "==" in lines[0].split("fix: ")[1]
