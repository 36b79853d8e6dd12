"""Output paths checked against the run's inputs before anything is written.

A command that writes where it reads destroys its own input: ``track Coke -o
Coke/groundtruth_rect.txt`` would replace the sequence's ground truth with the tracker's boxes,
``track clip.mp4 -o clip.mp4`` the video with a text file, ``track Coke/img -o
Coke/img/0001.png`` would add a frame, and two outputs that are one file (``-o x --video x``)
would interleave; ``eval --out`` inside the dataset would put plots and box files among the
frames. :func:`check_outputs` refuses all of these with a
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


def _input_folders(folder: Path) -> list[Path]:
    """The folders whose files a run on the input folder ``folder`` may read: the folder
    itself, its ``img/`` sub-folder (followed when it is a link to elsewhere), and, for the
    ``img/`` folder of an OTB sequence given on its own, the sequence folder holding its
    ground truth (``track Seq/img -o Seq/groundtruth_rect.txt`` must be refused too)."""
    folders = [folder]
    if (folder / "img").is_dir():
        folders.append(folder / "img")
    parent = folder.resolve().parent
    if folder.resolve().name == "img" and any(parent.glob("groundtruth_rect*.txt")):
        folders.append(parent)
    return [f.resolve() for f in folders]


def inside_input(path: Path, folder: Path) -> bool:
    """Whether ``path`` (an existing file or a new name) lies in the input folder ``folder``,
    below it, or in the sequence folder it belongs to (:func:`_input_folders`). A new file
    there could become a frame (``img/0001.png`` beside ``0001.jpg``), a ground truth
    (``groundtruth_rect.2.txt``) or an input the next run trips over, so every output goes
    outside."""
    if not folder.is_dir():
        return False
    target = path.expanduser().resolve()
    return any(target.is_relative_to(f) for f in _input_folders(folder))


def check_outputs(outputs: Sequence[tuple[str, Path | None]], inputs: Iterable[Path]) -> None:
    """Refuse outputs that would overwrite an input, or each other.

    Parameters
    ----------
    outputs:
        ``(option, path)`` pairs, e.g. ``("-o", Path("boxes.txt"))``; ``None`` paths (an
        option not given) are left out.
    inputs:
        What the run reads: files (a video, ``--boxes FILE``, a list file) and folders (an
        image folder or OTB sequence: nothing may be written in it, below it, or, for a
        sequence's ``img/`` folder, in the sequence folder).

    Raises
    ------
    UsageError
        An output is an input or lies inside an input folder, or two outputs are the same
        file; the message names both.
    """
    given = [(option, path) for option, path in outputs if path is not None]
    ins = list(inputs)
    for option, path in given:
        for source in ins:
            if same_file(path, source):
                raise UsageError(f"{option} {path} is the input {source}: it would be overwritten; "
                                 "write the output elsewhere")
            if inside_input(path, source):
                raise UsageError(f"{option} {path} is inside the input folder {source} (its frames "
                                 "or its ground truth), which could be overwritten or added to; "
                                 "write the output outside that folder")
    for i, (option_a, a) in enumerate(given):
        for option_b, b in given[i + 1:]:
            if same_file(a, b):
                raise UsageError(f"{option_a} {a} and {option_b} {b} are the same file: give each "
                                 "output its own path")


def _holds_sequence_files(folder: Path) -> bool:
    """Whether ``folder`` holds frames (image files), a ground truth (``groundtruth*.txt``) or
    an ``img/`` folder: a sequence or image folder, where a reader takes what it finds."""
    from ..data.sequences import IMAGE_EXTENSIONS

    if not folder.is_dir():
        return False
    if (folder / "img").is_dir():
        return True
    return any(f.suffix.lower() in IMAGE_EXTENSIONS or
               (f.name.startswith("groundtruth") and f.suffix == ".txt")
               for f in folder.iterdir())


def check_output_folder(option: str, out: Path, dataset: Path) -> None:
    """Refuse an output folder (``eval --out``) that is an existing file, or that is or lies
    inside a folder of the dataset holding frames or a ground truth (a sequence folder, its
    ``img/``): the run's plots and box files would land among the frames, and the next run of
    that dataset would read them or refuse the sequence. A new folder beside the sequences
    (``--out data/results``) is allowed: no reader takes it for a sequence.

    Raises
    ------
    UsageError
        Saying which, before anything is written.
    """
    if out.exists() and not out.is_dir():
        raise UsageError(f"{option} {out} is an existing file; give a folder (it is created when "
                         "missing)")
    root = dataset.expanduser().resolve()
    target = out.expanduser().resolve()
    if not root.is_dir() or not target.is_relative_to(root):
        return
    folder = target
    while True:  # from the output folder up to the dataset folder, both included
        if _holds_sequence_files(folder):
            raise UsageError(f"{option} {out} is inside the input folder {folder}, which holds "
                             "frames or a ground truth: the outputs would be mixed with them; "
                             "write them outside that folder")
        if folder == root:
            return
        folder = folder.parent
