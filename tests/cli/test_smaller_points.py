"""Smaller promises kept: demo names a tracker that cannot run and goes on, error messages say
what to do (TrackerNano's model files, a contrib tracker's install command, a video or image
name the writer cannot make), a sequence not in the dataset is a bad command line, the
multi-target example explains a lost object, fps_compare skips a peer it cannot run, and the
docs' commands and tables are what they show."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import REPO_ROOT, write_generated_otb

from wmiltrack import cli
from wmiltrack.integrations.opencv_wheels import TrackerUnavailable, available_opencv_trackers
from wmiltrack.networks.files import MODEL_ENV
from wmiltrack.trackers import make_tracker


@pytest.fixture()
def no_nano_files(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    """No model file in the environment, and an empty models folder (opencv:Nano looks there)."""
    for attrs in MODEL_ENV.values():
        for env in attrs.values():
            monkeypatch.delenv(env, raising=False)
    (tmp_path / "empty models").mkdir()
    monkeypatch.setenv("WMILTRACK_MODELS", str(tmp_path / "empty models"))


@pytest.fixture()
def data(tmp_path: Path) -> Path:
    write_generated_otb(tmp_path / "data", "Seq", seed=3, n=8)
    return tmp_path / "data"


def test_demo_names_a_tracker_that_cannot_run_and_runs_the_others(
        no_nano_files: None, capsys: pytest.CaptureFixture[str]) -> None:
    trackers = ["opencv:Nano", "rcwmil"]
    if "CSRT" not in available_opencv_trackers():
        trackers.append("opencv:CSRT")
    status = cli.main(["demo", "--trackers", ",".join(trackers), "--frames", "20"])
    out = capsys.readouterr().out
    assert status == 0
    assert re.search(r"^opencv:Nano +skipped: .*--nano-backbone", out, re.M)
    assert re.search(r"^rcwmil +\d\.\d{3}", out, re.M)
    if "opencv:CSRT" in trackers:  # the plain wheel: the row says how to get it
        assert re.search(r"^opencv:CSRT +skipped: ", out, re.M) and "pip install" in out


def test_nano_names_both_missing_files_and_their_options(no_nano_files: None) -> None:
    with pytest.raises(TrackerUnavailable) as err:
        make_tracker("opencv:Nano")
    text = str(err.value)
    for part in ("--nano-backbone", "--nano-head", "nanotrack_backbone_sim.onnx",
                 "nanotrack_head_sim.onnx", "WMILTRACK_NANO_BACKBONE", "WMILTRACK_NANO_HEAD"):
        assert part in text


def test_eval_skip_note_keeps_the_whole_reason(no_nano_files: None, data: Path, tmp_path: Path,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    trackers = ["rcwmil", "opencv:Nano"]
    if "CSRT" not in available_opencv_trackers():
        trackers.append("opencv:CSRT")
    assert cli.main(["eval", str(data), "--trackers", ",".join(trackers), "--out",
                     str(tmp_path / "o"), "--no-progress", "--no-plots"]) == 0
    table = (tmp_path / "o" / "eval_ope.md").read_text()
    note = next(line for line in table.splitlines() if line.startswith("- skipped opencv:Nano"))
    assert "--nano-backbone" in note and "--nano-head" in note
    if "opencv:CSRT" in trackers:
        note = next(line for line in table.splitlines() if line.startswith("- skipped opencv:CSRT"))
        assert "pip install" in note and "opencv-contrib-python" in note


def test_a_video_name_the_writer_cannot_make_is_refused_first(
        data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "boxes.txt"
    status = cli.main(["track", str(data / "Seq"), "-o", str(out), "--video", str(tmp_path / "v.xyz")])
    err = capsys.readouterr().err
    assert status == 2 and ".avi" in err and ".mp4" in err
    assert not out.exists()


def test_inspect_output_opencv_cannot_write_is_a_usage_error(
        data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    status = cli.main(["inspect", str(data / "Seq"), "-o", str(tmp_path / "x.txt")])
    err = capsys.readouterr().err
    assert status == 2 and ".png" in err and "OpenCV:" not in err
    assert not (tmp_path / "x.txt").exists()


def test_eval_of_a_sequence_not_in_the_dataset_is_a_bad_command_line(
        data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    status = cli.main(["eval", str(data), "--sequences", "NoSuch", "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert status == 2 and "NoSuch" in err and "Seq" in err


def test_multi_target_example_explains_a_lost_object(tmp_path: Path) -> None:
    done = subprocess.run([sys.executable, str(REPO_ROOT / "examples" / "multi_target.py"), "-o",
                           str(tmp_path / "t.mp4")], capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    rows = [line for line in done.stdout.splitlines() if "mean overlap" in line]
    assert len(rows) == 4
    for row in rows:
        overlap = float(re.search(r"mean overlap (\d\.\d\d)", row).group(1))  # type: ignore[union-attr]
        assert (overlap < 0.5) == ("lost;" in row), row


def test_fps_compare_skips_a_peer_it_cannot_run(no_nano_files: None) -> None:
    env = {k: v for k, v in os.environ.items() if not k.startswith("WMILTRACK_NANO")}
    done = subprocess.run([sys.executable, str(REPO_ROOT / "benchmarks" / "fps_compare.py"), "--quick",
                           "--trackers", "rcwmil,opencv:Nano", "--frames", "3", "--repeats", "1",
                           "--sizes", "160x120", "--boxes", "32"],
                          capture_output=True, text=True, check=False, env=env)
    assert done.returncode == 0, done.stderr
    assert "Traceback" not in done.stderr
    assert "opencv:Nano skipped" in done.stderr and "--nano-backbone" in done.stderr


def markdown_pages() -> list[Path]:
    return [REPO_ROOT / "README.md", *sorted((REPO_ROOT / "docs").glob("*.md"))]


@pytest.mark.parametrize("page", markdown_pages(), ids=lambda p: p.name)
def test_no_escaped_pipe_shows_in_a_table(page: Path) -> None:
    """Inside a code span of a table cell, ``\\|`` is shown as is by the site's renderer."""
    assert "\\|" not in page.read_text(encoding="utf-8")


def test_the_contrib_swap_command_uses_the_wheels_version_and_checks_first() -> None:
    text = (REPO_ROOT / "docs" / "integrations.md").read_text(encoding="utf-8")
    block = text.split("### OpenCV's other trackers", 1)[1].split("```bash", 1)[1].split("```", 1)[0]
    version_line = next(line for line in block.splitlines() if line.startswith("V=$("))
    code = re.search(r"python -c '(.*)'\)", version_line).group(1)  # type: ignore[union-attr]
    got = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip()
    from importlib.metadata import version

    assert got == version("opencv-python-headless")  # 5.0.0.93, a version the wheel has
    assert block.index("--dry-run") < block.index("pip uninstall")


def test_the_home_page_caption_quotes_its_figures_own_run() -> None:
    """The home page's accuracy-speed figure is the headline run's: its caption gives
    rcwmil-cf's AUC of that run (the one the figure plots), and says the README's is another."""
    perf = (REPO_ROOT / "docs" / "performance.md").read_text(encoding="utf-8")
    headline = perf.split("## Accuracy and speed in one run", 1)[1].split("\n## ", 1)[0]
    row = next(line for line in headline.splitlines() if line.startswith("| rcwmil-cf |"))
    auc = row.split("|")[2].split("±")[0].strip()
    index = (REPO_ROOT / "docs" / "index.md").read_text(encoding="utf-8")
    assert "accuracy_speed_otb17.png" in index and "accuracy_speed_otb17.png" in headline
    assert f"rcwmil-cf is at {auc} there" in index
    assert "42 sequences" in index
