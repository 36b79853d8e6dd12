"""One exit-status table for every subcommand (``wmiltrack.cli.options.EXIT_CODES``): 0 done,
1 the run failed, 2 bad command line or input (refused before anything ran), 130 Ctrl-C (one
line, no traceback), 141 standard output closed by its reader (quietly). Each ``--help`` shows
the table."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from conftest import write_generated_otb

from wmiltrack.cli import main
from wmiltrack.cli.options import EXIT_CODES, EXIT_CODES_EPILOG

SUBCOMMANDS = ("track", "inspect", "eval", "demo", "variants")


def run_main(*args: str) -> int:
    """``main`` as the shell sees it: argparse's own errors exit through SystemExit."""
    try:
        return main(list(args))
    except SystemExit as exc:
        return int(exc.code or 0)


def run(*args: str, **kw: object) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "wmiltrack", *args], capture_output=True, text=True,
                          timeout=300, env={**os.environ, "WMILTRACK_NO_PROGRESS": "1"}, **kw)  # type: ignore[call-overload]


@pytest.fixture(scope="module")
def seq(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("data")
    write_generated_otb(root, "Seq", seed=1, n=8)
    return root / "Seq"


def test_the_table_says_what_the_status_of_each_outcome_means(seq: Path, tmp_path: Path) -> None:
    """Each outcome's status, as the commands return it, is in the table under its meaning,
    and the epilog every ``--help`` shows lists the whole table."""
    outcomes = [
        (run_main("variants", "rcwmil"), "done"),
        (run_main("track", str(seq), "-q", "-o", str(tmp_path / "b.txt")), "done"),
        (run_main("track", str(seq), "--box", "1,2,3"), "bad command line"),
        (run_main("variants", "nope"), "bad command line"),
        (closed_pipe("variants")[0], "standard output closed by its reader"),
    ]
    if Path("/dev/full").exists():
        outcomes.append((run_main("track", str(seq), "-o", "/dev/full"), "the run failed"))
    for status, meaning in outcomes:
        assert EXIT_CODES.get(status, "").startswith(meaning), (status, meaning)
    for status, meaning in EXIT_CODES.items():
        assert f"{status} {meaning}" in EXIT_CODES_EPILOG


@pytest.mark.parametrize("cmd", (None, *SUBCOMMANDS))
def test_every_help_shows_the_table(cmd: str | None, capsys: pytest.CaptureFixture[str]) -> None:
    assert run_main(*([cmd] if cmd else []), "--help") == 0
    text = " ".join(capsys.readouterr().out.split())
    assert EXIT_CODES_EPILOG in text


def unknown_tracker_args(cmd: str, seq: Path, tmp_path: Path) -> list[str]:
    return {
        "track": ["track", str(seq), "-t", "nope"],
        "inspect": ["inspect", str(seq), "-t", "nope", "-o", str(tmp_path / "s.png")],
        "eval": ["eval", str(seq.parent), "--trackers", "rcwmil,nope", "--out", str(tmp_path / "o")],
        "demo": ["demo", "--trackers", "nope", "--frames", "5"],
        "variants": ["variants", "nope"],
    }[cmd]


@pytest.mark.parametrize("cmd", SUBCOMMANDS)
def test_an_unknown_tracker_is_2_everywhere(cmd: str, seq: Path, tmp_path: Path,
                                            capsys: pytest.CaptureFixture[str]) -> None:
    assert run_main(*unknown_tracker_args(cmd, seq, tmp_path)) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith("wmiltrack: error: unknown")
    assert not (tmp_path / "o").exists() and not (tmp_path / "s.png").exists()


@pytest.mark.parametrize("cmd", ["track", "inspect"])
@pytest.mark.parametrize("box", ["1,2,3", "10,10,-40,40", "10,10,40,0", "nan,10,40,40", "10,inf,40,40"])
def test_a_bad_box_is_2(cmd: str, box: str, seq: Path, tmp_path: Path) -> None:
    extra = ["-o", str(tmp_path / "s.png")] if cmd == "inspect" else []
    assert run_main(cmd, str(seq), f"--box={box}", *extra) == 2


def test_a_box_wholly_outside_the_frame_is_2(seq: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert run_main("track", str(seq), "--box", "500,500,20,20") == 2
    assert "wholly outside" in capsys.readouterr().err


def test_a_box_partly_outside_the_frame_is_warned_about(seq: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert run_main("track", str(seq), "--box", "110,10,40,30", "-q") == 0
    captured = capsys.readouterr()
    assert "warning: box 110,10,40,30 reaches past the 128x96 frame" in captured.err
    assert captured.out.splitlines()[0] == "110,10,18,30"
    assert run_main("track", str(seq), "--box", "10.4,10,40,30", "-q") == 0  # rounding: no word
    assert "warning" not in capsys.readouterr().err


def closed_pipe(*args: str) -> tuple[int, str]:
    """Run with standard output a pipe whose reader is gone before anything is written."""
    r, w = os.pipe()
    proc = subprocess.Popen([sys.executable, "-m", "wmiltrack", *args], stdout=w,
                            stderr=subprocess.PIPE, env={**os.environ, "WMILTRACK_NO_PROGRESS": "1"})
    os.close(w)
    os.close(r)
    _, err = proc.communicate(timeout=300)
    return proc.returncode, err.decode()


@pytest.mark.parametrize("cmd", ["track", "variants", "demo", "eval"])
def test_a_closed_pipe_is_141_quietly(cmd: str, seq: Path, tmp_path: Path) -> None:
    args = {"track": ["track", str(seq)], "variants": ["variants"],
            "demo": ["demo", "--frames", "10"],
            "eval": ["eval", str(seq.parent), "--out", str(tmp_path / "o"), "--no-progress"]}[cmd]
    status, err = closed_pipe(*args)
    assert (status, err) == (141, "")


def test_a_write_failure_is_1_and_the_summary_does_not_claim_the_boxes(
        seq: Path, capsys: pytest.CaptureFixture[str]) -> None:
    if not Path("/dev/full").exists():
        pytest.skip("no /dev/full on this system")
    assert run_main("track", str(seq), "-o", "/dev/full") == 1
    err = capsys.readouterr().err
    assert "cannot write the boxes" in err and "boxes in /dev/full" not in err


def _default_sigint() -> None:
    """In the child: Ctrl-C's default action, even when the tests run where SIGINT is ignored
    (a shell's background job), which Python would otherwise inherit."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def test_eval_interrupted_is_130_in_one_line(tmp_path: Path) -> None:
    """Ctrl-C reaches the whole process group (the workers too): one line, no traceback."""
    root = tmp_path / "data"
    for k in range(4):
        write_generated_otb(root, f"S{k}", seed=k, n=150)
    out = tmp_path / "out"
    proc = subprocess.Popen([sys.executable, "-m", "wmiltrack", "eval", str(root), "--trackers", "mil",
                             "--repeats", "4", "-j", "2", "--out", str(out), "--no-progress"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True, preexec_fn=_default_sigint)
    deadline = time.monotonic() + 120
    while not (out / "boxes").exists() and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)
    time.sleep(0.5)  # the workers are running
    assert proc.poll() is None, "eval finished before it could be interrupted"
    os.killpg(proc.pid, signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130
    assert err.strip().splitlines() == ["wmiltrack: interrupted by SIGINT (Ctrl-C); what was finished is written"]


def test_track_scores_and_quiet(seq: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "b.txt"
    assert run_main("track", str(seq), "--scores", "-q", "-o", str(out)) == 0
    assert capsys.readouterr().err == ""  # --quiet: no summary
    rows = [line.split(",") for line in out.read_text().splitlines()]
    assert len(rows) == 8 and all(len(r) == 6 for r in rows)
    assert rows[0][4:] == ["1", "1"]
    for r in rows[1:]:
        assert 0.0 <= float(r[4]) <= 1.0 and r[5] in ("0", "1")
    plain = tmp_path / "p.txt"
    assert run_main("track", str(seq), "-o", str(plain)) == 0
    assert "frames" in capsys.readouterr().err  # without --quiet: the summary
    assert [r[:4] for r in rows] == [line.split(",") for line in plain.read_text().splitlines()]
    assert run_main("track", str(seq), "--boxes", str(plain), "--scores") == 2


def test_variants_json(capsys: pytest.CaptureFixture[str]) -> None:
    from wmiltrack.engine.params import VARIANTS

    assert run_main("variants", "--json") == 0
    doc = json.loads(capsys.readouterr().out)
    assert list(doc) == list(VARIANTS)
    for name, p in VARIANTS.items():
        assert doc[name]["num_selected"] == p.num_selected
        assert doc[name]["description"] == p.description
    assert run_main("variants", "rcwmil-cf", "--json") == 0
    assert list(json.loads(capsys.readouterr().out)) == ["rcwmil-cf"]
