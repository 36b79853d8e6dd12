"""Shared pytest fixtures, and the ``extras`` marker's rule.

Tests of an optional extra (the ``integrations`` and ``cluster`` packages, or the C++ benchmarks
built by ``benchmarks/cpp/run.sh``) carry ``@pytest.mark.extras(...)``. Without what they need
they are skipped with the reason, so that the README's bare set-up (``pip install ".[test]"``,
``python -m pytest``) passes; with ``WMILTRACK_REQUIRE_EXTRAS=1`` (``.ci/run``'s second test step,
after it installed the extras) the same absence is a failure, so no skip hides a check in CI.
"""

from __future__ import annotations

import contextlib
import importlib
import importlib.util
import os
from collections.abc import Iterator
from pathlib import Path
from types import ModuleType
from typing import NoReturn

import pytest

OTB_ENV = "WMILTRACK_OTB"
REQUIRE_EXTRAS_ENV = "WMILTRACK_REQUIRE_EXTRAS"
REPO_ROOT = Path(__file__).resolve().parent.parent

#: Top-level module -> the extra of pyproject.toml that installs it.
EXTRA_OF = {"got10k": "integrations", "six": "integrations", "trax": "integrations",
            "distributed": "cluster", "dask": "cluster", "onnxruntime": "nano", "onnx": "nano"}


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


MODELS_ENV = "WMILTRACK_TEST_MODELS"
#: NanoTrack's two files per version, in ``<root>/v3/`` (``shared/models/nanotrack``'s layout) or
#: ``<root>/nanotrack-v3/`` (the models folder's, as ``wmiltrack models fetch`` leaves it).
NANOTRACK_FILES = {"v2": ("nanotrack_backbone_sim.onnx", "nanotrack_head_sim.onnx"),
                   "v3": ("nanotrack_backbone.onnx", "nanotrack_head.onnx")}
#: How to get NanoTrack's files for the tests, in skip and failure messages.
MODELS_HINT = (f"fetch them (`wmiltrack models fetch nanotrack-v3`, `wmiltrack models fetch "
               f"nanotrack-v2`) and set {MODELS_ENV} to the models folder `wmiltrack models list` "
               "names, or to a folder with v2/ and v3/ holding them")


def _shared_models() -> Path:
    env = os.environ.get(MODELS_ENV, "").strip()
    return Path(env).expanduser() if env else REPO_ROOT.parent / "shared" / "models" / "nanotrack"


def _real_nanotrack(root: Path) -> dict[str, tuple[Path, Path]]:
    """Each version's files under ``root``, in either layout (the ``v3/`` one when neither
    holds them, for the message)."""
    out = {}
    for version, (backbone, head) in NANOTRACK_FILES.items():
        pairs = [(root / d / backbone, root / d / head) for d in (version, f"nanotrack-{version}")]
        out[version] = next((p for p in pairs if p[0].is_file() and p[1].is_file()), pairs[0])
    return out


def real_files_missing(reason: str) -> NoReturn:
    """Skip a test that needs NanoTrack's real files with ``reason`` and how to get them, or
    fail with it under CI (env ``CI`` set)."""
    msg = f"{reason}; {MODELS_HINT}"
    if os.environ.get("CI"):
        pytest.fail(msg)
    pytest.skip(msg)


@pytest.fixture(scope="session")
def nanotrack_models() -> dict[str, tuple[Path, Path]]:
    """NanoTrack's real model files by version (never part of the project), for the tests of
    NanoTrack itself (its step, its accuracy): ``$WMILTRACK_TEST_MODELS`` if set, else
    ``<repo root>/../shared/models/nanotrack``. Missing: a failure under CI (env ``CI`` set),
    a skip elsewhere. Tests of the network expert's logic take :func:`nano_network`."""
    root = _shared_models()
    files = _real_nanotrack(root)
    if not all(p.is_file() for pair in files.values() for p in pair):
        real_files_missing(f"NanoTrack's model files not found in {root} (v2/ and v3/, or "
                           "nanotrack-v2/ and nanotrack-v3/)")
    return files


@pytest.fixture(scope="session")
def stand_in_networks(tmp_path_factory: pytest.TempPathFactory) -> dict[str, tuple[Path, Path]]:
    """Stand-in networks with NanoTrack's inputs, outputs and shapes, by version, written for
    this session from seeded weights (``stand_in_networks.py``; needs ``onnx``, in the
    ``test`` extra)."""
    if importlib.util.find_spec("onnx") is None:
        skip_or_fail("onnx not installed: it writes the stand-in networks (pip install '.[test]')")
    from stand_in_networks import write_stand_ins

    return write_stand_ins(tmp_path_factory.mktemp("stand_in_networks"))


@pytest.fixture(scope="session")
def nano_network(request: pytest.FixtureRequest) -> dict[str, tuple[Path, Path]]:
    """Model files for the tests of the network expert's logic (the judge, re-detection,
    recentring, copies, the bad-input matrix), by version: NanoTrack's real files when they
    are there (:func:`nanotrack_models`'s places), else the stand-ins, so that those tests run
    on a bare clone too."""
    real = _real_nanotrack(_shared_models())
    if all(p.is_file() for pair in real.values() for p in pair):
        return real
    files: dict[str, tuple[Path, Path]] = request.getfixturevalue("stand_in_networks")
    return files


@contextlib.contextmanager
def nano_files_in_environment(files: tuple[Path, Path]) -> Iterator[None]:
    """``WMILTRACK_NANO_BACKBONE`` / ``WMILTRACK_NANO_HEAD`` set to ``files`` meanwhile, so
    that a tracker made by preset name (``Tracker("rcwmil-nano")``), here or in a child
    process, runs on them."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("WMILTRACK_NANO_BACKBONE", str(files[0]))
        mp.setenv("WMILTRACK_NANO_HEAD", str(files[1]))
        yield


@pytest.fixture
def nano_in_environment(nano_network: dict[str, tuple[Path, Path]]) -> Iterator[tuple[Path, Path]]:
    """:func:`nano_network`'s v3 files (rcwmil-nano's network) in the environment for the test
    (:func:`nano_files_in_environment`): for tests that go over every preset by name."""
    with nano_files_in_environment(nano_network["v3"]):
        yield nano_network["v3"]


@pytest.fixture(scope="session", autouse=True)
def _models_folder(tmp_path_factory: pytest.TempPathFactory) -> object:
    """A models folder (``WMILTRACK_MODELS``) laid out as ``wmiltrack models fetch`` leaves it,
    its files linked to NanoTrack's shared copies when they are there, so that every preset,
    rcwmil-nano included, can start in tests that go over all presets. A test of the lookup
    sets its own folder."""
    folder = tmp_path_factory.mktemp("models")
    for version, files in _real_nanotrack(_shared_models()).items():
        (folder / f"nanotrack-{version}").mkdir()
        for path in files:
            if path.is_file():
                (folder / f"nanotrack-{version}" / path.name).symlink_to(path.resolve())
    before = {k: os.environ.get(k) for k in ("WMILTRACK_MODELS", "WMILTRACK_NANO_BACKBONE",
                                              "WMILTRACK_NANO_HEAD")}
    os.environ["WMILTRACK_MODELS"] = str(folder)
    for k in ("WMILTRACK_NANO_BACKBONE", "WMILTRACK_NANO_HEAD"):
        os.environ.pop(k, None)
    yield folder
    for k, v in before.items():
        if v is None:
            os.environ.pop(k, None)
        else:
            os.environ[k] = v


@pytest.fixture(autouse=True)
def _model_variables_restored() -> object:
    """The model files' environment variables as they were before each test: the command line
    puts ``--nano-backbone``/``--nano-head`` there for the run (and rcwmil-nano reads them too),
    so a test that runs ``main()`` in this process must not leave its files to the next one."""
    keys = ("WMILTRACK_MODELS", "WMILTRACK_NANO_BACKBONE", "WMILTRACK_NANO_HEAD")
    before = {k: os.environ.get(k) for k in keys}
    yield
    for k, v in before.items():
        if v is None:
            os.environ.pop(k, None)
        else:
            os.environ[k] = v


#: The variables that give NanoTrack's files to every tracker that runs it.
NANO_ENV = ("WMILTRACK_NANO_BACKBONE", "WMILTRACK_NANO_HEAD")


@pytest.fixture()
def no_models(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """An empty models folder and no model file in the environment."""
    for name in NANO_ENV:
        monkeypatch.delenv(name, raising=False)
    folder = tmp_path / "no-models"
    folder.mkdir()
    monkeypatch.setenv("WMILTRACK_MODELS", str(folder))
    return folder
