"""Shared pytest fixtures."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

OTB_ENV = "WMILTRACK_OTB"
REPO_ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="session")
def otb_root() -> Path:
    """Folder holding the real OTB sequences.

    ``$WMILTRACK_OTB`` if set, else ``<repo root>/../shared/data/otb``. When the folder is
    missing the test fails under CI (env ``CI`` set) and is skipped elsewhere.
    """
    env = os.environ.get(OTB_ENV, "").strip()
    root = Path(env).expanduser() if env else (REPO_ROOT.parent / "shared" / "data" / "otb")
    if not root.is_dir():
        msg = f"OTB data not found at {root}; set {OTB_ENV} to the folder holding the sequences"
        if os.environ.get("CI"):
            pytest.fail(msg)
        pytest.skip(msg)
    return root.resolve()
