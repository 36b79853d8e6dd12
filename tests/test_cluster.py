"""Tracker spec overrides, the Dask executor, ``--resume`` and ``--layout`` of ``wmiltrack eval``."""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import pytest

from wmiltrack.cli import main
from wmiltrack.data.boxes import read_boxes
from wmiltrack.data.synthetic import make_sequence
from wmiltrack.eval.peers import make_tracker, parse_spec
from wmiltrack.eval.report import safe_name

N = 20


def _write_seq(root: Path, name: str, *, seed: int, n: int = N) -> None:
    seq = make_sequence(n, size=(96, 128), target_size=(24, 20), seed=seed, occlusion=False)
    d = root / name / "img"
    d.mkdir(parents=True)
    for i, f in enumerate(seq.load()):
        assert cv2.imwrite(str(d / f"{i + 1:04d}.jpg"), f)
    gt = np.asarray(seq.groundtruth)
    (root / name / "groundtruth_rect.txt").write_text(
        "\n".join(",".join(repr(float(v)) for v in row) for row in gt) + "\n"
    )


@pytest.fixture(scope="module")
def otb(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("otb")
    _write_seq(root, "SynA", seed=3)
    _write_seq(root, "SynB", seed=4)
    return root


# ----------------------------------------------------------------------------- spec overrides
def test_parse_spec() -> None:
    assert parse_spec("rcwmil:num_selected=30:learning_rate=0.85") == (
        "rcwmil",
        {"num_selected": 30, "learning_rate": 0.85},
    )
    assert parse_spec("opencv:MIL") == ("opencv:MIL", {})
    assert parse_spec(" ct ") == ("ct", {})
    # not a Python literal: kept as the string
    assert parse_spec("rcwmil:colour=hsv:flag=True") == ("rcwmil", {"colour": "hsv", "flag": True})
    with pytest.raises(ValueError, match="twice"):
        parse_spec("rcwmil:num_selected=3:num_selected=4")
    with pytest.raises(ValueError, match="name=value"):
        parse_spec("rcwmil:=3")


def test_make_tracker_applies_overrides() -> None:
    t = make_tracker("rcwmil:num_selected=30:learning_rate=0.85")
    default = make_tracker("rcwmil")
    assert t.params.num_selected == 30 and t.params.learning_rate == 0.85  # type: ignore[attr-defined]
    assert default.params.num_selected != 30  # type: ignore[attr-defined]
    # keyword parameters win over the spec's
    assert make_tracker("rcwmil:num_selected=30", num_selected=12).params.num_selected == 12  # type: ignore[attr-defined]
    assert make_tracker("opencv:MIL").name == "opencv:MIL"  # type: ignore[attr-defined]
    with pytest.raises((TypeError, ValueError)):
        make_tracker("rcwmil:no_such_param=1")


def test_sweep_is_a_list_of_specs(otb: Path, tmp_path: Path) -> None:
    specs = ["rcwmil", "rcwmil:num_selected=5"]
    rc = main(["eval", str(otb), "--trackers", ",".join(specs), "--out", str(tmp_path),
               "--no-progress", "--no-plots"])
    assert rc == 0
    doc = json.loads((tmp_path / "eval_ope.json").read_text())
    assert doc["trackers"] == specs
    assert doc["box_folders"][specs[1]] == "rcwmil_num_selected_5"
    a = read_boxes(tmp_path / "boxes" / "rcwmil" / "SynA.txt")
    b = read_boxes(tmp_path / "boxes" / safe_name(specs[1]) / "SynA.txt")
    assert a.shape == b.shape == (N, 4)
    assert not np.array_equal(a, b)  # the override changed the tracker
