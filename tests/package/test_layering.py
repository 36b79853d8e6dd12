"""Module layering (issue 25): the command line that tracks and the integrations do not depend
on the evaluation package; only the ``eval`` command may import from ``wmiltrack.eval`` (``demo``
prints the scores the eval command gives it)."""

from __future__ import annotations

import ast
from pathlib import Path

from conftest import REPO_ROOT

PKG = REPO_ROOT / "src" / "wmiltrack"
#: Files allowed to import the evaluation package, with the reason.
ALLOWED = {
    "cli/eval.py": "the eval command itself",
}


def _imported_modules(path: Path) -> list[str]:
    """Absolute names of the modules ``path`` imports (relative imports resolved)."""
    package = ".".join(("wmiltrack", *path.relative_to(PKG).parent.parts)).rstrip(".")
    names: list[str] = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), filename=str(path))):
        if isinstance(node, ast.Import):
            names += [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - (node.level - 1)]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            names.append(mod)
            names += [f"{mod}.{a.name}" for a in node.names]  # `from .. import eval`
    return names


def test_cli_and_integrations_do_not_import_the_evaluation_package() -> None:
    offenders = []
    files = sorted((PKG / "cli").glob("*.py")) + sorted((PKG / "integrations").glob("*.py"))
    assert len(files) >= 8
    for f in files:
        rel = f.relative_to(PKG).as_posix()
        if rel in ALLOWED:
            continue
        bad = [m for m in _imported_modules(f) if m == "wmiltrack.eval" or m.startswith("wmiltrack.eval.")]
        if bad:
            offenders.append(f"{rel}: {sorted(set(bad))}")
    assert not offenders, "imports from wmiltrack.eval: " + "; ".join(offenders)


def test_the_check_sees_relative_and_absolute_imports() -> None:
    """The resolver itself: a relative import two levels up and an absolute one are caught."""
    f = PKG / "cli" / "track.py"
    names = _imported_modules(f)
    assert "wmiltrack.cli.options.tracker_from_args" in names   # `from .options import ...`
    assert "wmiltrack.trackers.make_tracker" in _imported_modules(PKG / "cli" / "options.py")  # `from ..`
    assert any(n.startswith("wmiltrack.eval.") for n in _imported_modules(PKG / "cli" / "eval.py"))
