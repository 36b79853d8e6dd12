"""The Siamese network families wmiltrack can run, and the one function that builds a network's
tracking step from the name of its model set (``"nanotrack-v3"``).

A family is a module of :mod:`wmiltrack.networks` with a function that builds its step from a
version, its files (``backbone``, ``head``: None finds them as
:func:`~wmiltrack.networks.files.find_files` says), a runtime, a number of threads and the crop
side of its narrow search (``narrow``, 0: none); it is
listed in :data:`FAMILIES`, and its versions are its sets in
:data:`~wmiltrack.networks.files.MODELS`.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from .files import MODELS
from .nanotrack import nanotrack_step
from .siamese import SiameseStep

__all__ = ["FAMILIES", "check_siamese", "load_siamese", "siamese_networks"]

FAMILIES: dict[str, Callable[..., SiameseStep]] = {"nanotrack": nanotrack_step}
"""Each family's builder: ``builder(version, *, backbone, head, runtime, threads, narrow)``."""


def siamese_networks() -> tuple[str, ...]:
    """The model sets that are Siamese networks wmiltrack runs: ``("nanotrack-v2",
    "nanotrack-v3")``."""
    return tuple(name for name, s in MODELS.items() if s.family in FAMILIES)


def load_siamese(network: str, *, backbone: str | Path | None = None,
                 head: str | Path | None = None, runtime: str = "auto",
                 threads: int = 1, narrow: int = 0) -> SiameseStep:
    """The tracking step of the model set ``network`` (one of :func:`siamese_networks`), its
    files given or found, run by ``runtime`` (``"auto"``, ``"onnxruntime"``, ``"opencv"``) on
    ``threads`` threads, with a narrow search over a crop of ``narrow`` px (0: none)."""
    if network not in siamese_networks():
        raise ValueError(f"no Siamese network {network!r}; the networks are "
                         f"{', '.join(siamese_networks())}")
    s = MODELS[network]
    return FAMILIES[s.family](s.version, backbone=backbone, head=head, runtime=runtime,
                              threads=threads, narrow=narrow)


_CHECKED: set[tuple[object, ...]] = set()


def check_siamese(network: str, *, backbone: Path, head: Path, runtime: str = "auto",
                  threads: int = 1, narrow: int = 0) -> None:
    """Load the files of ``network`` as :func:`load_siamese` does, so that a file that cannot
    be run (empty, corrupt, truncated, another role's) is a
    :class:`~wmiltrack.networks.files.ModelFileUnreadable` when a tracker is built, not at its
    first frame. Done once per file (path, size and time of change) and runtime: a tracker
    built again and again (``eval``'s runs) pays for one load."""
    key = (network, runtime, threads, narrow,
           *((str(p), p.stat().st_size, p.stat().st_mtime_ns) if p.is_file() else (str(p),)
             for p in (Path(backbone), Path(head))))
    if key in _CHECKED:
        return
    load_siamese(network, backbone=backbone, head=head, runtime=runtime, threads=threads,
                 narrow=narrow)
    _CHECKED.add(key)
