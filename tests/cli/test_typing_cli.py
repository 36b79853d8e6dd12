"""Typed package and complete command-line help; ``wmiltrack inspect`` and ``Tracker.samples``."""

from __future__ import annotations

import argparse
from importlib import resources
from pathlib import Path

import cv2
import numpy as np
import pytest

import wmiltrack
from wmiltrack.cli import build_parser, main
from wmiltrack.data.synthetic import make_sequence
from wmiltrack.engine.sampling import disc_offsets
from wmiltrack.visualize import draw_samples, grid_offsets


def test_package_ships_type_information() -> None:
    root = resources.files("wmiltrack")
    for name in ("py.typed", "_core.pyi", "_learn.pyi"):
        assert root.joinpath(name).is_file(), name


def _subparsers(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices)
    return {}


def test_every_subcommand_has_complete_help(capsys: pytest.CaptureFixture[str]) -> None:
    parser = build_parser()
    subs = _subparsers(parser)
    assert {"track", "demo", "inspect"} <= set(subs)
    with pytest.raises(SystemExit) as e:
        main(["--help"])
    assert e.value.code == 0
    top = capsys.readouterr().out
    for name, sub in subs.items():
        assert name in top
        assert sub.description, f"{name} has no description"
        for action in sub._actions:
            if action.dest != "help":
                assert action.help, f"{name}: option {action.option_strings or action.dest} has no help"
        with pytest.raises(SystemExit) as e:
            main([name, "--help"])
        assert e.value.code == 0 and "usage:" in capsys.readouterr().out


def test_samples_are_the_bags_and_grids_of_the_last_step() -> None:
    seq = make_sequence(5, seed=2, occlusion=False, illumination=False, clutter=False)
    frames = seq.load()
    gt = np.asarray(seq.groundtruth)
    t = wmiltrack.Tracker("rcwmil", seed=0)
    t.init(frames[0], gt[0])
    assert t.samples()["search"] == []
    prev = t.samples()["box"]
    t.update(frames[1])
    s = t.samples()
    p = t.params
    assert len(s["positive"]) == len(disc_offsets(p.pos_radius)) and len(s["negative"]) == p.neg_count
    assert [(r, st) for _, r, st in s["search"]] == [(p.coarse_radius, p.coarse_step),
                                                     (p.fine_radius, p.fine_step)]
    assert s["search"][0][0] == prev
    assert np.all(np.hypot(*(s["positive"] - np.array(s["box"][:2])).T) < p.pos_radius)
    # samples() reads state only: a second tracker without the calls gives the same boxes
    u = wmiltrack.Tracker("rcwmil", seed=0)
    u.init(frames[0], gt[0])
    u.update(frames[1])
    assert t.update(frames[2]).box == u.update(frames[2]).box
    img = draw_samples(frames[1], s, scale=2)
    assert img.ndim == 3 and img.shape[2] == 3 and img.shape[0] > 22
    g = grid_offsets(25, 4)
    assert (0, 0) in map(tuple, g) and np.all(np.hypot(g[:, 0], g[:, 1]) < 25)


def test_inspect_writes_a_png(otb_root: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "s.png"
    assert main(["inspect", str(otb_root / "Crossing"), "--frame", "3", "-o", str(out)]) == 0
    img = cv2.imread(str(out))
    assert img is not None and img.shape[0] > 50
    assert "positives" in capsys.readouterr().out
