"""MultiTracker: several targets in the same frames, each exactly a single Tracker."""

from __future__ import annotations

import multiprocessing
import os

import numpy as np
import pytest

import wmiltrack
from wmiltrack.data.synthetic import make_sequence
from wmiltrack.engine.multi import MultiTracker
from wmiltrack.eval.metrics import iou


@pytest.fixture(scope="module")
def two_targets() -> tuple[list[np.ndarray], list[tuple[float, ...]], np.ndarray, np.ndarray]:
    """Two generated sequences side by side: frames, first boxes, and both ground truths."""
    a = make_sequence(30, size=(120, 160), target_size=(32, 28), seed=1, occlusion=False)
    b = make_sequence(30, size=(120, 160), target_size=(28, 36), seed=2, occlusion=False)
    frames = [np.hstack([fa, fb]) for fa, fb in zip(a.load(), b.load())]
    gt_a = a.groundtruth.copy()
    gt_b = b.groundtruth.copy()
    gt_b[:, 0] += 160
    return frames, [tuple(gt_a[0]), tuple(gt_b[0])], gt_a, gt_b


def single(variant: str, seed: int, frames: list[np.ndarray], box: tuple[float, ...],
           start: int = 0) -> list[tuple[float, ...]]:
    t = wmiltrack.Tracker(variant, seed=seed)
    t.init(frames[start], box)
    return [t.update(f).box for f in frames[start + 1:]]


@pytest.mark.parametrize("variant", ["rcwmil", "mil", "rcwmil-plus", "rcwmil-cf"])
@pytest.mark.parametrize(("threads", "share"), [(1, "never"), (2, "never"), (1, "always"), (2, "always")])
def test_each_target_gives_the_boxes_of_a_single_tracker(two_targets, variant: str, threads: int,
                                                         share: str) -> None:
    frames, boxes, _, _ = two_targets
    with MultiTracker(variant, seed=5, threads=threads, share=share) as mt:
        ids = [mt.add(frames[0], b) for b in boxes]
        assert ids == [0, 1]
        got: dict[int, list[tuple[float, ...]]] = {0: [], 1: []}
        for f in frames[1:]:
            for i, r in mt.update(f).items():
                got[i].append(r.box)
            assert mt.last_shared == (share == "always")
    for i, b in enumerate(boxes):
        assert got[i] == single(variant, 5 + i, frames, b)


def test_target_added_later_matches_a_tracker_started_there(two_targets) -> None:
    frames, boxes, _, gt_b = two_targets
    mt = MultiTracker("rcwmil", seed=0, threads=2)
    mt.add(frames[0], boxes[0])
    later: list[tuple[float, ...]] = []
    for k, f in enumerate(frames[1:], start=1):
        if k == 10:
            assert mt.add(f, tuple(gt_b[10])) == 1
            continue
        res = mt.update(f)
        if k > 10:
            later.append(res[1].box)
    assert later == single("rcwmil", 1, frames, tuple(gt_b[10]), start=10)


def test_targets_follow_their_objects(two_targets) -> None:
    frames, boxes, gt_a, gt_b = two_targets
    mt = MultiTracker("rcwmil", seed=0)
    for b in boxes:
        mt.add(frames[0], b)
    got: dict[int, list[tuple[float, ...]]] = {0: [], 1: []}
    for f in frames[1:]:
        for i, r in mt.update(f).items():
            got[i].append(r.box)
    # each target overlaps its own object, not the other one
    for i, gt in enumerate((gt_a, gt_b)):
        assert iou(np.array(got[i]), gt[1:]).mean() > 0.5
        assert iou(np.array(got[i]), (gt_b, gt_a)[i][1:]).max() == 0.0


def test_remove_ids_and_len(two_targets) -> None:
    frames, boxes, _, _ = two_targets
    mt = MultiTracker("fct", seed=0, threads=1)
    a = mt.add(frames[0], boxes[0])
    b = mt.add(frames[0], boxes[1])
    assert len(mt) == 2 and mt.ids == [a, b] and a in mt
    mt.remove(a)
    assert mt.ids == [b] and len(mt) == 1 and a not in mt
    assert set(mt.update(frames[1])) == {b}
    with pytest.raises(KeyError, match="no live target"):
        mt.remove(a)
    with pytest.raises(KeyError):
        mt.remove(99)
    mt.remove(b)
    assert mt.update(frames[2]) == {}
    assert mt.add(frames[2], boxes[0]) == 2  # ids are never reused


def test_bad_box_uses_no_id_and_leaves_others_alone(two_targets) -> None:
    frames, boxes, _, _ = two_targets
    mt = MultiTracker("rcwmil", seed=3, threads=2)
    mt.add(frames[0], boxes[0])
    with pytest.raises(ValueError, match="outside"):
        mt.add(frames[0], (5000, 5000, 10, 10))
    with pytest.raises(TypeError):
        mt.add(frames[0], "1,2,3,4")
    assert mt.add(frames[0], boxes[1]) == 1
    got = [mt.update(f)[1].box for f in frames[1:]]
    assert got == single("rcwmil", 4, frames, boxes[1])


def test_bad_frame_moves_no_target(two_targets) -> None:
    frames, boxes, _, _ = two_targets
    mt = MultiTracker("rcwmil", seed=0)
    for b in boxes:
        mt.add(frames[0], b)
    before = mt.update(frames[1])
    with pytest.raises(TypeError):
        mt.update(frames[2].astype(bool))
    with pytest.raises(ValueError, match="frame size changed"):
        mt.update(frames[2][:, :200])
    after = mt.update(frames[2])
    want = [single("rcwmil", i, frames, b)[1] for i, b in enumerate(boxes)]
    assert [after[0].box, after[1].box] == want and before.keys() == after.keys()


def test_constructor_checks_arguments() -> None:
    with pytest.raises(ValueError, match="unknown variant"):
        MultiTracker("nope")
    with pytest.raises(TypeError, match="unknown parameter"):
        MultiTracker("rcwmil", bogus=1)
    with pytest.raises(ValueError, match="threads"):
        MultiTracker("rcwmil", threads=0)
    with pytest.raises(ValueError, match="seed"):
        MultiTracker("rcwmil", seed=-1)
    assert wmiltrack.MultiTracker is MultiTracker


def test_track_cli_with_boxes_writes_mot_lines(two_targets, tmp_path, capsys) -> None:
    import cv2

    from wmiltrack.cli import main

    frames, boxes, _, _ = two_targets
    folder = tmp_path / "frames"
    folder.mkdir()
    for k, f in enumerate(frames[:12]):
        cv2.imwrite(str(folder / f"{k + 1:04d}.png"), f)
    starts = tmp_path / "boxes.txt"
    starts.write_text("".join(",".join(repr(float(v)) for v in b) + "\n" for b in boxes))
    out = tmp_path / "mot.txt"
    assert main(["track", str(folder), "--boxes", str(starts), "-o", str(out), "--seed", "2"]) == 0
    assert "2 targets, 24 lines" in capsys.readouterr().err
    rows = [line.split(",") for line in out.read_text().splitlines()]
    assert len(rows) == 24 and all(len(r) == 10 and r[7:] == ["-1", "-1", "-1"] for r in rows)
    assert [(int(r[0]), int(r[1])) for r in rows] == [(k, i) for k in range(1, 13) for i in (1, 2)]
    assert [float(r[6]) for r in rows[:2]] == [1.0, 1.0]
    # the same boxes as the Python API on the decoded (lossless PNG) frames
    mt = MultiTracker("rcwmil", seed=2)
    for b in boxes:
        mt.add(frames[0], b)
    from wmiltrack.engine.frames import clip_box  # the first line: the box each tracker starts from

    h, w = frames[0].shape[:2]
    want = [tuple(float(v) for v in clip_box(b, w, h)) for b in boxes]
    for f in frames[1:12]:
        res = mt.update(f)
        want += [res[0].box, res[1].box]
    assert [tuple(float(v) for v in r[2:6]) for r in rows] == want


def test_track_cli_boxes_errors(tmp_path, capsys) -> None:
    import cv2

    from wmiltrack.cli import main

    folder = tmp_path / "frames"
    folder.mkdir()
    for k in range(3):
        cv2.imwrite(str(folder / f"{k + 1:04d}.png"), np.full((60, 80, 3), 40 * k, np.uint8))
    empty = tmp_path / "none.txt"
    empty.write_text("")
    assert main(["track", str(folder), "--boxes", str(empty)]) == 2  # bad input: 2
    assert "holds no box" in capsys.readouterr().err
    one = tmp_path / "one.txt"
    one.write_text("10,10,20,20\n")
    assert main(["track", str(folder), "--boxes", str(one), "-t", "opencv:MIL"]) == 2  # usage errors: 2
    assert "OpenCV tracker" in capsys.readouterr().err
    assert main(["track", str(folder), "--boxes", str(one), "--box", "1,1,5,5"]) == 2
    assert "not both" in capsys.readouterr().err


def test_one_integral_image_when_it_covers_fewer_pixels() -> None:
    rng = np.random.default_rng(0)
    small = [rng.integers(0, 256, (240, 320, 3), dtype=np.uint8) for _ in range(3)]
    mt = MultiTracker("rcwmil", seed=0, threads=1)
    for x, y in [(100, 80), (130, 90), (110, 120)]:  # close targets: their regions overlap
        mt.add(small[0], (x, y, 40, 40))
    mt.update(small[1])
    assert mt.last_shared
    # With two threads the separate tables are built two at a time: these regions, whose union
    # covers half their sum, are then as quick apart, and closer ones are still shared.
    two = MultiTracker("rcwmil", seed=0, threads=2)
    for x, y in [(100, 80), (130, 90), (110, 120)]:
        two.add(small[0], (x, y, 40, 40))
    two.update(small[1])
    assert not two.last_shared
    close = MultiTracker("rcwmil", seed=0, threads=2)
    for x, y in [(100, 80), (105, 85), (110, 90), (102, 88)]:
        close.add(small[0], (x, y, 40, 40))
    close.update(small[1])
    assert close.last_shared
    big = [rng.integers(0, 256, (720, 1280, 3), dtype=np.uint8) for _ in range(2)]
    far = MultiTracker("rcwmil", seed=0, threads=1)
    far.add(big[0], (40, 40, 40, 40))
    far.add(big[0], (1180, 620, 40, 40))  # the union would be nearly the whole frame
    far.update(big[1])
    assert not far.last_shared
    with pytest.raises(ValueError, match="share"):
        MultiTracker("rcwmil", share="sometimes")


def count_core_calls(monkeypatch: pytest.MonkeyPatch, *names: str) -> dict[str, int]:
    """Calls of these ``wmiltrack._core`` functions from now on (they still run), by name."""
    calls = dict.fromkeys(names, 0)
    for name in names:
        original = getattr(wmiltrack._core, name)

        def counting(*args, _name=name, _original=original):  # noqa: ANN001, ANN202
            calls[_name] += 1
            return _original(*args)

        monkeypatch.setattr(wmiltrack._core, name, counting)
    return calls


@pytest.mark.parametrize("size", [(360, 480), (120, 160)])
@pytest.mark.parametrize("variant", ["rcwmil", "ct", "fct", "mil", "wmil", "osil"])
def test_fused_frame_step_gives_the_two_call_results(variant: str, size: tuple[int, int],
                                                     monkeypatch) -> None:
    """Tracker.update makes one core call per frame for a paper preset (search, bags drawn
    in the core from the tracker's numpy generator, learning), and MultiTracker.update one for
    all its targets (on their own integral images, or on one shared table). With the bags
    sampled in Python instead (two core calls per target and frame) the results are the same
    every frame, in a large frame and in a small one where the bags are cut by the frame's
    edges."""
    from wmiltrack.engine import sampling

    seq = make_sequence(40, size=size, target_size=(40, 36), seed=3, occlusion=False)
    frames = seq.load()
    box = tuple(seq.groundtruth[0])
    h, w = size
    near = (min(box[0] + 30, w - 30), min(box[1] + 20, h - 30), 24, 24)  # shares the table

    def run(n_targets: int) -> list[list[wmiltrack.TrackResult]]:
        with MultiTracker(variant, seed=7, share="always") as mt:
            for b in (box, near)[:n_targets]:
                mt.add(frames[0], b)
            out = []
            for f in frames[1:]:
                found = mt.update(f)
                assert mt.last_shared == (n_targets > 1)
                out.append([found[i] for i in range(n_targets)])
        return out

    def alone() -> list[wmiltrack.TrackResult]:
        t = wmiltrack.Tracker(variant, seed=7)
        t.init(frames[0], box)
        return [t.update(f) for f in frames[1:]]

    with monkeypatch.context() as m:  # the two-call step: draws in Python
        m.setattr(sampling, "core_draws_match_numpy", lambda: False)
        m.setattr(wmiltrack._core, "frame_step", None)  # must not be called
        m.setattr(wmiltrack._core, "frame_step_many", None)
        separate, separate_two = alone(), run(2)
    calls = count_core_calls(monkeypatch, "frame_step", "frame_step_many")
    assert alone() == separate
    assert calls["frame_step"] == len(frames) - 1
    assert [r[0] for r in run(1)] == separate
    assert run(2) == separate_two
    assert calls["frame_step_many"] == 2 * (len(frames) - 1)


@pytest.mark.parametrize("variant", ["rcwmil-plus", "rcwmil-cf"])
def test_learning_at_a_box_draws_the_bags_of_the_python_sampler(variant: str, monkeypatch) -> None:
    """A preset of several parts learns with one core call that draws the bags around the
    box it chose (``_core.learn_at``; ``learn_at_many`` for a MultiTracker's targets): the
    same results every frame as bags sampled in Python, here with the box near the frame's
    edges too (bags cut by them) and with the scale estimator's extra negatives."""
    from wmiltrack.engine.sampling import BagSampler

    seq = make_sequence(30, size=(120, 160), target_size=(40, 36), seed=3, occlusion=False)
    frames = seq.load()
    box = tuple(seq.groundtruth[0])
    other = (4, 4, 30, 26)  # in the corner: its bags are cut by the frame

    def results() -> tuple[list[wmiltrack.TrackResult], list[dict[int, wmiltrack.TrackResult]]]:
        t = wmiltrack.Tracker(variant, seed=7)
        t.init(frames[0], box)
        alone = [t.update(f) for f in frames[1:]]
        with MultiTracker(variant, seed=7, threads=2) as mt:
            for b in (box, other):
                mt.add(frames[0], b)
            together = [mt.update(f) for f in frames[1:]]
        return alone, together

    calls = count_core_calls(monkeypatch, "learn_at", "learn_at_many")
    in_core = results()
    assert calls["learn_at"] >= len(frames) - 2 and calls["learn_at_many"] >= len(frames) - 2
    with monkeypatch.context() as m:  # the bags sampled in Python
        m.setattr(BagSampler, "drawn_in_core", lambda self: False)
        m.setattr(wmiltrack._core, "learn_at", None)  # must not be called
        m.setattr(wmiltrack._core, "learn_at_many", None)
        in_python = results()
    assert in_core == in_python


@pytest.mark.parametrize(("variant", "core_call"), [("rcwmil", "frame_step"),
                                                  ("rcwmil-plus", "learn_at")])
def test_a_numpy_whose_draws_differ_keeps_the_two_call_step(variant: str, core_call: str,
                                                            monkeypatch) -> None:
    """When the core's copies of numpy's draws do not match the installed numpy (checked once
    per process), Tracker.update samples in Python and makes two core calls: same boxes. The
    same for a preset of several parts: its learning steps take bags sampled in Python (no
    ``learn_at``)."""
    from wmiltrack.engine import sampling

    seq = make_sequence(15, size=(240, 320), target_size=(40, 36), seed=4, occlusion=False)
    frames = seq.load()
    box = tuple(seq.groundtruth[0])
    expected = single(variant, 2, frames, box)
    monkeypatch.setattr(sampling, "core_draws_match_numpy", lambda: False)
    monkeypatch.setattr(wmiltrack._core, core_call, None)  # must not be called
    assert single(variant, 2, frames, box) == expected


def test_an_exact_draw_numpy_would_shuffle_stays_in_python(monkeypatch) -> None:
    """An exact negative draw from more than 10 000 offsets may take numpy's tail shuffle,
    which the core does not repeat: such a tracker samples in Python (two core calls) and still
    tracks, with the same boxes as a MultiTracker."""
    seq = make_sequence(6, size=(360, 480), target_size=(40, 36), seed=5, occlusion=False)
    frames = seq.load()
    box = tuple(seq.groundtruth[0])
    overrides = {"neg_outer": 62.0, "neg_count": 300}  # about 12 000 offsets, 300 > 12 000 // 50
    monkeypatch.setattr(wmiltrack._core, "frame_step", None)  # must not be called
    t = wmiltrack.Tracker("rcwmil", seed=1, **overrides)
    t.init(frames[0], box)
    alone = [t.update(f) for f in frames[1:]]
    with MultiTracker("rcwmil", seed=1, **overrides) as mt:
        mt.add(frames[0], box)
        together = [mt.update(f)[0] for f in frames[1:]]
    assert alone == together


def _three_targets_boxes(frames: list[np.ndarray]) -> list[tuple[float, ...]]:
    mt = MultiTracker("rcwmil", seed=0, threads=2, share="never")
    for x, y in [(20, 20), (200, 150), (100, 80)]:
        mt.add(frames[0], (x, y, 40, 40))
    return [mt.update(f)[2].box for f in frames[1:]]


@pytest.mark.skipif(not hasattr(os, "fork"), reason="needs fork (POSIX)")
def test_a_forked_process_gets_its_own_core_threads() -> None:
    # The core keeps its worker threads between calls; a child forked after the parent used
    # them has none of them and must start its own (not wait for the parent's forever).
    rng = np.random.default_rng(0)
    frames = [rng.integers(0, 256, (240, 320, 3), dtype=np.uint8) for _ in range(4)]
    here = _three_targets_boxes(frames)
    ctx = multiprocessing.get_context("fork")
    with ctx.Pool(2) as pool:
        there = pool.map_async(_three_targets_boxes, [frames, frames]).get(timeout=30)
    assert there == [here, here]


def test_add_refuses_a_frame_of_another_size(two_targets) -> None:
    """All targets follow one video: a target started on frames of another size would make
    every later update fail (for it, or for the others)."""
    frames, boxes, _, _ = two_targets
    mt = MultiTracker("rcwmil", seed=0)
    mt.add(frames[0], boxes[0])
    small = np.ascontiguousarray(frames[0][:, :200])
    with pytest.raises(ValueError, match="live targets were started on 320x120"):
        mt.add(small, (10, 10, 30, 30))
    assert mt.ids == [0]
    assert mt.add(frames[0], boxes[1]) == 1  # the refused add used up no id
    got = [mt.update(f) for f in frames[1:4]]
    assert [r[1].box for r in got] == single("rcwmil", 1, frames[:4], boxes[1])
    mt.remove(0)
    mt.remove(1)
    assert mt.add(small, (10, 10, 30, 30)) == 2  # with no live target, any size starts anew
    assert set(mt.update(small)) == {2}


@pytest.mark.parametrize("variant", ["rcwmil", "rcwmil-cf"])
def test_an_update_that_raises_changes_no_target(two_targets, variant: str) -> None:
    frames, boxes, _, _ = two_targets
    mt = MultiTracker(variant, seed=0)
    for b in boxes:
        mt.add(frames[0], b)
    mt.update(frames[1])
    for bad in (frames[2][:, :200], frames[2][:100], frames[2].astype(bool)):
        with pytest.raises((ValueError, TypeError)):
            mt.update(bad)
    later = [mt.update(f) for f in frames[2:6]]
    for i, b in enumerate(boxes):
        assert [r[i].box for r in later] == single(variant, i, frames[:6], b)[1:]
