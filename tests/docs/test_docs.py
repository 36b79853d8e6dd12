"""The docs agree with the README and render: the README's table is the performance page's
(compared as tables, so both can change together), every figure the README's "Which tracker to
pick" states is on the performance page, every Markdown table can render (a blank line before
it), and the API page shows no raw Sphinx role."""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path

import pytest
from conftest import REPO_ROOT

ROOT = REPO_ROOT
README = ROOT / "README.md"
PERFORMANCE = ROOT / "docs" / "performance.md"


def tables(text: str) -> list[list[list[str]]]:
    """Every Markdown table of ``text``: rows of stripped cells (the rule line left out)."""
    out: list[list[list[str]]] = []
    current: list[list[str]] = []
    for line in [*text.splitlines(), ""]:
        s = line.strip()
        if s.startswith("|"):
            cells = [c.strip() for c in s.strip("|").split("|")]
            if not all(re.fullmatch(r":?-+:?", c) for c in cells):
                current.append(cells)
        elif current:
            out.append(current)
            current = []
    return out


def readme_section() -> str:
    text = README.read_text(encoding="utf-8")
    return text.split("## Which tracker to pick", 1)[1].split("\n## ", 1)[0]


def test_the_readme_table_is_the_performance_pages() -> None:
    (readme_table,) = tables(readme_section())
    same_head = [t for t in tables(PERFORMANCE.read_text(encoding="utf-8")) if t[0] == readme_table[0]]
    assert same_head, "the performance page has no table with the README table's header"
    assert readme_table in same_head, "the README table differs from the performance page's"


def numbers(text: str) -> set[str]:
    """The figures of ``text``: thousands written with a space joined (``1 941`` -> ``1941``),
    every number of a range on its own."""
    text = re.sub(r"(?<=\d)[ \u2009\u202f](?=\d{3}\b)", "", text)
    return set(re.findall(r"\d+(?:\.\d+)?", text))


def test_every_readme_figure_is_on_the_performance_page() -> None:
    missing = numbers(readme_section()) - numbers(PERFORMANCE.read_text(encoding="utf-8"))
    assert not missing, f"README figures the performance page does not state: {sorted(missing)}"


def test_the_figure_check_sees_a_new_figure() -> None:
    assert "1234" in numbers("about 1 234 updates") and "0.512" in numbers("0.512–0.6")


def unrenderable_tables(text: str) -> list[int]:
    """Lines that start a table directly under other text (Python-Markdown then shows it as
    text): the header row of a table whose previous line is not blank."""
    lines = text.splitlines()
    bad, in_code = [], False
    for i, line in enumerate(lines):
        if line.lstrip().startswith("```"):
            in_code = not in_code
        if in_code or i < 1 or i + 1 >= len(lines):
            continue
        rule = lines[i + 1].strip()
        starts = line.lstrip().startswith("|") and re.fullmatch(r"\|?(\s*:?-+:?\s*\|)+\s*(:?-+:?)?\s*", rule)
        if starts and lines[i - 1].strip():
            bad.append(i + 1)
    return bad


@pytest.mark.parametrize("page", sorted(p.name for p in (ROOT / "docs").glob("*.md")))
def test_every_table_can_render(page: str) -> None:
    assert unrenderable_tables((ROOT / "docs" / page).read_text(encoding="utf-8")) == []


def test_the_table_check_sees_a_table_glued_to_text() -> None:
    assert unrenderable_tables("* item:\n  | a | b |\n  |---|---|\n  | 1 | 2 |\n") == [2]
    assert unrenderable_tables("* item:\n\n  | a | b |\n  |---|---|\n") == []


def load_hook() -> object:
    spec = importlib.util.spec_from_file_location("sphinx_roles", ROOT / "docs" / "_hooks" / "sphinx_roles.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_docs_hook_turns_sphinx_roles_into_code() -> None:
    hook = load_hook()
    html = "see :class:<code>~wmiltrack.Params</code> and :func:<code>wmiltrack.variants</code>."
    assert hook.strip_roles(html) == "see <code>Params</code> and <code>wmiltrack.variants</code>."  # type: ignore[attr-defined]
    assert "hooks:" in (ROOT / "mkdocs.yml").read_text() and "docs/_hooks/sphinx_roles.py" in (ROOT / "mkdocs.yml").read_text()


def test_the_site_builds_without_raw_roles_and_with_every_table(tmp_path: Path) -> None:
    """The real build (needs docs/requirements.txt; CI runs it in scripts/ci_docs.sh too)."""
    if importlib.util.find_spec("mkdocs") is None or importlib.util.find_spec("mkdocstrings") is None:
        pytest.skip("mkdocs is not installed (pip install -r docs/requirements.txt)")
    import subprocess
    import sys

    site = tmp_path / "site"
    run = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-q", "-d", str(site)],
                         cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-3000:]
    api = (site / "api" / "index.html").read_text(encoding="utf-8")
    assert not re.search(r":(class|func|meth|mod|data|attr|exc):<code>", api)
    for page in ("rcwmil-plus-log", "performance", "trackers"):
        html = (site / page / "index.html").read_text(encoding="utf-8")
        source = (ROOT / "docs" / f"{page}.md").read_text(encoding="utf-8")
        assert html.count("<table>") == len(tables(source)), page


def test_the_reliability_page_counts_the_cases_the_tests_run() -> None:
    """The bad-input matrix's size, as the reliability page states it, is what pytest collects:
    the cases of every preset (each ``preset/case``) and those that need no preset."""
    import subprocess
    import sys

    from wmiltrack.engine.params import VARIANTS

    listed = subprocess.run([sys.executable, "-m", "pytest", "--collect-only", "-q", "-p",
                             "no:cacheprovider", "tests/engine/test_reliability.py"],
                            capture_output=True, text=True, cwd=ROOT, timeout=300, check=True).stdout
    ids = re.findall(r"::test_case\[([^\]]+)\]", listed)
    per_preset = {p: sum(i.startswith(f"{p}/") for i in ids) for p in VARIANTS}
    assert len(set(per_preset.values())) == 1 and all(per_preset.values()), per_preset
    n = next(iter(per_preset.values()))
    alone = len(ids) - n * len(VARIANTS)
    page = " ".join((ROOT / "docs" / "reliability.md").read_text(encoding="utf-8").split())
    words = {6: "six", 7: "seven", 8: "eight", 9: "nine", 10: "ten"}
    presets = words.get(len(VARIANTS), str(len(VARIANTS)))
    assert (f"({len(ids)} cases: {n} for each of the {presets} presets and {alone} that need no "
            "preset") in page
