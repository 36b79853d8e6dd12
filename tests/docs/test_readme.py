"""The README's commands and code run as written.

The README's examples name a clip ``clip.mp4``, a target file ``targets.txt``, a dataset folder
``DATASET`` and a box ``(x, y, w, h)``. This test makes each of them from a generated sequence
in a temporary folder, then runs every fenced block of the README there: shell lines with bash,
Python blocks with ``exec`` (one namespace, in order). The set-up block (``pip install ...`` and
``python -m pytest``) is left out: CI runs it itself, first, exactly as written.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest
from conftest import REPO_ROOT

from wmiltrack.data.boxes import write_boxes
from wmiltrack.data.synthetic import make_preset

README = REPO_ROOT / "README.md"
N_FRAMES = 40


def _blocks(language: str) -> list[str]:
    text = README.read_text(encoding="utf-8")
    return re.findall(rf"^```{language}\n(.*?)^```", text, flags=re.S | re.M)


def _write_clip(path: Path, frames: list[np.ndarray]) -> None:
    h, w = frames[0].shape[:2]
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter.fourcc(*"mp4v"), 30.0, (w, h))
    assert writer.isOpened()
    for f in frames:
        writer.write(f)
    writer.release()


@pytest.fixture()
def readme_folder(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> dict[str, object]:
    """A folder holding the README's placeholders, made from generated sequences; cwd is it."""
    seq = make_preset("clutter", seed=0, n_frames=N_FRAMES)
    frames = seq.load()
    assert seq.groundtruth is not None
    _write_clip(tmp_path / "clip.mp4", frames)
    first = [tuple(int(round(v)) for v in seq.groundtruth[0]),
             tuple(int(round(v)) for v in seq.meta["distractors"][0, 0])]
    (tmp_path / "targets.txt").write_text("".join(",".join(map(str, b)) + "\n" for b in first))
    for name in ("Occlusion", "Clutter"):
        s = make_preset(name.lower(), seed=1, n_frames=20)
        (tmp_path / "DATASET" / name / "img").mkdir(parents=True)
        for i, f in enumerate(s.load(), start=1):
            assert cv2.imwrite(str(tmp_path / "DATASET" / name / "img" / f"{i:04d}.jpg"), f)
        assert s.groundtruth is not None
        write_boxes(tmp_path / "DATASET" / name / "groundtruth_rect.txt", s.groundtruth)
    monkeypatch.chdir(tmp_path)
    (x, y, w, h), (x2, y2, w2, h2) = first
    return {"x": x, "y": y, "w": w, "h": h, "x1": x, "y1": y, "w1": w, "h1": h,
            "x2": x2, "y2": y2, "w2": w2, "h2": h2, "frame": frames[0], "next_frame": frames[1]}


def test_readme_has_the_two_setup_commands_as_ci_runs_them() -> None:
    setup = [b for b in _blocks("bash") if "pip install" in b]
    assert len(setup) == 1
    lines = [ln.split("#")[0].strip() for ln in setup[0].splitlines() if ln.strip()]
    assert lines == ['pip install ".[test]" && wmiltrack demo', "python -m pytest"]


def test_readme_command_lines_run(readme_folder: dict[str, object], tmp_path: Path) -> None:
    commands = [ln.split("  #")[0].strip() for b in _blocks("bash") if "pip install" not in b
                for ln in b.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    assert any(c.startswith("wmiltrack track") for c in commands)
    env = {**os.environ, "PATH": os.pathsep.join([str(Path(sys.executable).parent),
                                                  os.environ.get("PATH", "")]),
           "WMILTRACK_NO_PROGRESS": "1", "MPLBACKEND": "Agg"}
    for command in commands:
        done = subprocess.run(["bash", "-c", command], cwd=tmp_path, env=env, capture_output=True,
                              text=True, timeout=600)
        assert done.returncode == 0, f"{command}\n{done.stdout}\n{done.stderr}"
    assert len((tmp_path / "boxes.txt").read_text().splitlines()) == N_FRAMES
    assert (tmp_path / "tracked.mp4").stat().st_size > 0
    tracks = (tmp_path / "tracks.txt").read_text().splitlines()
    assert len(tracks) == 2 * N_FRAMES and tracks[0].startswith("1,1,")
    assert cv2.imread(str(tmp_path / "samples.png")) is not None
    table = (tmp_path / "results" / "eval_ope.md").read_text()
    assert "| **mean (2 seq)** | rcwmil |" in table


def test_readme_python_blocks_run(readme_folder: dict[str, object]) -> None:
    namespace: dict[str, object] = {}
    blocks = _blocks("python")
    assert len(blocks) >= 3
    for code in blocks:  # each block is a snippet of its own: the placeholders afresh for each
        namespace.update(readme_folder)
        exec(compile(code, str(README), "exec"), namespace)
    r = namespace["r"]
    assert len(r.box) == 4 and 0.0 <= r.score <= 1.0        # quick start, last frame
    assert sorted(namespace["results"]) == [0, 1]             # MultiTracker, both targets
    ok, rect = namespace["ok"], namespace["rect"]             # OpenCV-style update
    assert isinstance(ok, bool) and len(rect) == 4 and all(isinstance(v, int) for v in rect)
