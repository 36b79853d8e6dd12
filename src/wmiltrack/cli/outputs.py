"""Output paths checked against the run's inputs before anything is written.

A command that writes where it reads destroys its own input: ``track Coke -o
Coke/groundtruth_rect.txt`` would replace the sequence's ground truth with the tracker's boxes,
``track clip.mp4 -o clip.mp4`` the video with a text file, and two outputs that are one file
(``-o x --video x``) would interleave. :func:`check_outputs` refuses all of these with a
:class:`~wmiltrack.cli.options.UsageError` (exit status 2) while nothing has been opened yet.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Sequence
from pathlib import Path

from .options import UsageError


def same_file(a: Path, b: Path) -> bool:
    """Whether ``a`` and ``b`` name one file: :func:`os.path.samefile` when both exist (hard
    and symbolic links included), else their resolved paths are equal."""
    try:
        if a.exists() and b.exists():
            return os.path.samefile(a, b)
    except OSError:
        pass
    return a.expanduser().resolve() == b.expanduser().resolve()


def _inside(path: Path, folder: Path) -> bool:
    """Whether the existing file ``path`` lies in ``folder`` or below it (a file a sequence
    folder's reader may take: an image, the ground truth, ``start.txt``), its ``img/``
    sub-folder included when that is a link to elsewhere."""
    if not folder.is_dir() or not path.exists():
        return False
    target = path.resolve()
    return any(target.is_relative_to(f.resolve()) for f in (folder, folder / "img") if f.is_dir())


def check_outputs(outputs: Sequence[tuple[str, Path | None]], inputs: Iterable[Path]) -> None:
    """Refuse outputs that would overwrite an input, or each other.

    Parameters
    ----------
    outputs:
        ``(option, path)`` pairs, e.g. ``("-o", Path("boxes.txt"))``; ``None`` paths (an
        option not given) are left out.
    inputs:
        What the run reads: files (a video, ``--boxes FILE``, a list file) and folders (an
        image folder or OTB sequence: every existing file in it, or below it, is an input).

    Raises
    ------
    UsageError
        An output is an input or an existing file inside an input folder, or two outputs are
        the same file; the message names both.
    """
    given = [(option, path) for option, path in outputs if path is not None]
    ins = list(inputs)
    for option, path in given:
        for source in ins:
            if same_file(path, source):
                raise UsageError(f"{option} {path} is the input {source}: it would be overwritten; "
                                 "write the output elsewhere")
            if _inside(path, source) and path.is_file():
                raise UsageError(f"{option} {path} is a file of the input folder {source} (a frame "
                                 "or its ground truth): it would be overwritten; write the output "
                                 "elsewhere")
    for i, (option_a, a) in enumerate(given):
        for option_b, b in given[i + 1:]:
            if same_file(a, b):
                raise UsageError(f"{option_a} {a} and {option_b} {b} are the same file: give each "
                                 "output its own path")
