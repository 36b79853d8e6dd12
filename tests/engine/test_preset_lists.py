"""Every list of presets the package shows comes from the preset registry
(:data:`wmiltrack.engine.params.VARIANTS`): the help of each command, the compat classes, the
docstrings (which point at the registry instead of listing names) and the docs' introductions."""

from __future__ import annotations

import re

import pytest
from conftest import REPO_ROOT

from wmiltrack.engine import params as params_module
from wmiltrack.engine.params import VARIANTS

ROOT = REPO_ROOT
PRESET = re.compile(r"(?<![\w-])(" + "|".join(sorted(map(re.escape, VARIANTS), key=len, reverse=True))
                    + r")(?![\w-])")
COMMANDS = ("track", "inspect", "eval", "demo")


def command_help(cmd: str) -> str:
    from wmiltrack.cli import build_parser

    parser = build_parser()
    sub = next(a for a in parser._actions if getattr(a, "choices", None))  # noqa: SLF001
    return " ".join(sub.choices[cmd].format_help().split())


@pytest.mark.parametrize("cmd", COMMANDS)
def test_each_command_lists_the_registry_in_its_help(cmd: str, monkeypatch: pytest.MonkeyPatch) -> None:
    assert ", ".join(VARIANTS) in command_help(cmd)
    # a preset added to the registry shows up without touching the help text
    monkeypatch.setitem(params_module.VARIANTS, "zz-new-preset", VARIANTS["rcwmil"])
    assert "zz-new-preset" in command_help(cmd)


@pytest.mark.parametrize("cmd", COMMANDS)
def test_no_help_ranks_a_preset_by_hand(cmd: str) -> None:
    """'most accurate' was written beside rcwmil-plus, and stayed when rcwmil-cf came."""
    assert "most accurate" not in command_help(cmd)


@pytest.mark.usefixtures("nano_in_environment")  # (rcwmil-nano checks its files when made)
def test_every_preset_has_its_compat_class() -> None:
    from wmiltrack import compat

    assert set(compat.COMPAT_CLASSES) == set(VARIANTS)
    for name, cls in compat.COMPAT_CLASSES.items():
        assert cls.__name__ in compat.__all__ and getattr(compat, cls.__name__) is cls
        assert cls.create().tracker.variant == name
    assert compat.TrackerRCWMILCF.create().tracker.variant == "rcwmil-cf"


def hand_written_lists(text: str) -> list[str]:
    """Lines that name three or more presets as code (quoted or in backticks): a list of
    presets written by hand."""
    out = []
    for line in text.splitlines():
        quoted = set(re.findall(r"[\"'`]{1,2}(" + PRESET.pattern + r")[\"'`]{1,2}", line))
        if len({q[0] for q in quoted}) >= 3:
            out.append(line.strip())
    return out


def test_no_source_file_lists_presets_by_hand() -> None:
    found = {}
    for path in sorted((ROOT / "src" / "wmiltrack").rglob("*.py")):
        if path.name == "params.py" and path.parent.name == "engine":
            continue  # the registry itself
        lines = hand_written_lists(path.read_text(encoding="utf-8"))
        if lines:
            found[str(path.relative_to(ROOT))] = lines
    assert not found, f"presets listed by hand (build the list from VARIANTS instead): {found}"


def test_the_checker_sees_a_hand_written_list() -> None:
    assert hand_written_lists('    ``"rcwmil"``, ``"ct"`` or ``"rcwmil-plus"``; see variants')
    assert not hand_written_lists("    a key of :func:`wmiltrack.variants` such as ``\"rcwmil\"``")


@pytest.mark.parametrize("page", ["README.md", "docs/index.md"])
def test_front_pages_introduce_every_preset(page: str) -> None:
    """The introduction (up to the first heading after the title) names each preset in bold."""
    text = (ROOT / page).read_text(encoding="utf-8")
    intro = text.split("\n## ")[0]
    named = set(re.findall(r"\*\*(" + PRESET.pattern + r")\*\*", intro))
    assert {n[0] for n in named} == set(VARIANTS), page


@pytest.mark.parametrize("page", ["README.md", "docs/integrations.md", "docs/api.md"])
def test_pages_that_name_the_compat_classes_name_them_all(page: str) -> None:
    from wmiltrack import compat

    text = (ROOT / page).read_text(encoding="utf-8")
    missing = [cls.__name__ for cls in compat.COMPAT_CLASSES.values()
               if not re.search(rf"\b{cls.__name__}\b", text)]
    assert not missing, f"{page} does not name {missing}"


def test_the_trackers_pages_variant_table_has_every_preset() -> None:
    text = (ROOT / "docs" / "trackers.md").read_text(encoding="utf-8")
    table = text[text.index("| variant | features |"):]
    table = table[:table.index("\n\n")]
    names = re.findall(r"^\| \*\*([\w-]+)\*\* \|", table, flags=re.MULTILINE)
    assert names == list(VARIANTS)
