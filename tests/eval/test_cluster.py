"""Tracker spec overrides, the Dask executor, ``--resume`` and ``--layout`` of ``wmiltrack eval``."""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import pytest
from conftest import write_generated_otb

from wmiltrack.cli import main
from wmiltrack.data.boxes import read_boxes
from wmiltrack.data.synthetic import make_sequence
from wmiltrack.eval.report import safe_name
from wmiltrack.trackers import make_tracker, parse_spec, split_specs

N = 20


def _write_seq(root: Path, name: str, *, seed: int, n: int = N) -> None:
    write_generated_otb(root, name, seed=seed, n=n)


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


def test_split_specs_keeps_commas_in_brackets_and_quotes() -> None:
    text = "rcwmil, rcwmil-plus:gray_channels=('logluma','orient0'):x=[1, 2],opencv:MIL,,"
    got = split_specs(text)
    assert got == ["rcwmil", "rcwmil-plus:gray_channels=('logluma','orient0'):x=[1, 2]",
                   "opencv:MIL"]
    assert parse_spec(got[1])[1] == {"gray_channels": ("logluma", "orient0"), "x": [1, 2]}
    assert split_specs("a:s='x,y',b") == ["a:s='x,y'", "b"]
    assert split_specs(None) == [] and split_specs(" , ") == []


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
def _files(root: Path) -> dict[str, np.ndarray]:
    return {str(p.relative_to(root)): read_boxes(p) for p in sorted(root.rglob("*.txt"))}


@pytest.mark.extras("distributed")
def test_dask_local_cluster_gives_the_serial_boxes(otb: Path, tmp_path: Path) -> None:
    import socket

    serial, dask_out = tmp_path / "serial", tmp_path / "dask"
    common = ["--trackers", "rcwmil,ct", "--no-progress", "--no-plots", "--repeats", "2"]
    assert main(["eval", str(otb), "--out", str(serial), *common]) == 0
    # dask's default HTTP port taken by someone else (another cluster, a notebook) must not matter
    blocker = socket.socket()
    try:
        blocker.bind(("0.0.0.0", 8787))
        blocker.listen()
    except OSError:  # already taken: the same situation
        pass
    try:
        assert main(["eval", str(otb), "--out", str(dask_out), "--executor", "dask", "-j", "2",
                     *common]) == 0
    finally:
        blocker.close()
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


@pytest.mark.extras("distributed")
def test_dask_existing_cluster_by_scheduler_address(otb: Path, tmp_path: Path) -> None:
    """--scheduler ADDRESS: a scheduler and a worker started apart from wmiltrack, as the README
    shows (`dask scheduler`, `dask worker`), run the tasks and give the serial boxes."""
    import subprocess
    import time

    sched_file = tmp_path / "scheduler.json"
    env = {**os.environ, "DASK_DISTRIBUTED__WORKER__DAEMON": "False"}
    procs = [subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_scheduler",
                               "--scheduler-file", str(sched_file), "--port", "0",
                               "--dashboard-address", ":0", "--host", "127.0.0.1"],
                              env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    try:
        deadline = time.monotonic() + 60
        while not sched_file.exists() and time.monotonic() < deadline:
            time.sleep(0.2)
        assert sched_file.exists(), "the scheduler did not start"
        procs.append(subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_worker",
                                       "--scheduler-file", str(sched_file), "--nworkers", "1",
                                       "--nthreads", "1", "--dashboard-address", ":0",
                                       "--host", "127.0.0.1"],
                                      env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        address = json.loads(sched_file.read_text())["address"]
        from distributed import Client

        with Client(address, timeout=60) as client:
            client.wait_for_workers(1, timeout=60)
        serial, dask_out = tmp_path / "serial", tmp_path / "dask"
        common = ["--trackers", "rcwmil", "--no-progress", "--no-plots"]
        assert main(["eval", str(otb), "--out", str(serial), *common]) == 0
        assert main(["eval", str(otb), "--out", str(dask_out), "--executor", "dask",
                     "--scheduler", address, *common]) == 0
    finally:
        for p in reversed(procs):
            p.terminate()
        for p in procs:
            try:
                p.wait(timeout=20)
            except subprocess.TimeoutExpired:
                p.kill()
    a, b = _files(serial / "boxes"), _files(dask_out / "boxes")
    assert sorted(a) == sorted(b) and len(a) == 2
    for k in a:
        np.testing.assert_array_equal(a[k], b[k], err_msg=k)


def _die_once(marker: str, task: Any) -> Any:
    """Kill the worker process the first time (a worker dying under a task), then run it."""
    import os

    from wmiltrack.eval.runner import run_task

    if not os.path.exists(marker):
        Path(marker).write_text("died")
        os._exit(1)
    return run_task(task)


@pytest.mark.extras("distributed")
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


class _Maker:
    """``runner.make_tracker`` that records the specs it makes, and can interrupt the third
    task (SynB with rcwmil) or fail to make ct."""

    def __init__(self, real: Any) -> None:
        self.real = real
        self.made: list[str] = []
        self.interrupt = self.fail = False

    def __call__(self, spec: str, seed: int = 0, **params: Any) -> Any:
        self.made.append(spec)
        if len(self.made) == 3 and self.interrupt:
            raise KeyboardInterrupt
        if self.fail and spec == "ct":
            raise RuntimeError("cannot make it")
        return self.real(spec, seed=seed, **params)

    def run(self, *args: str) -> tuple[int, list[str]]:
        """``wmiltrack eval`` with ``args``: its exit status and the specs it made."""
        self.made.clear()
        status = main(["eval", *args, "--trackers", "rcwmil,ct", "--no-progress", "--no-plots"])
        return status, list(self.made)


def _check_resumed(full: Path, out: Path) -> dict[str, np.ndarray]:
    """A resumed run's box files and rows are those of the run that was not interrupted; the
    runs read back are untimed, the others timed."""
    a, b = _files(full / "boxes"), _files(out / "boxes")
    assert sorted(a) == sorted(b) and len(a) == 4
    for k in a:
        np.testing.assert_array_equal(a[k], b[k], err_msg=k)
    assert _rows(full) == _rows(out) and len(_rows(out)) == 6
    table = (out / "eval_ope.md").read_text()
    assert "resumed: 2 of 4 runs read back from their box files" in table
    doc = json.loads((out / "eval_ope.json").read_text())
    assert doc["settings"]["resumed_runs"] == 2
    assert doc["results"]["rcwmil"]["SynA"]["runs"][0]["fps"] is None
    assert doc["results"]["rcwmil"]["SynB"]["runs"][0]["fps"] > 0
    return a


def _check_failed_runs_run_again(make: _Maker, otb: Path, out: Path, full: Path) -> None:
    """A run that failed is recorded, and is run again by the next --resume."""
    for seq in ("SynA", "SynB"):
        (out / "boxes" / "ct" / f"{seq}.txt").unlink()
    make.fail = True
    assert make.run(str(otb), "--out", str(out), "--resume") == (1, ["ct", "ct"])
    record = json.loads((out / "boxes" / "ct" / "SynA.run.json").read_text())
    assert record["seed"] == 0 and record["error"] == "RuntimeError: cannot make it"
    assert np.isnan(read_boxes(out / "boxes" / "ct" / "SynA.txt")).all()
    make.fail = False
    assert make.run(str(otb), "--out", str(out), "--resume") == (0, ["ct", "ct"])  # not done
    assert _rows(full) == _rows(out)


def test_resume_after_an_interruption_runs_only_what_is_missing(
    otb: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from wmiltrack.eval import runner

    full, out = tmp_path / "full", tmp_path / "out"
    make = _Maker(runner.make_tracker)
    assert make.run(str(otb), "--out", str(full))[0] == 0
    monkeypatch.setattr(runner, "make_tracker", make)
    make.interrupt = True
    assert make.run(str(otb), "--out", str(out))[0] == 130  # Ctrl-C: one line, 130
    assert sorted(p.name for p in (out / "boxes").rglob("*.txt")) == ["SynA.txt", "SynA.txt"]
    make.interrupt = False
    assert make.run(str(otb), "--out", str(out), "--resume") == (0, ["rcwmil", "ct"])  # SynB's
    a = _check_resumed(full, out)

    # a deleted box file is run again; nothing else is
    (out / "boxes" / "ct" / "SynA.txt").unlink()
    assert make.run(str(otb), "--out", str(out), "--resume") == (0, ["ct"])
    np.testing.assert_array_equal(read_boxes(out / "boxes" / "ct" / "SynA.txt"), a["ct/SynA.txt"])
    _check_failed_runs_run_again(make, otb, out, full)

    # another --missing rule, or another seed, is another run
    every = ["rcwmil", "ct", "rcwmil", "ct"]
    assert make.run(str(otb), "--out", str(out), "--resume", "--missing", "miss") == (0, every)
    assert make.run(str(otb), "--out", str(out), "--resume", "--seed", "1") == (0, every)


def test_resume_is_ope_only(otb: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["eval", str(otb), "--out", str(tmp_path), "--protocol", "vot", "--resume",
                 "--no-progress"]) == 2  # options that do not go together: a bad command line
    assert "--resume reads OPE box files back" in capsys.readouterr().err


# ----------------------------------------------------------------------------- --layout
def _build(root: Path, layout: str, n: int = 12, absent: tuple[int, ...] = ()) -> Any:
    """One generated sequence written in a benchmark's layout (as tests/data/test_layouts.py's
    end-to-end test does); ``absent`` frames are flagged absent (LaSOT out_of_view, GOT-10k
    absence.label).  Returns the sequence as the layout loader reads it."""
    from wmiltrack.data.layouts import load_layout

    syn = make_sequence(n, size=(96, 128), target_size=(24, 20), seed=3, occlusion=False, clutter=False)
    rows = [",".join(f"{v:.6f}" for v in r) for r in np.asarray(syn.groundtruth)]
    flags = ["1" if k in absent else "0" for k in range(n)]
    if layout == "lasot":
        d = root / "toy" / "toy-1"
        img_dir, names = d / "img", [f"{k + 1:08d}.jpg" for k in range(n)]
        files = {d / "groundtruth.txt": rows, d / "full_occlusion.txt": [",".join(["0"] * n)],
                 d / "out_of_view.txt": [",".join(flags)]}
    elif layout == "got10k":
        d = root / "val" / "GOT-10k_Val_000001"
        img_dir, names = d, [f"{k + 1:08d}.jpg" for k in range(n)]
        files = {d / "groundtruth.txt": rows, d / "absence.label": flags,
                 d / "cover.label": ["0" if f == "1" else "8" for f in flags],
                 d / "meta_info.ini": ["[METAINFO]", "resolution: (128, 96)"],
                 root / "val" / "list.txt": ["GOT-10k_Val_000001"]}
    elif layout == "uav123":
        img_dir, names = root / "data_seq" / "UAV123" / "toy", [f"{k + 1:06d}.jpg" for k in range(n)]
        files = {root / "anno" / "UAV123" / "toy.txt": rows}
    elif layout == "trackingnet":
        img_dir, names = root / "TRAIN_0" / "frames" / "toy", [f"{k}.jpg" for k in range(n)]
        files = {root / "TRAIN_0" / "anno" / "toy.txt": rows}
    else:  # vot: 8-value polygons, the corners of each box
        img_dir, names = root / "toy" / "color", [f"{k + 1:08d}.jpg" for k in range(n)]
        polys = []
        for x, y, w, h in np.asarray(syn.groundtruth):
            polys.append(",".join(f"{v:.6f}" for v in (x, y, x + w, y, x + w, y + h, x, y + h)))
        files = {root / "toy" / "groundtruth.txt": polys, root / "list.txt": ["toy"]}
    for path, lines in files.items():
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text("\n".join(lines) + "\n")
    img_dir.mkdir(parents=True, exist_ok=True)
    for name, frame in zip(names, syn):
        assert cv2.imwrite(str(img_dir / name), frame)
    (seq,) = load_layout(root, layout)
    return seq


def _iou(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    x1 = np.maximum(a[:, 0], b[:, 0])
    y1 = np.maximum(a[:, 1], b[:, 1])
    x2 = np.minimum(a[:, 0] + a[:, 2], b[:, 0] + b[:, 2])
    y2 = np.minimum(a[:, 1] + a[:, 3], b[:, 1] + b[:, 3])
    inter = np.clip(x2 - x1, 0, None) * np.clip(y2 - y1, 0, None)
    return inter / (a[:, 2] * a[:, 3] + b[:, 2] * b[:, 3] - inter)


@pytest.mark.parametrize("layout", ["lasot", "got10k", "uav123", "trackingnet", "vot"])
def test_eval_reads_every_layout(tmp_path: Path, layout: str) -> None:
    from wmiltrack.engine.tracker import Tracker

    data, out = tmp_path / "data", tmp_path / "out"
    seq = _build(data, layout)
    rc = main(["eval", str(data), "--trackers", "rcwmil", "--out", str(out), "--no-plots",
               "--no-progress"])
    assert rc == 0
    doc = json.loads((out / "eval_ope.json").read_text())
    assert doc["layout"] == layout and doc["sequences"] == [seq.name]
    # the boxes are the tracker's own on the layout loader's frames
    pred = Tracker("rcwmil", seed=0).track(seq, seq.init_box)
    got = read_boxes(out / "boxes" / "rcwmil" / f"{seq.name}.txt")
    np.testing.assert_array_equal(got[1:], pred[1:])
    np.testing.assert_array_equal(got[0], seq.groundtruth[0])  # row 0: the initialisation box
    table = (out / "eval_ope.md").read_text()
    assert ("| Tracker | AO | SR@0.5 | SR@0.75 |" in table) == (layout == "got10k")
    assert (doc["got10k"] is not None) == (layout == "got10k")
    # named explicitly, the same
    assert main(["eval", str(data), "--layout", layout, "--trackers", "rcwmil", "--out",
                 str(tmp_path / "named"), "--no-plots", "--no-progress"]) == 0
    np.testing.assert_array_equal(read_boxes(tmp_path / "named" / "boxes" / "rcwmil" / f"{seq.name}.txt"), got)


def test_lasot_absent_frames_fail_and_got10k_metrics(tmp_path: Path) -> None:
    from wmiltrack.engine.tracker import Tracker

    absent = (4, 5, 9)
    for layout in ("lasot", "got10k"):
        data, out = tmp_path / layout, tmp_path / f"out_{layout}"
        seq = _build(data, layout, absent=absent)
        assert main(["eval", str(data), "--trackers", "rcwmil", "--out", str(out), "--no-plots",
                     "--no-progress"]) == 0
        doc = json.loads((out / "eval_ope.json").read_text())
        pred = read_boxes(out / "boxes" / "rcwmil" / f"{seq.name}.txt")
        assert np.array_equal(pred[1:], Tracker("rcwmil", seed=0).track(seq, seq.init_box)[1:])
        gt = np.asarray(seq.groundtruth)
        visible = np.all(np.isfinite(gt), axis=1)
        assert visible.sum() == 12 - len(absent)
        iou = _iou(pred[visible], gt[visible])
        run = doc["results"]["rcwmil"][seq.name]["runs"][0]
        if layout == "lasot":  # LaSOT toolkit: successes over visible frames / all frames
            assert run["success_50"] == pytest.approx(np.sum(iou > 0.5) / 12)
            assert "count frames where the target is absent as failures" in (out / "eval_ope.md").read_text()
        else:  # got10k toolkit: first frame skipped, absent frames left out
            assert run["success_50"] == pytest.approx(np.mean(iou > 0.5))
            keep = visible.copy()
            keep[0] = False
            iou_g = _iou(pred[keep], gt[keep])
            g = doc["got10k"]["rcwmil"]
            assert g["ao"] == pytest.approx(float(np.mean(iou_g)))
            assert g["sr50"] == pytest.approx(float(np.mean(iou_g > 0.5)))
            assert g["sr75"] == pytest.approx(float(np.mean(iou_g > 0.75)))


def test_first_frame_only_sequences_are_run_not_scored(tmp_path: Path) -> None:
    syn = make_sequence(8, size=(96, 128), target_size=(24, 20), seed=3, occlusion=False)
    d = tmp_path / "data" / "test" / "GOT-10k_Test_000001"
    d.mkdir(parents=True)
    for k, frame in enumerate(syn):
        assert cv2.imwrite(str(d / f"{k + 1:08d}.jpg"), frame)
    (d / "groundtruth.txt").write_text(",".join(f"{v:.3f}" for v in np.asarray(syn.groundtruth)[0]) + "\n")
    (d.parent / "list.txt").write_text("GOT-10k_Test_000001\n")
    out = tmp_path / "out"
    assert main(["eval", str(tmp_path / "data"), "--trackers", "rcwmil", "--out", str(out),
                 "--no-progress", "--no-plots"]) == 0
    boxes = read_boxes(out / "boxes" / "rcwmil" / "GOT-10k_Test_000001.txt")
    assert boxes.shape == (8, 4) and np.isfinite(boxes).all()  # for the benchmark's server
    doc = json.loads((out / "eval_ope.json").read_text())
    assert doc["layout"] == "got10k" and doc["sequences"] == [] and doc["results"] == {}
    assert doc["unscored_sequences"] == ["GOT-10k_Test_000001"]
    assert "not scored: 1 sequence annotated on the first frame only" in (out / "eval_ope.md").read_text()


def test_executor_arguments(otb: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    base = ["eval", str(otb), "--out", str(tmp_path), "--no-progress", "--no-plots"]
    assert main([*base, "--scheduler", "tcp://127.0.0.1:1"]) == 1
    assert "--scheduler needs --executor dask" in capsys.readouterr().err
    assert main([*base, "--executor", "serial", "-j", "2"]) == 1
    assert "--executor serial runs one task at a time" in capsys.readouterr().err
    assert main([*base, "--executor", "process", "-j", "2", "--sequences", "SynA"]) == 0
    assert json.loads((tmp_path / "eval_ope.json").read_text())["settings"]["executor"] == "process"
