"""Smoke tests of the benchmark scripts: verify_eval.py, fps_compare.py, the C++ benchmarks."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest
from conftest import REPO_ROOT, skip_or_fail, write_generated_otb

import wmiltrack
from wmiltrack.cli import main
from wmiltrack.data.synthetic import make_sequence
from wmiltrack.trackers import parse_spec

REPO = REPO_ROOT
BENCH = REPO / "benchmarks"


def _tiny_dataset(root: Path) -> Path:
    seq = make_sequence(20, size=(96, 128), target_size=(24, 20), seed=7, occlusion=False)
    d = root / "data" / "SynC" / "img"
    d.mkdir(parents=True)
    for i, f in enumerate(seq.load()):
        assert cv2.imwrite(str(d / f"{i + 1:04d}.jpg"), f)
    gt = np.asarray(seq.groundtruth)
    gt[4] = np.nan
    rows = ["NaN,NaN,NaN,NaN" if np.isnan(r).any() else ",".join(map(repr, r.tolist())) for r in gt]
    (d.parent / "groundtruth_rect.txt").write_text("\n".join(rows) + "\n")
    return root / "data"


def _run(args: list[str], timeout: float = 120) -> subprocess.CompletedProcess[str]:
    env = dict(os.environ, WMILTRACK_NO_PROGRESS="1")
    return subprocess.run(
        [sys.executable, *args],
        capture_output=True,
        text=True,
        timeout=timeout,
        check=False,
        env=env,
        cwd=REPO,
    )


def test_verify_eval_agrees_and_catches_a_difference(tmp_path: Path) -> None:
    data = _tiny_dataset(tmp_path)
    out = tmp_path / "out"
    assert (
        main(
            [
                "eval",
                str(data),
                "--trackers",
                "rcwmil,ct",
                "--out",
                str(out),
                "--repeats",
                "2",
                "--no-plots",
                "--no-progress",
            ]
        )
        == 0
    )
    r = _run([str(BENCH / "verify_eval.py"), str(out)])
    assert r.returncode == 0, r.stderr
    assert "4 box files" in r.stdout and "OK" in r.stdout
    # tamper with one figure: the check must notice
    path = out / "eval_ope.json"
    doc = json.loads(path.read_text())
    doc["results"]["ct"]["SynC"]["runs"][1]["auc"] += 1e-3
    path.write_text(json.dumps(doc))
    r = _run([str(BENCH / "verify_eval.py"), str(out)])
    assert r.returncode == 1 and "FAIL" in r.stdout


def test_fps_compare_tiny() -> None:
    r = _run(
        [
            str(BENCH / "fps_compare.py"),
            "--sizes",
            "128x96",
            "--boxes",
            "24",
            "--frames",
            "8",
            "--repeats",
            "1",
            "--trackers",
            "rcwmil,ct,opencv:MIL",
        ]
    )
    assert r.returncode == 0, r.stderr
    assert "128x96/24" in r.stdout and "every tracker timed in this process" in r.stdout
    cells = dict(re.findall(r"^\| (\S+) \| (\d+ \(\d\.\d\d\)) \|$", r.stdout, re.M))
    assert set(cells) == {"rcwmil", "ct", "opencv:MIL"}  # FPS (mean IoU) for each tracker
    assert all(0.0 <= float(c.split("(")[1][:-1]) <= 1.0 for c in cells.values())
    assert "Ratio to OpenCV TrackerMIL" in r.stdout
    assert "| opencv:MIL | 1.0 |" in r.stdout


def test_fps_compare_on_real_layout_sequences(tmp_path: Path) -> None:
    """--otb: one column per sequence (its first --frames frames) and "all", the frames of
    every sequence over their update time; a missing sequence is a usage error."""
    for name, seed in (("SynA", 3), ("SynB", 4)):
        write_generated_otb(tmp_path, name, seed=seed, n=10)
    args = [str(BENCH / "fps_compare.py"), "--otb", str(tmp_path), "--sequences", "SynA,SynB",
            "--frames", "6", "--repeats", "1", "--trackers", "rcwmil"]
    r = _run(args)
    assert r.returncode == 0, r.stderr
    assert "| Tracker | SynA | SynB | all |" in r.stdout and "by sequence" in r.stdout
    row = re.search(r"^\| rcwmil \| (\d+) \(.*\) \| (\d+) \(.*\) \| (\d+) \(.*\) \|$", r.stdout, re.M)
    assert row is not None, r.stdout
    a, b, both = (int(v) for v in row.groups())
    assert min(a, b) <= both <= max(a, b)  # 5 frames each: "all" lies between the two
    r = _run(args[:4] + ["SynA,Nope"] + args[5:])
    assert r.returncode == 2 and "no sequence Nope" in r.stderr


def test_fps_compare_refuses_an_unknown_tracker() -> None:
    r = _run([str(BENCH / "fps_compare.py"), "--quick", "--trackers", "rcwmil,rcwmil-pls"])
    assert r.returncode == 2 and "unknown tracker(s): rcwmil-pls" in r.stderr


def test_fps_compare_gray_frames(tmp_path: Path) -> None:
    out = tmp_path / "fps.json"
    r = _run([str(BENCH / "fps_compare.py"), "--sizes", "128x96", "--boxes", "24", "--frames", "8",
              "--repeats", "1", "--trackers", "rcwmil-plus,opencv:MIL", "--gray", "--json", str(out)])
    assert r.returncode == 0, r.stderr
    assert "8 gray frames per run" in r.stdout
    doc = json.loads(out.read_text())
    assert doc["gray"] is True and set(doc["fps_median"]) == {"rcwmil-plus", "opencv:MIL"}
    assert 0.0 <= doc["mean_iou"]["rcwmil-plus"]["128x96/24"] <= 1.0


def test_ablation_on_a_generated_dataset(tmp_path: Path) -> None:
    data = _tiny_dataset(tmp_path)
    out = tmp_path / "ablation.json"
    r = _run([str(BENCH / "ablation.py"), "--otb", str(data), "--seeds", "0,1", "--rows",
              "rcwmil,rcwmil + colour,rcwmil-plus", "--fps-sequences", "SynC", "--fps-frames", "6",
              "--fps-repeats", "1", "--no-progress", "--json", str(out)])
    assert r.returncode == 0, r.stderr
    doc = json.loads(out.read_text())
    assert list(doc["rows"]) == ["rcwmil", "rcwmil + colour", "rcwmil-plus"]
    assert doc["rows"]["rcwmil + colour"].startswith("rcwmil:colour_weight=0.7")
    for title in doc["rows"]:
        assert len(doc["auc"][title]) == 2 and all(0.0 <= a <= 1.0 for a in doc["auc"][title])
        assert doc["fps"][title] > 0
        assert f"| {title} | {sum(doc['auc'][title]) / 2:.3f} |" in r.stdout
    bad = _run([str(BENCH / "ablation.py"), "--otb", str(data), "--rows", "nonsense"])
    assert bad.returncode == 2 and "unknown rows" in bad.stderr


def test_ablation_of_rcwmil_cf_rows() -> None:
    """--preset rcwmil-cf: rcwmil-plus, rcwmil-cf and each part changed, each a valid spec."""
    sys.path.insert(0, str(BENCH))
    try:
        import ablation
    finally:
        sys.path.remove(str(BENCH))
    rows = ablation.default_rows("rcwmil-cf")
    assert list(rows)[:2] == ["rcwmil-plus", "rcwmil-cf"]
    assert rows["rcwmil-cf - DSST's vote"] == "rcwmil-cf:scale_dsst=0.0"
    for spec in rows.values():
        name, overrides = parse_spec(spec)
        wmiltrack.Params.for_variant(name, **overrides)  # every row is a valid tracker


def test_hidden_target_check_runs() -> None:
    r = _run([str(BENCH / "hidden_target.py"), "--trackers", "rcwmil", "--seeds", "0"])
    assert r.returncode == 0, r.stderr
    row = next(line for line in r.stdout.splitlines() if line.startswith("rcwmil "))
    assert row.split()[1] == "0" and row.split()[2].endswith("%"), r.stdout


def test_cf_probe_on_a_generated_dataset(tmp_path: Path) -> None:
    data = _tiny_dataset(tmp_path)
    r = _run([str(BENCH / "cf_probe.py"), "--otb", str(data), "--confidence"])
    assert r.returncode == 0, r.stderr
    row = next(line for line in r.stdout.splitlines() if line.startswith("SynC "))
    auc = float(row.split()[2])
    assert 0.3 < auc <= 1.0, r.stdout  # a slow, textured target on a generated sequence
    assert re.search(r"^mean\s+20\s", r.stdout, re.M), r.stdout
    assert re.search(r"^  psr\s+ROC AUC", r.stdout, re.M), r.stdout


@pytest.mark.extras()
def test_cpp_bench_binary_if_built() -> None:
    exe = REPO / "build" / "bench" / "benchmarks" / "cpp" / "bench_core"
    if not exe.is_file():  # .ci/run builds them before its second test step
        skip_or_fail(f"C++ benchmarks not built at {exe} (benchmarks/cpp/run.sh builds them, ~30 s)")
    r = subprocess.run(
        [str(exe), "--quick", "--reps", "5"],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert r.returncode == 0, r.stderr
    for word in ("integral", "project", "score", "exhaustive 25/1", "Mval/s"):
        assert word in r.stdout


def test_devset_halves_and_lost_flag_shares(tmp_path: Path) -> None:
    """benchmarks/devset.py: the halves are the sorted names alternated, and the figures it
    prints are those of its JSON (AUC per half; the lost flag's shares over the scored
    frames); two roots are one development set."""
    for i, name in enumerate(["Cc", "Aa", "Dd"]):
        write_generated_otb(tmp_path / "one", name, seed=i, n=12)
    write_generated_otb(tmp_path / "two", "Bb", seed=5, n=12)
    out = tmp_path / "dev.json"
    r = _run([str(BENCH / "devset.py"), "--roots", f"{tmp_path / 'one'},{tmp_path / 'two'}",
              "--trackers", "rcwmil,rcwmil-cf", "--seeds", "0,1", "--json", str(out)])
    assert r.returncode == 0, r.stderr
    got = json.loads(out.read_text())
    assert got["halves"] == [["Aa", "Cc"], ["Bb", "Dd"]]
    runs = [x for x in got["runs"] if x["spec"] == "rcwmil"]
    assert sorted((x["name"], x["seed"]) for x in runs) == sorted(
        (n, s) for n in ["Aa", "Bb", "Cc", "Dd"] for s in (0, 1))
    s = got["summary"]["rcwmil"]
    per = s["per_sequence"]
    assert s["half1"] == pytest.approx((per["Aa"] + per["Cc"]) / 2)
    assert s["half2"] == pytest.approx((per["Bb"] + per["Dd"]) / 2)
    assert 0.0 <= s["well_tracked_flagged_lost"] <= 1.0
    assert (f"rcwmil: half 1 {s['half1']:.3f} (sd {s['half1_spread']:.3f}), half 2 "
            f"{s['half2']:.3f} (sd {s['half2_spread']:.3f})") in r.stdout
    # the init jitter: seeded by seed and sequence only, the same for every tracker, within 1 px
    sys.path.insert(0, str(BENCH))
    import devset

    box = (10.0, 20.0, 30.0, 40.0)
    shifted = [devset.jitter(box, seed, "Aa", 1.0) for seed in (0, 1, 2)]
    assert len({b[:2] for b in shifted}) == 3 and all(b[2:] == box[2:] for b in shifted)
    assert all(0.25 - 1e-9 <= np.hypot(b[0] - 10, b[1] - 20) <= 1 + 1e-9 for b in shifted)
    assert devset.jitter(box, 1, "Aa", 1.0) == shifted[1] != devset.jitter(box, 1, "Bb", 1.0)
    assert devset.jitter(box, 1, "Aa", 0.0) == box
    rc = [x for x in got["runs"] if x["spec"] == "rcwmil-cf"]
    assert {(x["name"], x["seed"]): x["boxes"][0] for x in rc} == {
        (x["name"], x["seed"]): x["boxes"][0] for x in runs}
    same = _run([str(BENCH / "devset.py"), "--roots", f"{tmp_path / 'one'},{tmp_path / 'one'}"])
    assert same.returncode != 0 and "is in both" in same.stderr


def _hidden_target_dataset(root: Path) -> range:
    """A generated target hidden behind an occluder on frames 25-54 (rcwmil-cf flags them
    lost), whose ground truth says it is in view 60 px away on frames 30-49 (returned)."""
    seq = make_sequence(70, size=(160, 200), target_size=(28, 24), seed=3, occlusion=False,
                        full_occlusion=(25, 30))
    d = root / "Hidden" / "img"
    d.mkdir(parents=True)
    for i, f in enumerate(seq.load()):
        assert cv2.imwrite(str(d / f"{i + 1:04d}.png"), f)
    gt = np.asarray(seq.groundtruth, dtype=np.float64)
    moved = range(30, 50)
    for i in moved:
        gt[i, 0] = (gt[i, 0] + 60.0) % (200 - gt[i, 2])
        gt[i, 1] = (gt[i, 1] + 60.0) % (160 - gt[i, 3])
    (d.parent / "groundtruth_rect.txt").write_text(
        "\n".join(",".join(repr(float(v)) for v in row) for row in gt) + "\n")
    return moved


def test_lost_study_looks_only_at_frames_flagged_lost_whose_box_misses_a_target_in_view(
        tmp_path: Path) -> None:
    """benchmarks/lost_study.py: a generated target hidden behind an occluder on frames 25-54
    (rcwmil-cf flags them lost), whose ground truth, on frames 30-49, says it is in view 60 px
    away: those frames are studied, each a box side or more from the box, no frame outside the
    hidden ones is, and the printed summary is the JSON's."""
    moved = _hidden_target_dataset(tmp_path / "dev")
    out = tmp_path / "lost.json"
    r = _run([str(BENCH / "lost_study.py"), "--roots", str(tmp_path / "dev"), "--json", str(out)])
    assert r.returncode == 0, r.stderr
    got = json.loads(out.read_text())
    rows = got["runs"][0]["rows"]
    studied = [row["frame"] for row in rows]
    assert set(moved) <= set(studied) <= set(range(25, 55))
    assert all(row["distance"] >= 1.0 for row in rows if row["frame"] in moved)
    assert all(len(row["filter_random"]) <= 6 for row in rows)
    assert got["summary"]["frames"] == len(rows)
    assert f"'frames': {len(rows)}," in r.stdout
    missing = _run([str(BENCH / "lost_study.py"), "--roots", str(tmp_path / "dev"),
                    "--sequences", "Nope"])
    assert missing.returncode != 0 and "no such sequence" in missing.stderr


def test_lost_study_asks_nanotrack_only_with_its_model_files(
        tmp_path: Path, nano_network: dict[str, tuple[Path, Path]]) -> None:
    """benchmarks/lost_study.py --nano: a clear error without NanoTrack's files; with v2's
    (conftest's ``nano_network``: NanoTrack's own when they are there, else the stand-in), the
    network's log-odds at the target and at up to three places whose window misses it, on
    every studied frame."""
    _hidden_target_dataset(tmp_path / "dev")
    env = {k: v for k, v in os.environ.items() if not k.startswith("WMILTRACK_NANO_")}
    r = subprocess.run([sys.executable, str(BENCH / "lost_study.py"), "--roots",
                        str(tmp_path / "dev"), "--nano"], capture_output=True, text=True,
                       timeout=120, check=False, env=env, cwd=REPO)
    assert r.returncode != 0 and "WMILTRACK_NANO_BACKBONE" in r.stderr
    backbone, head = (str(p) for p in nano_network["v2"])
    out = tmp_path / "lost.json"
    env.update(WMILTRACK_NANO_BACKBONE=backbone, WMILTRACK_NANO_HEAD=head,
               WMILTRACK_NO_PROGRESS="1")
    r = subprocess.run([sys.executable, str(BENCH / "lost_study.py"), "--roots",
                        str(tmp_path / "dev"), "--nano", "--json", str(out)],
                       capture_output=True, text=True, timeout=300, check=False, env=env,
                       cwd=REPO)
    assert r.returncode == 0, r.stderr
    rows = json.loads(out.read_text())["runs"][0]["rows"]
    assert rows and all(np.isfinite(row["nano_at_target"]) for row in rows)
    assert all(len(row["nano_random"]) <= 3 for row in rows)
    assert "nano_target_above_random_q95" in json.loads(out.read_text())["summary"]


def test_interleaved_times_two_interpreters_in_turns(tmp_path: Path) -> None:
    """benchmarks/interleaved.py: the same interpreter twice gives a line with both speeds and
    their ratio (no figure is asserted: speed is not tested); a worker that cannot start is an
    error naming its interpreter."""
    write_generated_otb(tmp_path, "Seq", seed=1, n=6)
    args = [str(BENCH / "interleaved.py"), sys.executable, sys.executable, "--otb",
            str(tmp_path), "--sequences", "Seq", "--frames", "5", "--chunk", "3",
            "--seconds", "1", "--tracker", "rcwmil"]
    r = _run(args)
    assert r.returncode == 0, r.stderr
    assert re.search(r"rcwmil on Seq \(5 frames each; (core \d+|not pinned)\), \d+ turns of 3 "
                     r"updates each: old \d+ updates/s, new \d+ updates/s; new / old time: "
                     r"[\d.]+ in all", r.stdout)
    gen = _run([str(BENCH / "interleaved.py"), sys.executable, sys.executable, "--generated",
                "128x96/24", "--frames", "5", "--chunk", "3", "--seconds", "1", "--tracker",
                "rcwmil"])
    assert gen.returncode == 0, gen.stderr
    assert "rcwmil on 128x96/24 (5 frames each;" in gen.stdout
    free = _run([*args, "--cpu", "-1"])
    assert free.returncode == 0 and "(5 frames each; not pinned)" in free.stdout, free.stderr
    if hasattr(os, "sched_getaffinity"):
        beyond = max(os.sched_getaffinity(0)) + 1
        far = _run([*args, "--cpu", str(beyond)])
        assert far.returncode != 0 and f"--cpu {beyond}" in far.stderr
    wrong = _run([str(BENCH / "interleaved.py"), sys.executable, sys.executable, "--generated",
                  "128x96"])
    assert wrong.returncode != 0 and "WxH/BOX" in wrong.stderr
    bad = _run([*args[:2], str(tmp_path / "no-python"), *args[3:]])
    assert bad.returncode != 0 and "cannot run" in bad.stderr and "no-python" in bad.stderr


def test_devset_counts_only_annotated_frames_of_a_sparse_sequence(tmp_path: Path) -> None:
    """A sequence its pool calls sparse (``_meta.json``): a missing box there is "not
    annotated", so those frames are neither absent nor off target in the lost-flag shares;
    elsewhere a missing box is an absent target."""
    sys.path.insert(0, str(BENCH))
    import devset

    (tmp_path / "_meta.json").write_text(json.dumps({
        "Sparse": {"gt_format": "annotated every 5th frame", "notes": "sparse: NaN = not annotated"},
        "Dense": {"gt_format": "x,y,w,h", "notes": "NaN = absent"}}))
    assert devset.sparse_sequences([tmp_path, tmp_path / "none"]) == {"Sparse"}
    gt = np.array([[0, 0, 10, 10], [np.nan] * 4, [0, 0, 10, 10], [np.nan] * 4], dtype=float)
    boxes = [[0.0, 0.0, 10.0, 10.0]] * 4
    runs = [{"name": n, "seed": 0, "boxes": boxes, "lost": [False, True, False, True],
             "seconds": 1.0, "updates": 3} for n in ("Sparse", "Dense")]
    s = devset.summarise(runs, {"Sparse": gt, "Dense": gt}, ["Dense", "Sparse"], {"Sparse"})
    # off target: only Dense's two absent frames (both flagged); Sparse's NaN frames left out
    assert s["frames_off_target"] == 2 and s["off_target_flagged_lost"] == 1.0
    assert s["frames_well_tracked"] == 2 and s["well_tracked_flagged_lost"] == 0.0
    everything = devset.summarise(runs, {"Sparse": gt, "Dense": gt}, ["Dense", "Sparse"])
    assert everything["frames_off_target"] == 4
