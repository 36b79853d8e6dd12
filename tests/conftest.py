"""Shared pytest fixtures, and the ``extras`` marker's rule.

Tests of an optional extra (the ``integrations`` and ``cluster`` packages, or the C++ benchmarks
built by ``benchmarks/cpp/run.sh``) carry ``@pytest.mark.extras(...)``. Without what they need
they are skipped with the reason, so that the README's bare set-up (``pip install ".[test]"``,
``python -m pytest``) passes; with ``WMILTRACK_REQUIRE_EXTRAS=1`` (``.ci/run``'s second test step,
after it installed the extras) the same absence is a failure, so no skip hides a check in CI.
"""

from __future__ import annotations

import importlib
import importlib.util
import os
from pathlib import Path
from types import ModuleType
from typing import NoReturn

import pytest

OTB_ENV = "WMILTRACK_OTB"
REQUIRE_EXTRAS_ENV = "WMILTRACK_REQUIRE_EXTRAS"
REPO_ROOT = Path(__file__).resolve().parent.parent

#: Top-level module -> the extra of pyproject.toml that installs it.
EXTRA_OF = {"got10k": "integrations", "six": "integrations", "trax": "integrations",
            "distributed": "cluster", "dask": "cluster"}


def write_generated_otb(root: Path, name: str, *, seed: int, n: int) -> None:
    """A tiny OTB-layout sequence ``root/name`` (``img/0001.jpg`` ..., ``groundtruth_rect.txt``)
    from ``n`` generated 128x96 frames with a 24x20 target, for tests of code that reads the
    layout."""
    import cv2
    import numpy as np

    from wmiltrack.data.synthetic import make_sequence

    seq = make_sequence(n, size=(96, 128), target_size=(24, 20), seed=seed, occlusion=False)
    d = root / name / "img"
    d.mkdir(parents=True)
    for i, f in enumerate(seq.load()):
        assert cv2.imwrite(str(d / f"{i + 1:04d}.jpg"), f)
    rows = np.asarray(seq.groundtruth)
    (root / name / "groundtruth_rect.txt").write_text(
        "\n".join(",".join(repr(float(v)) for v in row) for row in rows) + "\n")


def extras_required() -> bool:
    """True when a missing extra must fail the test instead of skipping it."""
    return os.environ.get(REQUIRE_EXTRAS_ENV, "").strip() not in ("", "0")


def skip_or_fail(reason: str) -> NoReturn:
    """Skip with ``reason``, or fail with it under ``WMILTRACK_REQUIRE_EXTRAS=1``."""
    if extras_required():
        pytest.fail(f"{reason} ({REQUIRE_EXTRAS_ENV} is set: an absent extra is an error)")
    pytest.skip(reason)


def _missing_reason(module: str) -> str:
    extra = EXTRA_OF.get(module.split(".")[0], "integrations")
    return f"{module} not installed (optional extra: pip install '.[{extra}]')"


def import_extra(module: str) -> ModuleType:
    """Import an optional extra's module at a test module's top: skip the whole test module
    when it is absent, unless ``WMILTRACK_REQUIRE_EXTRAS=1``, where the import error stands."""
    if extras_required():
        return importlib.import_module(module)
    return pytest.importorskip(module, reason=_missing_reason(module))


def pytest_runtest_setup(item: pytest.Item) -> None:
    """Apply ``@pytest.mark.extras("module", ...)``: each named top-level module must import."""
    for mark in item.iter_markers("extras"):
        for module in mark.args:
            if importlib.util.find_spec(module) is None:
                skip_or_fail(_missing_reason(module))


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
