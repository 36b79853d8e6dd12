"""MkDocs hook: Sphinx roles in docstrings (``:class:`~wmiltrack.Params```) shown as code.

The package's docstrings are numpydoc, written for Sphinx as much as for this site; mkdocstrings
renders a role's backquoted target as code but leaves the role's name in front of it, so the API
page read ":class:`~wmiltrack.Params`". This hook drops the role: ``~a.b.C`` shows as ``C`` (as
Sphinx shows it), any other target as written. Registered in ``mkdocs.yml`` (``hooks:``).
"""

from __future__ import annotations

import re
from typing import Any

#: A role as mkdocstrings leaves it in the page's HTML: ``:func:<code>target</code>``.
ROLE = re.compile(r":(?:py:)?(?:class|func|meth|mod|data|attr|exc|obj|const|ref|term):"
                  r"<code>(~?)([^<]*)</code>")


def _code(match: re.Match[str]) -> str:
    tilde, target = match.group(1), match.group(2)
    shown = target.rsplit(".", 1)[-1] if tilde else target
    return f"<code>{shown}</code>"


def strip_roles(html: str) -> str:
    """``html`` with every Sphinx role in front of a code span removed."""
    return ROLE.sub(_code, html)


def on_page_content(html: str, **kwargs: Any) -> str:
    """MkDocs' event after a page's Markdown became HTML (docstrings included)."""
    return strip_roles(html)
