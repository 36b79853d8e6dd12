"""Tracking sequences: OTB-style folders, plain image folders, video files and in-memory frames.

An OTB sequence folder looks like::

    <Seq>/img/0001.jpg, 0002.jpg, ...
    <Seq>/groundtruth_rect.txt      one "x,y,w,h" line per annotated frame
    <Seq>/start.txt                 optional: the image the first ground-truth line belongs to

Ground-truth boxes are used **exactly as written in the files**: ``(x, y, w, h)`` floats with the
published coordinates. OTB publishes 1-based pixel coordinates; no ``-1`` shift is applied here,
so the numbers you get are the numbers in the file. Lines reading ``NaN`` (target absent, as in
the TLD-derived sequences) become rows of ``nan``.

Frames are returned as OpenCV decodes them: BGR ``uint8`` arrays of shape ``(H, W, 3)``
(grayscale images are expanded to three channels).
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Generator, Iterator
from collections.abc import Sequence as AbcSequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from .boxes import read_boxes

__all__ = [
    "DATA_ENV",
    "GT_FILE",
    "IMAGE_EXTENSIONS",
    "OTB100_FRAMES",
    "Sequence",
    "TolerantFrames",
    "default_otb_root",
    "list_otb_sequences",
    "load_dataset",
    "load_otb_sequence",
    "natural_key",
    "open_input",
]

DATA_ENV = "WMILTRACK_OTB"
"""Environment variable that overrides the folder holding the OTB sequences."""

GT_FILE = "groundtruth_rect.txt"
"""Name of the ground-truth file inside an OTB sequence folder."""

START_FILE = "start.txt"
"""Optional file inside an OTB sequence folder: the image the first ground-truth line belongs to."""

OTB100_FRAMES: dict[str, tuple[int, int]] = {
    "BlurCar1": (247, 988),
    "BlurCar3": (3, 359),
    "BlurCar4": (18, 397),
    "David": (300, 770),
    "Diving": (1, 215),
    "Football1": (1, 74),
    "Freeman3": (1, 460),
    "Freeman4": (1, 283),
    "Tiger1": (6, 354),
}
"""OTB-100's annotated image range ``(start, end)`` (1-based image numbers, inclusive) for the
sequences whose images and ground-truth lines do not simply start together at image 1 and end
together (from the OTB toolkit's ``configSeqs100.m``, as the got10k and pytracking loaders use
it).  Every other OTB sequence covers images ``1 .. len(groundtruth)``."""

_TARGET_GT = re.compile(r"^groundtruth_rect\.(\d+)\.txt$")
_TARGET_NAME = re.compile(r"^(?P<folder>.+)\.(?P<target>\d+)$")

IMAGE_EXTENSIONS = frozenset(
    {".jpg", ".jpeg", ".png", ".bmp", ".tif", ".tiff", ".webp", ".pgm", ".ppm", ".pbm"}
)
"""File suffixes (lower case) treated as images."""

Frame = NDArray[np.uint8]
Box = tuple[float, float, float, float]

_DIGITS = re.compile(r"(\d+)")


def default_otb_root() -> Path:
    """Return the folder holding the OTB sequences.

    Returns
    -------
    pathlib.Path
        ``$WMILTRACK_OTB`` (see :data:`DATA_ENV`) when that variable is set and non-empty,
        otherwise ``<current working directory>/../shared/data/otb``. The fallback is relative
        to the working directory, not to this file, because the installed package no longer
        lives next to the repository; run from the repository root or set the variable.
        The folder is not checked for existence.
    """
    env = os.environ.get(DATA_ENV, "").strip()
    if env:
        return Path(env).expanduser()
    return (Path.cwd() / ".." / "shared" / "data" / "otb").resolve()


def natural_key(name: str) -> tuple[Any, ...]:
    """Sort key ordering embedded numbers numerically (``img2`` before ``img10``).

    Parameters
    ----------
    name:
        A file name.

    Returns
    -------
    tuple
        Alternating lower-cased text and integer parts, followed by ``name`` itself to break ties.
    """
    parts = _DIGITS.split(name)
    key: list[Any] = [int(p) if i % 2 else p.lower() for i, p in enumerate(parts)]
    return (tuple(key), name)


def _read_image(path: Path) -> Frame:
    img = cv2.imread(str(path), cv2.IMREAD_COLOR)
    if img is None:
        if not path.exists():
            raise FileNotFoundError(f"image not found: {path}")
        raise ValueError(f"could not decode image {path} (corrupt or unsupported format)")
    return np.ascontiguousarray(img, dtype=np.uint8)


def _as_frame(img: ArrayLike) -> Frame:
    arr = np.asarray(img)
    if arr.dtype != np.uint8:
        raise ValueError(f"frames must be uint8, got {arr.dtype}")
    if arr.ndim == 2:
        arr = cv2.cvtColor(arr, cv2.COLOR_GRAY2BGR)
    if arr.ndim != 3 or arr.shape[2] != 3:
        raise ValueError(f"frames must be HxWx3 BGR (or HxW gray), got shape {arr.shape}")
    return arr


@dataclass(eq=False)
class Sequence:
    """A tracking sequence: frames plus optional ground truth.

    Exactly one frame source is used: ``paths`` (image files, decoded on demand), ``video``
    (a file read with :class:`cv2.VideoCapture`) or ``frames`` (in-memory BGR ``uint8`` arrays).

    Attributes
    ----------
    name:
        Sequence name (the folder or file name for loaded data).
    groundtruth:
        ``(n_frames, 4)`` float64 ``x, y, w, h`` boxes as written in the annotation file,
        with ``nan`` rows where the target is absent; ``None`` when unknown.
    fps:
        Frame rate when known (videos, synthetic sequences), else ``None``.
    paths:
        Image files, one per frame, in order.
    video:
        Video file.
    frames:
        In-memory frames.
    meta:
        Free-form extra per-sequence information (synthetic sequences store per-frame
        occlusion fractions and illumination gains here).
    """

    name: str
    groundtruth: NDArray[np.float64] | None = None
    fps: float | None = None
    paths: tuple[Path, ...] | None = field(default=None, repr=False)
    video: Path | None = field(default=None, repr=False)
    frames: list[Frame] | None = field(default=None, repr=False)
    meta: dict[str, Any] = field(default_factory=dict, repr=False)
    _cache: list[Frame] | None = field(default=None, init=False, repr=False)
    _n_video: int | None = field(default=None, init=False, repr=False)
    _cap: Any = field(default=None, init=False, repr=False)
    _cap_pos: int = field(default=0, init=False, repr=False)

    def __post_init__(self) -> None:
        """Check the frame source and the ground truth's shape and length."""
        sources = sum(s is not None for s in (self.paths, self.video, self.frames))
        if sources != 1:
            raise ValueError("give exactly one of paths=, video= or frames=")
        if self.paths is not None:
            self.paths = tuple(Path(p) for p in self.paths)
        if self.frames is not None:
            self.frames = [_as_frame(f) for f in self.frames]
            self._cache = self.frames
        if self.video is not None:
            self.video = Path(self.video)
            cap = cv2.VideoCapture(str(self.video))
            try:
                if not cap.isOpened():
                    raise ValueError(f"could not open video {self.video}")
                if self.fps is None:
                    fps = float(cap.get(cv2.CAP_PROP_FPS))
                    self.fps = fps if math.isfinite(fps) and fps > 0 else None
            finally:
                cap.release()
        if self.groundtruth is not None:
            gt = np.asarray(self.groundtruth, dtype=np.float64)
            if gt.ndim != 2 or gt.shape[1] != 4:
                raise ValueError(f"groundtruth must have shape (n, 4), got {gt.shape}")
            self.groundtruth = gt
            if len(gt) != len(self):
                raise ValueError(
                    f"{self.name}: {len(gt)} ground-truth boxes for {len(self)} frames"
                )

    # ------------------------------------------------------------------ size and access
    def __len__(self) -> int:
        """Return the number of frames (a video is counted by reading it through once)."""
        if self._cache is not None:
            return len(self._cache)
        if self.paths is not None:
            return len(self.paths)
        if self._n_video is None:
            self._n_video = self._count_video_frames()
        return self._n_video

    def _count_video_frames(self) -> int:
        cap = cv2.VideoCapture(str(self.video))
        n = 0
        try:
            while cap.grab():
                n += 1
        finally:
            cap.release()
        return n

    def _index(self, i: int) -> int:
        n = len(self)
        j = int(i) + n if int(i) < 0 else int(i)
        if not 0 <= j < n:
            raise IndexError(f"frame {i} out of range for {self.name!r} with {n} frames")
        return j

    def frame(self, i: int) -> Frame:
        """Return frame ``i`` (negative indices count from the end).

        Parameters
        ----------
        i:
            Frame index.

        Returns
        -------
        numpy.ndarray
            BGR ``uint8`` array ``(H, W, 3)``. In-memory and cached frames are returned
            without copying; do not modify them in place.

        Raises
        ------
        IndexError
            If ``i`` is out of range.
        ValueError
            If the image or video frame cannot be decoded.
        """
        j = self._index(i)
        if self._cache is not None:
            return self._cache[j]
        if self.paths is not None:
            return _read_image(self.paths[j])
        return self._video_frame(j)

    def _video_frame(self, j: int) -> Frame:
        # Sequential reads are exact; seeking with CAP_PROP_POS_FRAMES is not for every codec,
        # so going backwards reopens the file and skips forward with grab().
        if self._cap is None or j < self._cap_pos:
            self.close()
            self._cap = cv2.VideoCapture(str(self.video))
            self._cap_pos = 0
            if not self._cap.isOpened():
                raise ValueError(f"could not open video {self.video}")
        while self._cap_pos < j:
            if not self._cap.grab():
                raise ValueError(f"{self.video}: video ended before frame {j + 1}")
            self._cap_pos += 1
        ok, img = self._cap.read()
        if not ok or img is None:
            raise ValueError(f"{self.video}: could not decode frame {j + 1}")
        self._cap_pos += 1
        return _as_frame(img)

    def close(self) -> None:
        """Release the video reader held open by :meth:`frame` (no-op for other sources)."""
        if self._cap is not None:
            self._cap.release()
            self._cap = None
            self._cap_pos = 0

    def __iter__(self) -> Iterator[Frame]:
        """Yield the frames in order (decoded one at a time unless :meth:`load` was called)."""
        if self._cache is not None:
            yield from self._cache
            return
        if self.paths is not None:
            for p in self.paths:
                yield _read_image(p)
            return
        cap = cv2.VideoCapture(str(self.video))
        if not cap.isOpened():
            raise ValueError(f"could not open video {self.video}")
        try:
            n = 0
            while True:
                ok, img = cap.read()
                if not ok or img is None:
                    break
                n += 1
                yield _as_frame(img)
            self._n_video = n
        finally:
            cap.release()

    def load(self) -> list[Frame]:
        """Decode every frame once and keep them in memory.

        Returns
        -------
        list of numpy.ndarray
            The frames; later :meth:`frame` and iteration use this cache.
        """
        if self._cache is None:
            frames = list(self)
            if self.groundtruth is not None and len(frames) != len(self.groundtruth):
                raise ValueError(
                    f"{self.name}: decoded {len(frames)} frames but have "
                    f"{len(self.groundtruth)} ground-truth boxes"
                )
            self.close()
            self._cache = frames
        return self._cache

    # ------------------------------------------------------------------ ground truth
    @property
    def init_box(self) -> Box:
        """Ground-truth box ``(x, y, w, h)`` of frame 0, the box a tracker is started with.

        Raises
        ------
        ValueError
            If the sequence has no ground truth, or the target is absent (``nan``) in frame 0.
        """
        if self.groundtruth is None or len(self.groundtruth) == 0:
            raise ValueError(f"sequence {self.name!r} has no ground truth: give the box yourself")
        row = self.groundtruth[0]
        if not np.all(np.isfinite(row)):
            raise ValueError(
                f"sequence {self.name!r}: the target is not annotated in frame 0 ({row.tolist()})"
            )
        x, y, w, h = (float(v) for v in row)
        return (x, y, w, h)

    @property
    def valid(self) -> NDArray[np.bool_]:
        """Boolean mask of frames whose ground truth is present (all four values finite).

        Raises
        ------
        ValueError
            If the sequence has no ground truth.
        """
        if self.groundtruth is None:
            raise ValueError(f"sequence {self.name!r} has no ground truth")
        return np.asarray(np.all(np.isfinite(self.groundtruth), axis=1))


# ---------------------------------------------------------------------- loading
def _list_images(folder: Path) -> list[Path]:
    files = [p for p in folder.iterdir() if p.is_file() and p.suffix.lower() in IMAGE_EXTENSIONS]
    files.sort(key=lambda p: natural_key(p.name))
    return files


def _read_start(path: Path, images: list[Path]) -> int:
    """0-based position in ``images`` of the image named by ``start.txt``."""
    text = path.read_text(encoding="utf-8-sig").split()
    if len(text) != 1:
        raise ValueError(f"{path}: expected a single 1-based image index, got {text!r}")
    try:
        start = int(float(text[0]))
    except ValueError:
        raise ValueError(f"{path}: not an image index: {text[0]!r}") from None
    for pos, p in enumerate(images):
        digits = _DIGITS.findall(p.stem)
        if digits and int(digits[-1]) == start:
            return pos
    if 1 <= start <= len(images):
        return start - 1
    raise ValueError(
        f"{path}: start image {start} is neither an image number in the folder nor a "
        f"position among its {len(images)} images"
    )


def _image_sequence(
    name: str, img_dir: Path, gt_file: Path | None, start_file: Path | None
) -> Sequence:
    images = _list_images(img_dir)
    if not images:
        exts = ", ".join(sorted(IMAGE_EXTENSIONS))
        raise ValueError(f"no images in {img_dir} (looked for {exts})")
    if start_file is not None and start_file.is_file():
        images = images[_read_start(start_file, images) :]
    gt: NDArray[np.float64] | None = None
    if gt_file is not None:
        gt = read_boxes(gt_file)
        if len(gt) == 0:
            raise ValueError(f"{gt_file} holds no boxes")
        if len(gt) > len(images):
            raise ValueError(
                f"{gt_file} has {len(gt)} boxes but {img_dir} only {len(images)} images"
                + (" after start.txt" if start_file is not None and start_file.is_file() else "")
            )
        images = images[: len(gt)]  # annotation covers only the first frames (e.g. Football1)
    _read_image(images[0])  # fail early on an unreadable folder
    return Sequence(name=name, groundtruth=gt, paths=tuple(images))


def _target_files(path: Path) -> list[tuple[int, Path]]:
    """``(k, groundtruth_rect.<k>.txt)`` of a folder annotating several targets, sorted by k."""
    found = []
    for f in path.iterdir():
        m = _TARGET_GT.match(f.name)
        if m is not None and f.is_file():
            found.append((int(m.group(1)), f))
    return sorted(found)


def _is_otb_folder(path: Path) -> bool:
    return (path / "img").is_dir() and (
        (path / GT_FILE).is_file() or bool(_target_files(path))
    )


def _image_numbers(images: list[Path]) -> list[int]:
    """The number in each image's name (last digit group), or positions 1..n if the names
    are not all numbered or not all different."""
    nums: list[int] = []
    for p in images:
        digits = _DIGITS.findall(p.stem)
        if not digits:
            return list(range(1, len(images) + 1))
        nums.append(int(digits[-1]))
    if len(set(nums)) != len(nums):
        return list(range(1, len(images) + 1))
    return nums


def _otb_sequence(name: str, folder: Path, gt_file: Path) -> Sequence:
    """Line up an OTB folder's images with its ground truth by image number, or refuse."""
    img_dir = folder / "img"
    images = _list_images(img_dir)
    if not images:
        exts = ", ".join(sorted(IMAGE_EXTENSIONS))
        raise ValueError(f"no images in {img_dir} (looked for {exts})")
    gt = read_boxes(gt_file)
    if len(gt) == 0:
        raise ValueError(f"{gt_file} holds no boxes")
    numbers = _image_numbers(images)
    by_number = dict(zip(numbers, images, strict=True))
    start_file = folder / START_FILE
    known = OTB100_FRAMES.get(name.split(".")[0])
    if start_file.is_file():
        first = numbers[_read_start(start_file, images)]
        last = first + len(gt) - 1
        why = f"{START_FILE} names image {first}"
    elif known is not None:
        first, last = known
        why = f"OTB-100 annotates images {first}..{last} of {name}"
    else:
        first, last = 1, len(gt)
        why = f"{gt_file.name} has {len(gt)} lines for images 1..{len(gt)}"
    span = last - first + 1
    if len(gt) == span:
        rows = gt
    elif known is not None and not start_file.is_file() and len(gt) == last:
        rows = gt[first - 1 : last]  # lines start at image 1 (Tiger1): keep the range's lines
    else:
        raise ValueError(
            f"{folder}: {why}, but {gt_file.name} has {len(gt)} lines; the images and the "
            "ground truth do not line up"
        )
    absent = [n for n in range(first, last + 1) if n not in by_number]
    if absent:
        raise ValueError(
            f"{folder}: {why}, but image(s) {', '.join(map(str, absent[:5]))}"
            + (" ..." if len(absent) > 5 else "")
            + f" are missing from {img_dir}"
        )
    extra = [n for n in numbers if not first <= n <= last]
    if extra and known is None and not start_file.is_file():
        raise ValueError(
            f"{folder}: {len(images)} images but {len(gt)} ground-truth lines, and OTB-100's "
            f"start/end frames are not known for {name!r}; add a {START_FILE} naming the image "
            "of the first line, or remove the images that are not annotated"
        )
    chosen = [by_number[n] for n in range(first, last + 1)]
    _read_image(chosen[0])  # fail early on an unreadable folder
    return Sequence(name=name, groundtruth=np.asarray(rows, dtype=np.float64), paths=tuple(chosen))


def load_otb_sequence(path: str | os.PathLike[str]) -> Sequence:
    """Load an OTB-layout sequence folder (or one target of a two-target folder).

    Parameters
    ----------
    path:
        Folder holding ``img/`` and ``groundtruth_rect.txt`` (optionally ``start.txt``); or
        ``<root>/<Seq>.<k>`` for the ``k``-th target of a folder ``<root>/<Seq>`` that holds
        ``groundtruth_rect.<k>.txt`` files instead (Jogging, Skating2, Human4: the sequence
        is then named ``Jogging.1``, ``Jogging.2`` as the OTB toolkits name them).

    Returns
    -------
    Sequence
        Image-backed sequence.  Ground-truth line ``i`` belongs to the image numbered
        ``first + i`` (the number in the file name, e.g. ``0300.jpg`` -> 300), where ``first``
        is the image named by ``start.txt`` if present (its number, or else its 1-based
        position), else OTB-100's known start frame (:data:`OTB100_FRAMES`: David 300..770,
        Football1 1..74, ...), else 1.  Boxes are kept exactly as written (no 1-based shift).

    Raises
    ------
    FileNotFoundError
        If the folder, ``img/`` or the ground-truth file is missing.
    ValueError
        If the images and the ground truth do not line up (an annotated image is missing,
        the line count does not match the known range, or there are more images than lines
        and nothing says which ones are annotated), or a folder of several targets is given
        without choosing one; the message says which.  Also for no images, a malformed box
        line, or an unreadable first image.
    """
    p = Path(path)
    if not p.is_dir():
        m = _TARGET_NAME.match(p.name)
        folder = p.parent / m.group("folder") if m else None
        if m is not None and folder is not None and folder.is_dir():
            gt_file = folder / f"groundtruth_rect.{m.group('target')}.txt"
            if not gt_file.is_file():
                raise FileNotFoundError(f"{folder} has no {gt_file.name}")
            if not (folder / "img").is_dir():
                raise FileNotFoundError(f"{folder} has no img/ folder (expected OTB layout)")
            return _otb_sequence(p.name, folder, gt_file)
        raise FileNotFoundError(f"sequence folder not found: {p}")
    img_dir = p / "img"
    gt_file = p / GT_FILE
    if not img_dir.is_dir():
        raise FileNotFoundError(f"{p} has no img/ folder (expected OTB layout)")
    if not gt_file.is_file():
        targets = _target_files(p)
        if targets:
            names = ", ".join(f"{p.name}.{k}" for k, _ in targets)
            raise ValueError(f"{p} annotates {len(targets)} targets: load one of {names}")
        raise FileNotFoundError(f"{p} has no {GT_FILE}")
    return _otb_sequence(p.name, p, gt_file)


def list_otb_sequences(root: str | os.PathLike[str] | None = None) -> list[Path]:
    """List the OTB sequence folders under ``root``.

    Parameters
    ----------
    root:
        Folder to scan (not recursive); ``None`` means :func:`default_otb_root`.

    Returns
    -------
    list of pathlib.Path
        Sub-folders holding ``img/`` and ``groundtruth_rect.txt``, sorted by name; a folder
        annotating several targets (``groundtruth_rect.1.txt``, ``.2.txt``: Jogging, Skating2,
        Human4) gives one path per target, ``<root>/Jogging.1``, ``<root>/Jogging.2``, which
        :func:`load_otb_sequence` accepts.

    Raises
    ------
    FileNotFoundError
        If ``root`` is not a folder.
    """
    r = default_otb_root() if root is None else Path(root)
    if not r.is_dir():
        raise FileNotFoundError(
            f"OTB root not found: {r} (set {DATA_ENV} to the folder holding the sequences)"
        )
    out: list[Path] = []
    for p in r.iterdir():
        if not (p.is_dir() and _is_otb_folder(p)):
            continue
        if (p / GT_FILE).is_file():
            out.append(p)
        else:
            out += [r / f"{p.name}.{k}" for k, _ in _target_files(p)]
    return sorted(out, key=lambda p: p.name)


def load_dataset(
    root: str | os.PathLike[str] | None = None, names: AbcSequence[str] | None = None
) -> list[Sequence]:
    """Load several OTB sequences.

    Parameters
    ----------
    root:
        Folder holding the sequence folders; ``None`` means :func:`default_otb_root`.
    names:
        Sequence names to load, in this order; ``None`` loads all of them (sorted by name).

    Returns
    -------
    list of Sequence

    Raises
    ------
    FileNotFoundError
        If ``root`` or a requested sequence is missing (the message lists what is available).
    """
    available = list_otb_sequences(root)
    if names is None:
        return [load_otb_sequence(p) for p in available]
    if isinstance(names, str):
        names = [names]
    by_name = {p.name: p for p in available}
    missing = [n for n in names if n not in by_name]
    if missing:
        raise FileNotFoundError(
            f"sequence(s) not found: {', '.join(missing)}; available: {', '.join(sorted(by_name))}"
        )
    return [load_otb_sequence(by_name[n]) for n in names]


def open_input(path: str | os.PathLike[str], *, groundtruth: bool = True) -> Sequence:
    """Open whatever the user pointed at as a :class:`Sequence`.

    Parameters
    ----------
    path:
        One of

        * an OTB sequence folder (``img/`` + ``groundtruth_rect.txt``): loaded with ground truth
          by :func:`load_otb_sequence`;
        * a folder with an ``img/`` sub-folder but no ground truth: its images, no ground truth;
        * a folder of images, taken in natural order (``2.png`` before ``10.png``); a
          ``groundtruth_rect.txt`` next to them is used if present;
        * a video file, read with :class:`cv2.VideoCapture`.
    groundtruth:
        ``False``: a folder's ground-truth file is not read (for a caller that has its own
        first box, so that a damaged file does not stop it); an OTB folder then gives all the
        images of ``img/``, in natural order.

    Returns
    -------
    Sequence

    Raises
    ------
    FileNotFoundError
        If ``path`` does not exist.
    ValueError
        If a folder holds no images, the first image cannot be decoded, the path is a single
        image, or the video cannot be opened or holds no readable frame.
    """
    p = Path(path).expanduser()
    if not p.exists():
        raise FileNotFoundError(f"input not found: {p}")
    if p.is_dir():
        if groundtruth and _is_otb_folder(p):
            return load_otb_sequence(p)
        if (p / "img").is_dir():
            return _image_sequence(p.name, p / "img", None, None)
        gt = p / GT_FILE
        return _image_sequence(p.name, p, gt if groundtruth and gt.is_file() else None,
                               p / START_FILE)
    if p.suffix.lower() in IMAGE_EXTENSIONS:
        raise ValueError(f"{p} is a single image; pass the folder holding the frames instead")
    cap = cv2.VideoCapture(str(p))
    try:
        if not cap.isOpened():
            raise ValueError(f"could not open {p} as a video (unknown format or corrupt file)")
        ok, img = cap.read()
        if not ok or img is None:
            raise ValueError(f"{p}: video holds no readable frame")
    finally:
        cap.release()
    return Sequence(name=p.stem, video=p)


# ---------------------------------------------------------------------- tolerant reading
def _decode_image_checked(path: Path) -> tuple[Frame | None, str | None]:
    """Decode one image file; ``(frame, None)``, or ``(None, reason)`` when it cannot be used.

    The bytes are decoded with :func:`cv2.imdecode`, not :func:`cv2.imread`: for a truncated
    JPEG, ``imread`` (libjpeg's file reader) pads the missing part with grey and returns an
    image, while ``imdecode`` returns ``None`` (checked with OpenCV 5.0). In case another OpenCV
    version's ``imdecode`` pads too, a JPEG is also rejected when no end-of-image marker
    (``FF D9``) follows its last start-of-scan marker (``FF DA``); these two byte pairs cannot
    occur inside entropy-coded data, and data appended after the end marker is allowed.
    Not detected: a JPEG whose scan data is damaged but which still ends with its end marker
    (libjpeg conceals the damage and only prints a warning).
    """
    try:
        data = path.read_bytes()
    except OSError as exc:
        return None, f"cannot read the file ({exc.strerror or exc})"
    if not data:
        return None, "empty file"
    try:
        img = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_COLOR)
    except cv2.error as exc:
        return None, f"could not decode the image ({str(exc).strip().splitlines()[-1]})"
    if img is None:
        return None, "could not decode the image (truncated, corrupt or unsupported format)"
    if data[:2] == b"\xff\xd8" and data.rfind(b"\xff\xd9") < data.rfind(b"\xff\xda"):
        return None, "truncated JPEG (no end-of-image marker after the last scan)"
    return np.ascontiguousarray(img, dtype=np.uint8), None


class TolerantFrames:
    """The frames of a :class:`Sequence`, in order, not stopping at one that cannot be used.

    Iterating yields ``(index, frame, problem)`` for every frame: ``frame`` is the BGR ``uint8``
    array and ``problem`` is ``None``, or ``frame`` is ``None`` and ``problem`` says why the frame
    cannot be used: an image file that cannot be read or decoded (truncated JPEG or PNG, see
    :func:`_decode_image_checked` for what is and is not detected), or a frame whose size differs
    from the first usable frame's. Indices are 0-based and count every frame, usable or not.

    A video is read with :meth:`cv2.VideoCapture.read` until it fails. A damaged tail usually
    ends reading early; the frames never read get no entry, but :attr:`ended_early` then says
    how many frames were read and how many the container announces.

    Attributes
    ----------
    sequence:
        The sequence read.
    expected:
        Number of frames the source announces: the image count, the container's frame count
        for a video (``None`` when the container does not say), ``len(frames)`` in memory.
        Known without decoding anything (``len(sequence)`` reads a whole video).
    ended_early:
        After iteration: for a video whose reading stopped before :attr:`expected` frames,
        a message such as ``"the video ended after 32 frames; its container announces 40"``;
        otherwise ``None``.
    """

    def __init__(self, sequence: Sequence) -> None:
        self.sequence = sequence
        self.ended_early: str | None = None
        self.expected: int | None
        if sequence._cache is not None:
            self.expected = len(sequence._cache)
        elif sequence.paths is not None:
            self.expected = len(sequence.paths)
        else:
            cap = cv2.VideoCapture(str(sequence.video))
            try:
                n = cap.get(cv2.CAP_PROP_FRAME_COUNT) if cap.isOpened() else 0.0
            finally:
                cap.release()
            self.expected = int(n) if math.isfinite(n) and n > 0 else None

    def __iter__(self) -> Generator[tuple[int, Frame | None, str | None], None, None]:
        """Yield ``(index, frame, problem)`` for each frame, in order (see the class).

        Closing the generator early (``close()``) releases the video reader at once.
        """
        shape: tuple[int, ...] | None = None
        raw = self._raw()
        try:
            for i, frame, problem in raw:
                if frame is not None:
                    if shape is None:
                        shape = frame.shape
                    elif frame.shape != shape:
                        problem = (f"size {frame.shape[1]}x{frame.shape[0]} differs from the first "
                                   f"frame's {shape[1]}x{shape[0]}")
                        frame = None
                yield i, frame, problem
        finally:
            raw.close()

    def _raw(self) -> Generator[tuple[int, Frame | None, str | None], None, None]:
        seq = self.sequence
        if seq._cache is not None:
            for i, f in enumerate(seq._cache):
                yield i, f, None
            return
        if seq.paths is not None:
            for i, p in enumerate(seq.paths):
                img, problem = _decode_image_checked(p)
                yield i, img, (None if problem is None else f"{p.name}: {problem}")
            return
        cap = cv2.VideoCapture(str(seq.video))
        if not cap.isOpened():
            raise ValueError(f"could not open video {seq.video}")
        n = 0
        try:
            while True:
                ok, raw = cap.read()
                if not ok or raw is None:
                    break
                yield n, _as_frame(raw), None
                n += 1
        finally:
            cap.release()
        if self.expected is not None and n < self.expected:
            self.ended_early = (f"the video ended after {n} frames; its container announces "
                                f"{self.expected}")
