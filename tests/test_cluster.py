"""Tracker spec overrides, the Dask executor, ``--resume`` and ``--layout`` of ``wmiltrack eval``."""

from __future__ import annotations

import importlib.util
import json
import os
import sys
from pathlib import Path
from typing import Any

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


# ----------------------------------------------------------------------------- Dask
@pytest.fixture
def need_distributed() -> None:
    """Skip without ``distributed`` (the ``cluster`` extra), but fail under CI, which installs
    it (``.ci/run``)."""
    if importlib.util.find_spec("distributed") is None:
        msg = 'distributed not installed (pip install -e ".[cluster]")'
        if os.environ.get("CI"):
            pytest.fail(msg)
        pytest.skip(msg)


def _files(root: Path) -> dict[str, np.ndarray]:
    return {str(p.relative_to(root)): read_boxes(p) for p in sorted(root.rglob("*.txt"))}


@pytest.mark.usefixtures("need_distributed")
def test_dask_local_cluster_gives_the_serial_boxes(otb: Path, tmp_path: Path) -> None:
    serial, dask_out = tmp_path / "serial", tmp_path / "dask"
    common = ["--trackers", "rcwmil,ct", "--no-progress", "--no-plots", "--repeats", "2"]
    assert main(["eval", str(otb), "--out", str(serial), *common]) == 0
    assert main(["eval", str(otb), "--out", str(dask_out), "--executor", "dask", "-j", "2",
                 *common]) == 0
    a, b = _files(serial / "boxes"), _files(dask_out / "boxes")
    assert sorted(a) == sorted(b) and len(a) == 2 * 2 * 2
    for k in a:
        np.testing.assert_array_equal(a[k], b[k], err_msg=k)
    ja = json.loads((serial / "eval_ope.json").read_text())
    jb = json.loads((dask_out / "eval_ope.json").read_text())
    assert ja["settings"]["executor"] == "serial" and jb["settings"]["executor"] == "dask"
    assert ja["settings"]["jobs"] == 1 and jb["settings"]["jobs"] == 2
    for t in ("rcwmil", "ct"):
        for k in ("auc", "auc_std", "success_50", "precision_20", "success_curve", "n_lost", "errors"):
            assert ja["summary"][t][k] == jb["summary"][t][k], (t, k)
    # the table: the same rows up to the timing columns (FPS, FPS ratio, Init ms)
    rows_a, rows_b = (
        [line.split("|")[1:-4] for line in (d / "eval_ope.md").read_text().splitlines()
         if line.startswith("| Syn") or line.startswith("| **mean")]
        for d in (serial, dask_out)
    )
    assert len(rows_a) == 6 and rows_a == rows_b


def _die_once(marker: str, task: Any) -> Any:
    """Kill the worker process the first time (a worker dying under a task), then run it."""
    import os

    from wmiltrack.eval.runner import run_task

    if not os.path.exists(marker):
        Path(marker).write_text("died")
        os._exit(1)
    return run_task(task)


@pytest.mark.usefixtures("need_distributed")
def test_dask_retries_a_failed_task_once_and_reports_it(otb: Path, tmp_path: Path) -> None:
    import functools
    import sys

    import cloudpickle
    import dask

    from wmiltrack.eval.cluster import DaskExecutor
    from wmiltrack.eval.pipeline import make_tasks
    from wmiltrack.eval.runner import run_task

    # a tracker spec that fails in every try: its error comes back, after one retry
    said: list[str] = []
    tasks = make_tasks([otb / "SynA"], ["rcwmil", "rcwmil:no_such_param=1"], [0])
    outs = list(DaskExecutor(2, log=said.append).map(run_task, tasks))
    assert sorted(o.tracker for o in outs) == ["rcwmil", "rcwmil:no_such_param=1"]
    bad = next(o for o in outs if o.tracker != "rcwmil")
    assert bad.error is not None and "no_such_param" in bad.error
    assert len(said) == 1 and said[0].startswith("retrying rcwmil:no_such_param=1 on SynA")
    good = next(o for o in outs if o.tracker == "rcwmil")
    assert good.error is None and good.boxes.shape == (N, 4)

    # a worker that dies under its task: the task is submitted again and finishes
    cloudpickle.register_pickle_by_value(sys.modules[__name__])
    try:
        marker = tmp_path / "died"
        said.clear()
        with dask.config.set({"distributed.scheduler.allowed-failures": 0}):
            outs = list(
                DaskExecutor(1, log=said.append).map(
                    functools.partial(_die_once, str(marker)), tasks[:1]
                )
            )
        assert marker.read_text() == "died"
        assert len(outs) == 1 and outs[0].error is None
        np.testing.assert_array_equal(outs[0].boxes, good.boxes)
        assert len(said) == 1 and "KilledWorker" in said[0]
    finally:
        cloudpickle.unregister_pickle_by_value(sys.modules[__name__])


def test_without_distributed_the_message_says_how_to_install(
    otb: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setitem(sys.modules, "distributed", None)  # import distributed -> ImportError
    rc = main(["eval", str(otb), "--out", str(tmp_path), "--executor", "dask", "--no-progress"])
    assert rc == 1
    assert 'pip install "wmiltrack[cluster]"' in capsys.readouterr().err
    assert not (tmp_path / "boxes").exists()  # said before anything ran


# ----------------------------------------------------------------------------- --resume
def _rows(out: Path) -> list[list[str]]:
    """The table's result rows up to the timing columns (FPS, FPS ratio, Init ms)."""
    return [line.split("|")[1:-4] for line in (out / "eval_ope.md").read_text().splitlines()
            if line.startswith("| Syn") or line.startswith("| **mean")]


def test_resume_after_an_interruption_runs_only_what_is_missing(
    otb: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from wmiltrack.eval import runner

    full, out = tmp_path / "full", tmp_path / "out"
    common = ["--trackers", "rcwmil,ct", "--no-progress", "--no-plots"]
    assert main(["eval", str(otb), "--out", str(full), *common]) == 0

    real = runner.make_tracker
    made: list[str] = []

    def make(spec: str, seed: int = 0, **params: Any) -> Any:
        made.append(spec)
        if len(made) == 3 and interrupt:  # the third task: SynB with rcwmil
            raise KeyboardInterrupt
        if fail and spec == "ct":
            raise RuntimeError("cannot make it")
        return real(spec, seed=seed, **params)

    monkeypatch.setattr(runner, "make_tracker", make)
    interrupt, fail = True, False
    with pytest.raises(KeyboardInterrupt):
        main(["eval", str(otb), "--out", str(out), *common])
    assert sorted(p.name for p in (out / "boxes").rglob("*.txt")) == ["SynA.txt", "SynA.txt"]

    made.clear()
    interrupt = False
    assert main(["eval", str(otb), "--out", str(out), "--resume", *common]) == 0
    assert made == ["rcwmil", "ct"]  # only SynB's two runs
    a, b = _files(full / "boxes"), _files(out / "boxes")
    assert sorted(a) == sorted(b) and len(a) == 4
    for k in a:
        np.testing.assert_array_equal(a[k], b[k], err_msg=k)
    assert _rows(full) == _rows(out) and len(_rows(out)) == 6
    table = (out / "eval_ope.md").read_text()
    assert "resumed: 2 of 4 runs read back from their box files" in table
    doc = json.loads((out / "eval_ope.json").read_text())
    assert doc["settings"]["resumed_runs"] == 2
    # resumed runs are untimed; the runs made now are timed
    assert doc["results"]["rcwmil"]["SynA"]["runs"][0]["fps"] is None
    assert doc["results"]["rcwmil"]["SynB"]["runs"][0]["fps"] > 0

    # a deleted box file and a failed run are run again; nothing else is
    (out / "boxes" / "ct" / "SynA.txt").unlink()
    made.clear()
    assert main(["eval", str(otb), "--out", str(out), "--resume", *common]) == 0
    assert made == ["ct"]
    np.testing.assert_array_equal(read_boxes(out / "boxes" / "ct" / "SynA.txt"), a["ct/SynA.txt"])

    # a run that failed is run again
    for seq in ("SynA", "SynB"):
        (out / "boxes" / "ct" / f"{seq}.txt").unlink()
    made.clear()
    fail = True
    assert main(["eval", str(otb), "--out", str(out), "--resume", *common]) == 1
    assert made == ["ct", "ct"]
    record = json.loads((out / "boxes" / "ct" / "SynA.run.json").read_text())
    assert record["seed"] == 0 and record["error"] == "RuntimeError: cannot make it"
    assert np.isnan(read_boxes(out / "boxes" / "ct" / "SynA.txt")).all()
    made.clear()
    fail = False
    assert main(["eval", str(otb), "--out", str(out), "--resume", *common]) == 0
    assert made == ["ct", "ct"]  # failed runs are not taken as done
    assert _rows(full) == _rows(out)

    # another seed is another run
    made.clear()
    assert main(["eval", str(otb), "--out", str(out), "--resume", "--seed", "1", *common]) == 0
    assert made == ["rcwmil", "ct", "rcwmil", "ct"]


def test_resume_is_ope_only(otb: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["eval", str(otb), "--out", str(tmp_path), "--protocol", "vot", "--resume",
                 "--no-progress"]) == 1
    assert "--resume reads OPE box files back" in capsys.readouterr().err
