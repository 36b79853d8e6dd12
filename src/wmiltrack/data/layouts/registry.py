"""The one registry of benchmark layouts, and the entry points that use it.

A layout is a :class:`Layout`: its name, its title and what its folder should hold (for error
messages), an ``index`` that lists a folder's sequences when the folder is in this layout (each an
:class:`Entry` that loads it later) and, when the structure alone is ambiguous, a stricter
``detect`` used while guessing. Each benchmark family's module builds its layouts and calls
:func:`register_layout`; nothing else in the package names a benchmark, so adding one is one new
module and one import line in ``__init__.py`` (or a :func:`register_layout` call from outside).
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator
from collections.abc import Sequence as AbcSequence
from dataclasses import dataclass, field
from pathlib import Path

from ..sequences import Sequence, natural_key

__all__ = [
    "LAYOUT_REGISTRY",
    "Entry",
    "Layout",
    "LayoutError",
    "detect_layout",
    "iter_layout",
    "list_layout",
    "load_layout",
    "register_layout",
]


class LayoutError(ValueError):
    """A folder is not a dataset in the requested layout, or is a broken one."""


@dataclass(frozen=True)
class Entry:
    """A sequence found while listing: its name and how to load it (nothing read yet)."""

    name: str
    load: Callable[[], Sequence]


Indexer = Callable[[Path], "list[Entry] | None"]


@dataclass(frozen=True)
class Layout:
    """How one benchmark's folders are found, listed and loaded.

    ``index(folder)`` returns the folder's sequences when it is a dataset in this layout (a
    root, a split or chunk folder, or one sequence folder, as the layout allows), ``None`` when it
    is not, and raises :class:`LayoutError` when it is one but broken in a way seen while listing.
    It lists folders and may read list files, but reads no annotation and opens no image: each
    :class:`Entry` loads its sequence when asked. ``detect`` replaces ``index`` while guessing a
    folder's layout, for a layout whose structure another one shares (DTB70 and OTB). Detection
    asks layouts in increasing ``order`` (ties in registration order): the most specific
    structures first.
    """

    name: str
    title: str
    expected: str
    index: Indexer
    detect: Indexer | None = None
    aliases: tuple[str, ...] = field(default=())
    order: int = 50

    def detector(self) -> Indexer:
        """What detection calls: ``detect`` when given, else ``index``."""
        return self.detect if self.detect is not None else self.index


#: Layout name -> :class:`Layout`, in registration order. Add to it with :func:`register_layout`.
LAYOUT_REGISTRY: dict[str, Layout] = {}


def register_layout(layout: Layout) -> Layout:
    """Make ``layout`` known to :func:`detect_layout`, :func:`list_layout`, :func:`load_layout`
    and :func:`iter_layout` (and its aliases to ``layout=``); returns it.

    Raises
    ------
    ValueError
        If its name or one of its aliases is already a registered name or alias.
    """
    key = layout.name.lower()
    taken = {name for known in LAYOUT_REGISTRY.values() for name in (known.name, *known.aliases)}
    clash = sorted(taken & {key, *(a.lower() for a in layout.aliases)})
    if clash:
        raise ValueError(f"layout name(s) already registered: {', '.join(clash)}")
    LAYOUT_REGISTRY[key] = layout
    return layout


def _detection_order() -> list[Layout]:
    return sorted(LAYOUT_REGISTRY.values(), key=lambda lay: lay.order)  # stable: ties stay in order


def _normalize_layout(layout: str) -> Layout:
    key = layout.strip().lower()
    for known in LAYOUT_REGISTRY.values():
        if key == known.name or key in known.aliases:
            return known
    raise ValueError(f"unknown layout {layout!r}; choose one of {', '.join(LAYOUT_REGISTRY)}")


def _root(path: str | os.PathLike[str]) -> Path:
    p = Path(path).expanduser()
    if not p.exists():
        raise FileNotFoundError(f"dataset folder not found: {p}")
    if not p.is_dir():
        raise LayoutError(f"{p} is a file, not a dataset folder")
    return p


def _not_a(p: Path, layout: Layout) -> LayoutError:
    hint = ""
    for other in _detection_order():
        try:
            found = other.name != layout.name and other.detector()(p)
        except LayoutError:
            found = False
        if found:
            hint = f"; it looks like a {other.title} dataset (layout {other.name!r})"
            break
    return LayoutError(f"{p} is not a {layout.title} dataset: expected {layout.expected}{hint}")


def _entries(path: str | os.PathLike[str], layout: str | None) -> tuple[Layout, list[Entry]]:
    p = _root(path)
    if layout is not None:
        chosen = _normalize_layout(layout)
        found = chosen.index(p)
        if not found:
            raise _not_a(p, chosen)
        return chosen, found
    order = _detection_order()
    for candidate in order:
        found = candidate.detector()(p)
        if found:
            return candidate, found
    lines = "\n".join(f"  {lay.title}: {lay.expected}" for lay in order)
    raise LayoutError(f"{p} is not a tracking dataset in any known layout; expected one of\n{lines}")


def detect_layout(path: str | os.PathLike[str]) -> str:
    """Name the layout of a dataset folder.

    Parameters
    ----------
    path:
        Dataset root, a split or chunk folder (GOT-10k ``val/``, TrackingNet ``TRAIN_0/``), a
        LaSOT class folder, or a single sequence folder.

    Returns
    -------
    str
        One of :data:`LAYOUTS` (or of a layout registered since).  Only folders are listed: no
        annotation or image is read.

    Raises
    ------
    FileNotFoundError
        If ``path`` does not exist.
    LayoutError
        If the folder matches no layout (the message lists what each layout expects), or it
        matches one but is broken in a way seen while listing (GOT-10k or VOT ``list.txt``
        naming missing folders, several GOT-10k splits without ``val/``).
    """
    return _entries(path, None)[0].name


def list_layout(path: str | os.PathLike[str], layout: str | None = None) -> list[str]:
    """Names of the sequences of a dataset, without reading any annotation or image.

    Parameters
    ----------
    path:
        As for :func:`detect_layout`.
    layout:
        Layout name (see :data:`LAYOUTS`; ``"got-10k"`` and ``"uav"`` are accepted too), or
        ``None`` to detect it.

    Returns
    -------
    list of str
        In ``list.txt`` order where the benchmark has one, else in natural name order.
    """
    return [e.name for e in _entries(path, layout)[1]]


def _chosen(
    path: str | os.PathLike[str], layout: str | None, sequences: AbcSequence[str] | None
) -> list[Entry]:
    found, entries = _entries(path, layout)
    if sequences is None:
        return entries
    names = [sequences] if isinstance(sequences, str) else list(sequences)
    by_name = {e.name: e for e in entries}
    missing = [n for n in names if n not in by_name]
    if missing:
        avail = sorted(by_name, key=natural_key)
        shown = ", ".join(avail[:10]) + (f", ... ({len(avail)} in all)" if len(avail) > 10 else "")
        raise LayoutError(
            f"sequence(s) not in the {found.title} dataset {path}: {', '.join(missing)}; "
            f"available: {shown}"
        )
    return [by_name[n] for n in names]


def load_layout(
    path: str | os.PathLike[str],
    layout: str | None = None,
    sequences: AbcSequence[str] | None = None,
) -> list[Sequence]:
    """Load the sequences of a benchmark dataset.

    Parameters
    ----------
    path:
        As for :func:`detect_layout`.
    layout:
        Layout name, or ``None`` to detect it with :func:`detect_layout`.
    sequences:
        Names to load, in this order (a single string is one name); ``None`` loads every
        sequence.  Only the chosen sequences' annotation files are read.

    Returns
    -------
    list of Sequence
        Image-backed sequences (no image is decoded here), ground truth with ``nan`` rows on
        absent frames, and ``meta`` as described in the package documentation.  Loading costs
        folder listings and annotation parsing, roughly 10 ms per 1 000 frames: for all of LaSOT
        (3.5 M frames) prefer :func:`iter_layout`, which loads one sequence at a time.

    Raises
    ------
    FileNotFoundError
        If ``path`` does not exist.
    LayoutError
        If the folder is not a dataset in ``layout`` (or in any layout), a requested sequence is
        missing, or a sequence is broken: image and annotation counts differ, a flag file has the
        wrong length, or an annotation line cannot be parsed.
    ValueError
        If ``layout`` is not a known name.
    """
    return [e.load() for e in _chosen(path, layout, sequences)]


def iter_layout(
    path: str | os.PathLike[str],
    layout: str | None = None,
    sequences: AbcSequence[str] | None = None,
) -> Iterator[Sequence]:
    """Like :func:`load_layout`, but load each sequence only when the iteration reaches it.

    The dataset is detected and listed (and requested names checked) before the first sequence
    is yielded; a broken sequence raises :class:`LayoutError` when it is reached.
    """
    for entry in _chosen(path, layout, sequences):
        yield entry.load()
