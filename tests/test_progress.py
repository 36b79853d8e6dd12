"""Tests for wmiltrack.progress."""

from __future__ import annotations

import io
import re
from collections.abc import Generator, Iterator

import pytest

import wmiltrack.progress as prog
from wmiltrack.progress import NO_PROGRESS_ENV, format_duration, progress


class FakeClock:
    """Monotonic clock advanced by hand."""

    def __init__(self) -> None:
        self.t = 1000.0

    def __call__(self) -> float:
        return self.t


class TTY(io.StringIO):
    def isatty(self) -> bool:
        return True


@pytest.fixture
def clock(monkeypatch: pytest.MonkeyPatch) -> FakeClock:
    c = FakeClock()
    monkeypatch.setattr(prog, "_now", c)
    monkeypatch.delenv(NO_PROGRESS_ENV, raising=False)
    return c


def _ticking(n: int, clock: FakeClock, dt: float) -> Iterator[int]:
    for i in range(n):
        clock.t += dt
        yield i


def test_format_duration() -> None:
    assert format_duration(0) == "0s"
    assert format_duration(4.4) == "4s"
    assert format_duration(125) == "2m05s"
    assert format_duration(3723) == "1h02m03s"
    assert format_duration(float("inf")) == "?"
    assert format_duration(float("nan")) == "?"
    assert format_duration(-1) == "?"


def test_items_pass_through_unchanged(clock: FakeClock) -> None:
    out = io.StringIO()
    items = [object() for _ in range(7)]
    assert list(progress(items, desc="x", file=out)) == items
    assert list(progress(iter(items), enabled=False, file=out)) == items


def test_plain_output_every_ten_percent(clock: FakeClock) -> None:
    out = io.StringIO()
    result = list(progress(_ticking(150, clock, 0.04), total=150, desc="David", file=out))
    assert result == list(range(150))
    text = out.getvalue()
    assert "\r" not in text
    lines = text.splitlines()
    assert len(lines) == 10  # 15, 30, ..., 135 and the final line
    assert lines[0].startswith("David   15/150 [##------------------] 25.0 it/s ETA 5s")
    assert re.fullmatch(r"David  150/150 \[#{20}\] 25\.0 it/s in 6s", lines[-1])
    counts = [int(re.search(r"(\d+)/150", line).group(1)) for line in lines]  # type: ignore[union-attr]
    assert counts == [15, 30, 45, 60, 75, 90, 105, 120, 135, 150]


def test_total_taken_from_len(clock: FakeClock) -> None:
    out = io.StringIO()
    list(progress(list(range(20)), desc="a", file=out))
    assert out.getvalue().splitlines()[-1].startswith("a  20/20 [")


def test_small_total_prints_at_most_once_per_item(clock: FakeClock) -> None:
    out = io.StringIO()
    list(progress(_ticking(3, clock, 1.0), total=3, file=out))
    lines = out.getvalue().splitlines()
    assert [line.split(" ")[0] for line in lines] == ["1/3", "2/3", "3/3"]
    assert lines[-1].endswith("in 3s")


def test_tty_redraws_in_place_at_most_ten_per_second(clock: FakeClock) -> None:
    out = TTY()
    list(progress(_ticking(100, clock, 0.01), total=100, desc="run", file=out))
    text = out.getvalue()
    assert text.endswith("\n") and text.count("\n") == 1
    frames = text.rstrip("\n").split("\r")[1:]
    # 1 s of work at <= 10 redraws/s, plus the initial and the final draw
    assert 3 <= len(frames) <= 13
    assert frames[0].startswith("run    0/100 [--------------------] ? it/s")
    assert frames[-1].startswith("run  100/100 [####################] 100.0 it/s in 1s")
    # a shorter line overwrites a longer one completely
    assert all(len(f) >= len(frames[0].rstrip()) for f in frames)


def test_tty_without_total(clock: FakeClock) -> None:
    out = TTY()
    list(progress(_ticking(5, clock, 0.5), file=out))
    last = out.getvalue().rstrip("\n").split("\r")[-1]
    assert last.strip() == "5 [2.0 it/s] in 2s"


def test_plain_without_total_prints_every_ten_seconds(clock: FakeClock) -> None:
    out = io.StringIO()
    list(progress(_ticking(30, clock, 1.0), desc="g", file=out))
    lines = out.getvalue().splitlines()
    assert [line.split(" ")[2] for line in lines] == ["10", "20", "30", "30"]
    assert lines[-1] == "g  30 [1.0 it/s] in 30s"


def test_early_stop_still_finishes_the_line(clock: FakeClock) -> None:
    out = TTY()
    gen = progress(_ticking(50, clock, 0.1), total=50, file=out)
    assert isinstance(gen, Generator)
    for i in gen:
        if i == 9:
            break
    gen.close()
    text = out.getvalue()
    assert text.endswith("\n")
    # the item being processed when the loop broke is not counted (as in tqdm)
    assert text.rstrip("\n").split("\r")[-1].strip().startswith("9/50 [###")


def test_exception_propagates(clock: FakeClock) -> None:
    def boom() -> Iterator[int]:
        yield 1
        raise RuntimeError("bad frame")

    out = io.StringIO()
    with pytest.raises(RuntimeError, match="bad frame"):
        list(progress(boom(), total=4, file=out))
    assert out.getvalue().splitlines()[-1].startswith("1/4")


def test_disabled_and_env(clock: FakeClock, monkeypatch: pytest.MonkeyPatch) -> None:
    out = io.StringIO()
    assert list(progress(range(5), file=out, enabled=False)) == list(range(5))
    assert out.getvalue() == ""
    monkeypatch.setenv(NO_PROGRESS_ENV, "1")
    assert list(progress(range(5), file=out)) == list(range(5))
    assert out.getvalue() == ""
    list(progress(range(5), file=out, enabled=True))  # explicit True wins over the env
    assert out.getvalue() != ""
    for off in ("", "0", "false"):
        monkeypatch.setenv(NO_PROGRESS_ENV, off)
        buf = io.StringIO()
        list(progress(range(2), file=buf))
        assert buf.getvalue() != "", off


def test_default_file_is_stderr(clock: FakeClock, capsys: pytest.CaptureFixture[str]) -> None:
    list(progress(range(3), desc="err"))
    captured = capsys.readouterr()
    assert captured.out == ""
    assert "err  3/3" in captured.err


def test_empty_iterable(clock: FakeClock) -> None:
    out = io.StringIO()
    assert list(progress([], file=out)) == []
    assert out.getvalue() == "0 [? it/s] in 0s\n"


def test_not_started_prints_nothing(clock: FakeClock) -> None:
    out = io.StringIO()
    progress(range(3), file=out)
    assert out.getvalue() == ""
