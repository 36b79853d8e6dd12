"""wmiltrack.progress: tqdm on standard error, off when WMILTRACK_NO_PROGRESS is set."""

from __future__ import annotations

import pytest

from wmiltrack.progress import NO_PROGRESS_ENV, progress


def test_items_pass_through_and_bar_is_drawn(monkeypatch: pytest.MonkeyPatch,
                                             capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.delenv(NO_PROGRESS_ENV, raising=False)
    assert list(progress(range(5), total=5, desc="seq")) == [0, 1, 2, 3, 4]
    err = capsys.readouterr().err
    assert "seq" in err and "5/5" in err


@pytest.mark.parametrize("value", ["1", "yes", "true"])
def test_environment_turns_it_off(monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str],
                                  value: str) -> None:
    monkeypatch.setenv(NO_PROGRESS_ENV, value)
    assert list(progress(range(3), desc="seq")) == [0, 1, 2]
    assert capsys.readouterr().err == ""


def test_enabled_overrides_environment(monkeypatch: pytest.MonkeyPatch,
                                       capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.setenv(NO_PROGRESS_ENV, "1")
    list(progress(range(2), total=2, desc="forced", enabled=True))
    assert "forced" in capsys.readouterr().err
