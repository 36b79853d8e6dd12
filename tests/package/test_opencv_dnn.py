"""OpenCV's neural-network trackers, ``opencv:Nano`` and ``opencv:Vit``: their model files come
from spec parameters, from ``--nano-backbone``/``--nano-head``/``--vit-model`` or from the
``WMILTRACK_*`` environment variables, and a missing file is a clear error. The plumbing is
tested with a stand-in for OpenCV's factory; the real models run only where the variables name
them (they are not part of the project)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import cv2
import numpy as np
import pytest

from wmiltrack.cli import main
from wmiltrack.integrations.opencv_peers import OpenCVTracker
from wmiltrack.integrations.opencv_wheels import TrackerUnavailable
from wmiltrack.networks.files import MODEL_ENV
from wmiltrack.trackers import make_tracker

NANO_ENV = MODEL_ENV["Nano"]


@pytest.fixture(autouse=True)
def no_model_env(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    """No model file in the environment, and an empty models folder."""
    for attrs in MODEL_ENV.values():
        for env in attrs.values():
            monkeypatch.delenv(env, raising=False)
    (tmp_path / "empty models").mkdir()
    monkeypatch.setenv("WMILTRACK_MODELS", str(tmp_path / "empty models"))


class FakeNano:
    """Records what OpenCV's tracker would get."""

    made: list[Any] = []

    def __init__(self, params: Any) -> None:
        self.params = params
        self.frames: list[tuple[int, ...]] = []
        FakeNano.made.append(self)

    def init(self, img: np.ndarray, box: tuple[int, int, int, int]) -> None:
        self.frames.append(img.shape)
        self.box = box

    def update(self, img: np.ndarray) -> tuple[bool, tuple[int, int, int, int]]:
        self.frames.append(img.shape)
        return True, self.box

    def getTrackingScore(self) -> float:  # noqa: N802 (OpenCV's name)
        return 0.75


@pytest.fixture()
def fake_nano(monkeypatch: pytest.MonkeyPatch) -> type[FakeNano]:
    FakeNano.made = []
    monkeypatch.setattr(cv2, "TrackerNano_create", FakeNano, raising=False)
    return FakeNano


def model_files(tmp_path: Path) -> tuple[Path, Path]:
    backbone, head = tmp_path / "backbone.onnx", tmp_path / "head.onnx"
    backbone.write_bytes(b"not read by the stand-in")
    head.write_bytes(b"not read by the stand-in")
    return backbone, head


def test_without_model_files_the_error_names_the_option_and_the_variable() -> None:
    with pytest.raises(TrackerUnavailable, match="WMILTRACK_NANO_BACKBONE") as info:
        make_tracker("opencv:Nano")
    assert "opencv:Nano:backbone=FILE" in str(info.value)
    with pytest.raises(TrackerUnavailable, match="WMILTRACK_VIT_MODEL"):
        make_tracker("opencv:Vit")


def test_a_model_path_that_is_not_a_file_is_named(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    backbone, _ = model_files(tmp_path)
    with pytest.raises(TrackerUnavailable, match="missing_head.onnx is not a file"):
        make_tracker(f"opencv:Nano:backbone={backbone}:neckhead={tmp_path / 'missing_head.onnx'}")
    monkeypatch.setenv(NANO_ENV["backbone"], str(backbone))
    monkeypatch.setenv(NANO_ENV["neckhead"], str(tmp_path / "nope.onnx"))
    with pytest.raises(TrackerUnavailable, match="WMILTRACK_NANO_HEAD=.*nope.onnx is not a file"):
        make_tracker("opencv:Nano")


@pytest.mark.parametrize("source", ["spec", "environment"])
def test_model_paths_reach_opencv(fake_nano: type[FakeNano], tmp_path: Path, source: str,
                                  monkeypatch: pytest.MonkeyPatch) -> None:
    backbone, head = model_files(tmp_path)
    if source == "spec":
        t = make_tracker(f"opencv:Nano:backbone={backbone}:neckhead={head}")
    else:
        monkeypatch.setenv(NANO_ENV["backbone"], str(backbone))
        monkeypatch.setenv(NANO_ENV["neckhead"], str(head))
        t = make_tracker("opencv:Nano")
    gray = np.zeros((60, 80), np.uint8)
    t.init(gray, (10, 10, 20, 20))
    r = t.update(gray)
    made = fake_nano.made[-1]
    assert (made.params.backbone, made.params.neckhead) == (str(backbone), str(head))
    assert made.frames == [(60, 80, 3), (60, 80, 3)]  # gray frames given as 3 channels
    assert r.ok and r.box == (10.0, 10.0, 20.0, 20.0) and r.score == 0.75  # OpenCV's own score


def test_nano_finds_nanotrack_v2_in_the_models_folder_and_refuses_v3(
        fake_nano: type[FakeNano], tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        nanotrack_models: dict[str, tuple[Path, Path]]) -> None:
    """opencv:Nano finds its files as every network does: in the models folder, where
    ``wmiltrack models fetch nanotrack-v2`` puts them; a file of NanoTrack v3 given for it is
    refused by its SHA-1, with the fetch command when none is there."""
    with pytest.raises(TrackerUnavailable, match="wmiltrack models fetch nanotrack-v2"):
        make_tracker("opencv:Nano")
    folder = tmp_path / "models" / "nanotrack-v2"
    folder.mkdir(parents=True)
    for f in nanotrack_models["v2"]:
        (folder / f.name).symlink_to(f)
    monkeypatch.setenv("WMILTRACK_MODELS", str(tmp_path / "models"))
    make_tracker("opencv:Nano").init(np.zeros((60, 80), np.uint8), (10, 10, 20, 20))
    made = fake_nano.made[-1]
    assert (made.params.backbone, made.params.neckhead) == tuple(str(folder / f.name)
                                                                 for f in nanotrack_models["v2"])
    with pytest.raises(TrackerUnavailable, match="neckhead=.* is NanoTrack v3's head, not NanoTrack v2's"):
        make_tracker(f"opencv:Nano:neckhead={nanotrack_models['v3'][1]}")


def test_track_takes_the_model_options(fake_nano: type[FakeNano], tmp_path: Path,
                                       capsys: pytest.CaptureFixture[str]) -> None:
    from conftest import write_generated_otb

    write_generated_otb(tmp_path, "Seq", seed=1, n=5)
    backbone, head = model_files(tmp_path)
    seq = str(tmp_path / "Seq")
    assert main(["track", seq, "-t", "opencv:Nano", "-q"]) == 1  # not given: runtime failure
    assert "WMILTRACK_NANO_BACKBONE" in capsys.readouterr().err
    assert main(["track", seq, "-t", "opencv:Nano", "--nano-backbone", str(tmp_path / "x.onnx"),
                 "--nano-head", str(head)]) == 2  # a path that is not a file: bad command line
    assert "--nano-backbone" in capsys.readouterr().err
    assert main(["track", seq, "-t", "opencv:Nano", "--nano-backbone", str(backbone),
                 "--nano-head", str(head), "-q"]) == 0
    assert len(capsys.readouterr().out.splitlines()) == 5
    assert fake_nano.made[-1].params.backbone == str(backbone.resolve())


def test_eval_skips_nano_without_models_with_a_note(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from conftest import write_generated_otb

    write_generated_otb(tmp_path / "data", "Seq", seed=1, n=6)
    rc = main(["eval", str(tmp_path / "data"), "--trackers", "rcwmil,opencv:Nano", "--out",
               str(tmp_path / "out"), "--no-progress", "--no-plots"])
    captured = capsys.readouterr()
    assert rc == 0
    assert "skipped opencv:Nano: opencv:Nano needs 2 model file(s)" in captured.err
    assert "--nano-backbone" in captured.err and "--nano-head" in captured.err


def test_real_nano_follows_a_generated_target(nanotrack_models: dict[str, tuple[Path, Path]]) -> None:
    """OpenCV's TrackerNano on NanoTrack v2's real files (conftest's ``nanotrack_models``:
    skipped without them, a failure under CI) follows a generated target."""
    from wmiltrack.data.synthetic import make_sequence
    from wmiltrack.eval.metrics import iou

    backbone, head = (str(p) for p in nanotrack_models["v2"])
    seq = make_sequence(20, size=(240, 320), target_size=(48, 40), seed=2, occlusion=False)
    frames, gt = seq.load(), np.asarray(seq.groundtruth)
    t = OpenCVTracker("Nano", backbone=backbone, neckhead=head)
    t.init(frames[0], gt[0])
    boxes = [t.update(f).box for f in frames[1:]]
    assert float(np.mean(iou(np.asarray(boxes), gt[1:]))) > 0.3
