"""wmiltrack.progress: tqdm on standard error, off when WMILTRACK_NO_PROGRESS is set."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from wmiltrack.progress import NO_PROGRESS_ENV, progress


def slow(n: int) -> Iterator[int]:
    """``range(n)`` taking longer than the half second before a bar is drawn."""
    import time

    for i in range(n):
        time.sleep(0.6 / n)
        yield i


def test_items_pass_through_and_bar_is_drawn(monkeypatch: pytest.MonkeyPatch,
                                             capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.delenv(NO_PROGRESS_ENV, raising=False)
    assert list(progress(slow(5), total=5, desc="seq")) == [0, 1, 2, 3, 4]
    err = capsys.readouterr().err
    assert "seq" in err and "5/5" in err


def test_a_run_that_stops_at_once_draws_no_bar(monkeypatch: pytest.MonkeyPatch,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    """An early error is shown alone, not after a bar drawn at 0 % and again when closed."""
    monkeypatch.delenv(NO_PROGRESS_ENV, raising=False)
    bar = progress(range(100), total=100, desc="seq")
    for _ in bar:
        break
    bar.close()
    assert capsys.readouterr().err == ""


@pytest.mark.parametrize("value", ["1", "yes", "true"])
def test_environment_turns_it_off(monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str],
                                  value: str) -> None:
    monkeypatch.setenv(NO_PROGRESS_ENV, value)
    assert list(progress(range(3), desc="seq")) == [0, 1, 2]
    assert capsys.readouterr().err == ""


def test_enabled_overrides_environment(monkeypatch: pytest.MonkeyPatch,
                                       capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.setenv(NO_PROGRESS_ENV, "1")
    list(progress(slow(4), total=4, desc="forced", enabled=True))
    assert "forced" in capsys.readouterr().err
