"""The model sets of the networks wmiltrack runs (NanoTrack v2 and v3): their files, where
they are found, how they are fetched and checked, and the constants their authors publish with
them. :data:`MODELS` is the one registry of networks and their versions; the rest of wmiltrack
derives its lists from it.

No model file ships with wmiltrack: the files stay in their authors' public repository, pinned
here by commit and SHA-1. A tracker finds each file, in this order,

1. at the path it is given (``backbone=``, ``head=``; on the command line ``--nano-backbone``,
   ``--nano-head``);
2. at the path in its environment variable (``WMILTRACK_NANO_BACKBONE``, ``WMILTRACK_NANO_HEAD``,
   the ones ``opencv:Nano`` reads);
3. in the models folder (:func:`models_dir`: ``$WMILTRACK_MODELS``, else the user's cache
   folder), under the set's name, where ``wmiltrack models fetch`` puts it.

A path that is given but is no file is an error, never a reason to look further; a file that is
another set's or another role's (NanoTrack v2's backbone given for v3's) is an error too. A
fetched file is checked against its SHA-1 before it takes its name, so that the models folder
never holds a partial or altered download.
"""

from __future__ import annotations

import hashlib
import os
import sys
import tempfile
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path, PurePosixPath
from typing import BinaryIO

from ..integrations.opencv_wheels import TrackerUnavailable

__all__ = [
    "DEFAULT_BASE_URL",
    "MODELS",
    "MODELS_ENV",
    "MODEL_ENV",
    "MODELS_URL_ENV",
    "FetchError",
    "FileLookup",
    "ModelFile",
    "ModelFileMismatch",
    "ModelFileUnreadable",
    "ModelFilesMissing",
    "ModelSet",
    "fetch",
    "identify",
    "find_files",
    "look_up_files",
    "models_dir",
    "models_dir_origin",
    "nanotrack_files",
    "nanotrack_versions",
    "unreadable_message",
]

MODEL_ENV: dict[str, dict[str, str]] = {
    "Nano": {"backbone": "WMILTRACK_NANO_BACKBONE", "neckhead": "WMILTRACK_NANO_HEAD"},
    "Vit": {"net": "WMILTRACK_VIT_MODEL"},
}
"""The environment variables that give model files, by OpenCV tracker (``Nano``, ``Vit``) and
its ``Params`` attribute. NanoTrack's two are also the ones every NanoTrack set reads
(:attr:`ModelSet.env`), so that ``opencv:Nano``, ``nanotrack:VERSION`` and rcwmil-nano share
them."""

MODELS_ENV = "WMILTRACK_MODELS"
"""The models folder, when set and not empty (else the user's cache folder: :func:`models_dir`)."""

MODELS_URL_ENV = "WMILTRACK_MODELS_URL"
"""Where :func:`fetch` downloads from instead of :data:`DEFAULT_BASE_URL` (a mirror laid out
as ``BASE/owner/repository/commit/path``)."""

DEFAULT_BASE_URL = "https://raw.githubusercontent.com"
"""GitHub's raw files: ``BASE/owner/repository/commit/path`` is a file of a repository at a
commit, byte for byte."""

_CHUNK = 1 << 16


class ModelFilesMissing(FileNotFoundError, TrackerUnavailable):
    """A set's model files cannot be used: each missing (or wrong) file with where it was looked
    for, and in the same message every way to give or fetch them. A tracker that cannot start
    (:class:`~wmiltrack.integrations.opencv_wheels.TrackerUnavailable`), as one not installed
    is: ``eval`` and ``demo`` skip it with this message.

    ``problems`` holds the :class:`FileLookup` entries that are not usable (empty after
    unpickling a message made elsewhere, where only the message travels)."""

    def __init__(self, message: str, problems: tuple[FileLookup, ...] = ()) -> None:
        super().__init__(message)
        self.problems = problems


class ModelFileUnreadable(ModelFilesMissing):
    """A model file is there but cannot be run as the file it was given for: empty, corrupt or
    truncated, a folder, or another role's file (a head given as the backbone). Its message is
    one line naming the file, its role and the fix; a tracker that cannot start, as for
    :class:`ModelFilesMissing`."""


def unreadable_message(path: Path, role: str, reason: str, model: str | None = None) -> str:
    """The one line of a :class:`ModelFileUnreadable`: the file at ``path``, given as the
    ``role`` of the set ``model`` (None: no set known), ``reason`` what is wrong, and how to
    give the right file or fetch the set again."""
    s = MODELS.get(model or "")
    if s is None:
        return f"the {role} file {path} cannot be used: {reason}; give the right file"
    return (f"{s.title}'s {role} {path} cannot be used: {reason}; give the right file "
            f"({role}=FILE in Python, {s.options[role]} FILE on the command line, or "
            f"{s.env[role]}), or fetch the set again: `wmiltrack models fetch {s.name}`")


class ModelFileMismatch(ValueError):
    """A file's content is not the one pinned for it (SHA-1 or size): a download altered on the
    way, a different release, or another set's file."""


class FetchError(RuntimeError):
    """A model file could not be downloaded (no connection, an HTTP error, a cut transfer)."""


@dataclass(frozen=True)
class ModelFile:
    """One file of a :class:`ModelSet`: its role, its path in the repository, its size and the
    SHA-1 of its bytes."""

    role: str
    path: str
    sha1: str
    size: int

    @property
    def name(self) -> str:
        """The file's name, as it is stored in the models folder."""
        return PurePosixPath(self.path).name


@dataclass(frozen=True)
class ModelSet:
    """The files one network needs, pinned to a commit of their public repository.

    ``family`` is the network (``"nanotrack"``) and ``version`` its release (``"v3"``);
    ``files`` maps each role (``"backbone"``, ``"head"``) to its :class:`ModelFile`; ``env`` the
    role to the environment variable that gives its path, and ``options`` to the command-line
    option that does; ``step`` the constants of the tracking step the authors publish with the
    files (their configuration: for NanoTrack the head's grid, the window's influence, the
    penalty's ``k`` and the size's learning rate), read by the family's module."""

    name: str
    title: str
    family: str
    version: str
    repository: str
    commit: str
    license: str
    files: Mapping[str, ModelFile]
    env: Mapping[str, str]
    options: Mapping[str, str]
    step: Mapping[str, float]

    def url(self, role: str, base_url: str | None = None) -> str:
        """The download address of the file of ``role``: ``base_url`` (default
        ``$WMILTRACK_MODELS_URL``, else :data:`DEFAULT_BASE_URL`), the repository, the pinned
        commit and the file's path."""
        base = base_url or os.environ.get(MODELS_URL_ENV, "").strip() or DEFAULT_BASE_URL
        return f"{base.rstrip('/')}/{self.repository}/{self.commit}/{self.files[role].path}"

    def folder(self, root: Path | None = None) -> Path:
        """Where the set's files live in the models folder ``root`` (default :func:`models_dir`)."""
        return (models_dir() if root is None else root) / self.name


_SIAMTRACKERS = "HonglinChu/SiamTrackers"
_SIAMTRACKERS_COMMIT = "248663fde6bf7c40190cf10ee396d5662919ecd3"
_NANO_ENV = {"backbone": MODEL_ENV["Nano"]["backbone"], "head": MODEL_ENV["Nano"]["neckhead"]}
_NANO_OPTIONS = {"backbone": "--nano-backbone", "head": "--nano-head"}


def _nanotrack(version: str, backbone: tuple[str, str, int], head: tuple[str, str, int],
               step: dict[str, float]) -> ModelSet:
    """NanoTrack ``version``'s set; ``backbone`` and ``head`` are (file name, SHA-1, size),
    ``step`` the published constants of its tracking step."""
    folder = f"NanoTrack/models/nanotrack{version}"
    files = {role: ModelFile(role, f"{folder}/{name}", sha1, size)
             for role, (name, sha1, size) in (("backbone", backbone), ("head", head))}
    return ModelSet(name=f"nanotrack-{version}", title=f"NanoTrack {version}", family="nanotrack",
                    version=version, repository=_SIAMTRACKERS, commit=_SIAMTRACKERS_COMMIT,
                    license="Apache-2.0", files=files, env=dict(_NANO_ENV),
                    options=dict(_NANO_OPTIONS), step=step)


MODELS: dict[str, ModelSet] = {
    s.name: s for s in (
        _nanotrack("v2",
                   ("nanotrack_backbone_sim.onnx", "6e773a364457b78574f9f63a23b0659ee8646f8f", 1056849),
                   ("nanotrack_head_sim.onnx", "39f168489671700cf739e402dfc67d41ce648aef", 726198),
                   {"grid": 16, "window_influence": 0.490, "penalty_k": 0.150, "lr": 0.385}),
        _nanotrack("v3",
                   ("nanotrack_backbone.onnx", "60814e834733116131ed0a5f66ca674438b2de87", 1431635),
                   ("nanotrack_head.onnx", "68c3e1ec4dbda74a895afd5bff549777ea4810d8", 1183740),
                   {"grid": 15, "window_influence": 0.455, "penalty_k": 0.138, "lr": 0.348}),
    )
}
"""The model sets wmiltrack knows, by name: NanoTrack v2 (the files OpenCV's TrackerNano runs)
and v3, from ``NanoTrack/models/`` of HonglinChu/SiamTrackers at a pinned commit, with the
constants of the repository's configuration files (``shared/models/nanotrack/README.md``).
Another network is another set here and a module of its own in :mod:`wmiltrack.networks`."""


def nanotrack_versions() -> tuple[str, ...]:
    """NanoTrack's versions, from :data:`MODELS`: ``("v2", "v3")``."""
    return tuple(s.version for s in MODELS.values() if s.family == "nanotrack")


# -- where the files are -------------------------------------------------------------------
def models_dir() -> Path:
    """The models folder: ``$WMILTRACK_MODELS`` when set, else ``wmiltrack/models`` in the user's
    cache folder (``$XDG_CACHE_HOME``, else ``~/.cache``). Looking it up creates nothing."""
    env = os.environ.get(MODELS_ENV, "").strip()
    if env:
        return Path(env).expanduser().absolute()
    cache = os.environ.get("XDG_CACHE_HOME", "").strip()
    # the XDG rule: a relative XDG_CACHE_HOME is invalid and is ignored
    base = Path(cache) if cache and Path(cache).is_absolute() else Path.home() / ".cache"
    return base / "wmiltrack" / "models"


def models_dir_origin() -> str:
    """How :func:`models_dir` chose its folder, in words for messages and listings."""
    if os.environ.get(MODELS_ENV, "").strip():
        return f"from {MODELS_ENV}"
    return f"the user's cache folder; {MODELS_ENV} sets another"


_SHA1_CACHE: dict[tuple[str, int, int], str] = {}


def _sha1(path: Path) -> str:
    """The SHA-1 of a file's bytes, remembered by path, size and modification time so that
    making many trackers reads each file once."""
    st = path.stat()
    key = (str(path.resolve()), st.st_size, st.st_mtime_ns)
    digest = _SHA1_CACHE.get(key)
    if digest is None:
        h = hashlib.sha1(usedforsecurity=False)
        with path.open("rb") as f:
            while chunk := f.read(_CHUNK):
                h.update(chunk)
        digest = _SHA1_CACHE[key] = h.hexdigest()
    return digest


def _known_file(path: Path) -> tuple[ModelSet, ModelFile] | None:
    """The set and file whose pinned bytes ``path`` holds, or None (a file of no known size is
    not read)."""
    size = path.stat().st_size
    candidates = [(s, f) for s in MODELS.values() for f in s.files.values() if f.size == size]
    if not candidates:
        return None
    digest = _sha1(path)
    return next(((s, f) for s, f in candidates if f.sha1 == digest), None)


def identify(path: str | Path) -> tuple[str, str] | None:
    """The (set name, role) whose pinned bytes the file at ``path`` holds, or None (another
    file, or no file): so that a file given for one network is not given to another."""
    p = Path(path).expanduser()
    known = _known_file(p) if p.is_file() else None
    return None if known is None else (known[0].name, known[1].role)


@dataclass(frozen=True)
class FileLookup:
    """Where a set's file of ``role`` was looked for: ``path``, ``origin`` (``"backbone="``,
    ``"$WMILTRACK_NANO_BACKBONE"`` or ``"models folder"``) and ``problem``, None when the file
    is there and usable, else what is wrong with it."""

    role: str
    path: Path
    origin: str
    problem: str | None


def _model_set(name: str) -> ModelSet:
    """The set called ``name``, or a ValueError naming the sets there are."""
    if not isinstance(name, str) or name not in MODELS:
        raise ValueError(f"no model set {name!r}; the sets are {', '.join(MODELS)}")
    return MODELS[name]


def _check_given(s: ModelSet, role: str, path: Path, label: str) -> str | None:
    """What is wrong with a path given for ``role`` (``label`` says how it was given): not a
    file, or a file of another role or set."""
    if not path.is_file():
        return f"{label}{path} is not a file"
    known = _known_file(path)
    if known is not None and known[1] != s.files[role]:
        other_set, other = known
        fix = "" if other_set == s else (
            f" (to run {other_set.title}, choose it: network='{other_set.name}' for a preset, "
            f"--set network={other_set.name} on the command line, or nanotrack:{other_set.version})")
        return f"{label}{path} is {other_set.title}'s {other.role}, not {s.title}'s {role}{fix}"
    return None


def _check_stored(s: ModelSet, role: str, path: Path) -> str | None:
    """What is wrong with the models folder's file of ``role``: missing, or not the pinned bytes."""
    f = s.files[role]
    if not path.is_file():
        return f"{f.name} is not in {path.parent}"
    digest = _sha1(path)
    if digest != f.sha1:
        return (f"{path} is not {s.title}'s {role} (SHA-1 {digest}, expected {f.sha1}): "
                "remove it and fetch again")
    return None


def look_up_files(name: str, paths: Mapping[str, str | Path | None] | None = None) -> tuple[FileLookup, ...]:
    """Find each file of set ``name``, in the order of its roles: the path in ``paths[role]``
    if given, else the one in the role's environment variable, else the models folder's.

    Nothing is raised for a missing file: each :class:`FileLookup` says what is wrong, so that
    ``wmiltrack models list`` can show every file and :func:`nanotrack_files` can name them all.
    """
    s = _model_set(name)
    given = dict(paths or {})
    unknown = set(given) - set(s.files)
    if unknown:
        raise ValueError(f"{s.name} has no file {sorted(unknown)}; its files are {', '.join(s.files)}")
    out = []
    for role, f in s.files.items():
        value = given.get(role)
        env_value = os.environ.get(s.env[role], "").strip()
        if value is not None:
            path = Path(value).expanduser()
            out.append(FileLookup(role, path, f"{role}=", _check_given(s, role, path, f"{role}=")))
        elif env_value:
            path = Path(env_value).expanduser()
            label = f"{s.env[role]}="
            out.append(FileLookup(role, path, f"${s.env[role]}", _check_given(s, role, path, label)))
        else:
            path = s.folder() / f.name
            out.append(FileLookup(role, path, "models folder", _check_stored(s, role, path)))
    return tuple(out)


def _missing_message(s: ModelSet, problems: tuple[FileLookup, ...]) -> str:
    """One message: every unusable file, where wmiltrack looked, and how to give or fetch them."""
    roles = list(s.files)
    what = "; ".join(f"the {p.role}: {p.problem}" for p in problems)
    keywords = " and ".join(f"{r}=FILE" for r in roles)
    options = " and ".join(f"{s.options[r]} FILE" for r in roles)
    env = " and ".join(s.env[r] for r in roles)
    return (f"{s.title}'s model files are missing or wrong: {what}. wmiltrack looks at the paths "
            f"given, then at {env}, then in the models folder {models_dir()} ({models_dir_origin()}). "
            f"Give the paths ({keywords} in Python, {options} on the command line, or the "
            f"environment variables {env}), or fetch the files into the models folder: "
            f"`wmiltrack models fetch {s.name}` (from a local copy: "
            f"`wmiltrack models fetch {s.name} --from DIR`)")


def find_files(name: str, paths: Mapping[str, str | Path | None] | None = None) -> tuple[Path, ...]:
    """The paths of set ``name``'s files, in the order of its roles, found as :func:`look_up_files`
    says.

    Raises
    ------
    ModelFilesMissing
        A file is not found, a given path is no file, or a file is another set's or role's: one
        message names every such file and how to give or fetch them.
    """
    s = _model_set(name)
    found = look_up_files(s.name, paths)
    problems = tuple(p for p in found if p.problem is not None)
    if problems:
        raise ModelFilesMissing(_missing_message(s, problems), problems)
    return tuple(p.path for p in found)


def nanotrack_files(version: str = "v3", backbone: str | Path | None = None,
                    head: str | Path | None = None) -> tuple[Path, Path]:
    """NanoTrack ``version``'s (``"v2"`` or ``"v3"``) backbone and head: the paths given, else
    ``$WMILTRACK_NANO_BACKBONE`` / ``$WMILTRACK_NANO_HEAD``, else the models folder's
    (:func:`find_files`, which raises :class:`ModelFilesMissing` naming every missing file).
    ``version`` not one of NanoTrack's is a ValueError."""
    versions = nanotrack_versions()
    if version not in versions:
        raise ValueError(f"NanoTrack version {version!r}: use one of {', '.join(map(repr, versions))}")
    found = find_files(f"nanotrack-{version}", {"backbone": backbone, "head": head})
    return found[0], found[1]


# -- fetching ------------------------------------------------------------------------------
def fetch(name: str, *, source: str | Path | None = None, dest: Path | None = None,
          base_url: str | None = None, quiet: bool = False) -> list[Path]:
    """Put set ``name``'s files into ``dest/<name>/`` (``dest`` default :func:`models_dir`) and
    return their paths, in the order of the set's roles.

    Each file is downloaded from the set's public repository at its pinned commit
    (:meth:`ModelSet.url`; ``base_url`` or ``$WMILTRACK_MODELS_URL`` for a mirror), or, with
    ``source``, copied from a local folder that holds it directly, in a subfolder named by the
    version (``v3``), the set (``nanotrack-v3``) or the repository's (``nanotrackv3``), or at its
    path in a checkout of the repository. All files are written under temporary names beside
    their targets and checked against their SHA-1 and size before any takes its name, so a
    failure leaves no file behind. A file already in place with the right bytes is kept; one
    with other bytes is never overwritten (FileExistsError). Unless ``quiet``, each file's
    progress and what became of it are written to standard error.

    Raises
    ------
    ValueError
        ``name`` is no set.
    ModelFileMismatch
        A downloaded or copied file does not have its pinned bytes.
    FetchError
        A download failed.
    FileNotFoundError, NotADirectoryError, FileExistsError
        ``source`` lacks a file or is no folder; a target exists with other bytes.
    """
    s = _model_set(name)
    folder = s.folder(None if dest is None else Path(dest).expanduser().absolute())
    if folder.exists() and not folder.is_dir():
        raise NotADirectoryError(f"{folder} is not a folder: the files of {s.name} go there")
    say: Callable[[str], None] = (lambda _: None) if quiet else (lambda m: print(m, file=sys.stderr))
    todo = _still_to_fetch(s, folder, say)
    sources = _local_sources(s, Path(source).expanduser(), todo) if source is not None else {}
    created = _make_folders(folder) if todo else []
    staged: list[tuple[Path, ModelFile, str]] = []  # checked temporary file, its file, its origin
    try:
        for f in todo:
            if source is not None:
                src = sources[f.role]
                with src.open("rb") as stream:
                    staged.append((_stage(stream, folder, s, f, str(src), quiet), f, f"copied {src}"))
            else:
                url = s.url(f.role, base_url)
                staged.append((_download(url, folder, s, f, quiet), f, f"fetched {url}"))
        for tmp, f, how in staged:
            _place(tmp, folder / f.name, f.sha1)
            say(f"{how} -> {folder / f.name} (SHA-1 checked)")
    except BaseException:
        _remove([tmp for tmp, _, _ in staged], created)
        raise
    return [folder / f.name for f in s.files.values()]


def _still_to_fetch(s: ModelSet, folder: Path, say: Callable[[str], None]) -> list[ModelFile]:
    """The files of ``s`` not yet in ``folder``; a file there with the right bytes is kept and
    reported, one with other bytes is a FileExistsError (before anything is written)."""
    todo = []
    for role, f in s.files.items():
        target = folder / f.name
        if not target.exists():
            todo.append(f)
        elif target.is_file() and _sha1(target) == f.sha1:
            say(f"kept {target} (already there, SHA-1 checked)")
        else:
            raise FileExistsError(
                f"{target} exists and is not {s.title}'s {role} (SHA-1 {f.sha1}); it is not "
                "overwritten: move it away and fetch again")
    return todo


def _remove(temporaries: list[Path], created: list[Path]) -> None:
    """Undo a failed fetch: its temporary files, then the folders it made (innermost first,
    only while empty)."""
    for tmp in temporaries:
        tmp.unlink(missing_ok=True)
    for d in reversed(created):
        try:
            d.rmdir()
        except OSError:
            break


def _make_folders(folder: Path) -> list[Path]:
    """Create ``folder`` and its missing parents; return the ones made, outermost first."""
    made = [p for p in (folder, *folder.parents) if not p.exists()][::-1]
    folder.mkdir(parents=True, exist_ok=True)
    return made


def _source_candidates(s: ModelSet, root: Path, f: ModelFile) -> list[Path]:
    """Where a local copy of ``f`` may be in the folder ``root``."""
    repo_folder = PurePosixPath(f.path).parent.name  # "nanotrackv3"
    return [root / f.name, root / s.version / f.name, root / s.name / f.name,
            root / repo_folder / f.name, root.joinpath(*PurePosixPath(f.path).parts)]


def _local_sources(s: ModelSet, root: Path, files: list[ModelFile]) -> dict[str, Path]:
    """The file of the right bytes for each of ``files`` in the local folder ``root``."""
    if not root.is_dir():
        raise NotADirectoryError(f"{root} is not a folder (the local copy of {s.name}'s files)")
    out = {}
    for f in files:
        places = _source_candidates(s, root, f)
        present = [p for p in places if p.is_file()]
        right = [p for p in present if _sha1(p) == f.sha1]
        if right:
            out[f.role] = right[0]
        elif present:
            found = ", ".join(f"{p} (SHA-1 {_sha1(p)})" for p in present)
            raise ModelFileMismatch(f"{s.title}'s {f.role} in {root} has other bytes: {found}; "
                                    f"expected SHA-1 {f.sha1}")
        else:
            raise FileNotFoundError(f"{s.title}'s {f.role} {f.name} is not in {root}: looked at "
                                    + ", ".join(str(p) for p in places))
    return out


def _download(url: str, folder: Path, s: ModelSet, f: ModelFile, quiet: bool) -> Path:
    """Download ``url`` into a checked temporary file in ``folder``; see :func:`_stage`."""
    import urllib.error  # here: only a download needs the network modules
    import urllib.request
    from http.client import HTTPException

    try:
        response = urllib.request.urlopen(url, timeout=60)
    except urllib.error.HTTPError as exc:
        raise FetchError(f"could not download {url}: HTTP {exc.code} {exc.reason}") from None
    except (urllib.error.URLError, OSError, HTTPException) as exc:
        reason = getattr(exc, "reason", exc)
        raise FetchError(f"could not download {url}: {reason}. Without a connection, copy the "
                         f"files from a machine that has them and run `wmiltrack models fetch "
                         f"{s.name} --from DIR`") from None
    with response:
        length = response.headers.get("Content-Length")
        total = int(length) if length and length.isdigit() else f.size
        return _stage(_ReadOrFetchError(response, url), folder, s, f, url, quiet, total=total)


class _ReadOrFetchError:
    """A response whose read errors (a cut connection) are :class:`FetchError`, so that they
    are not taken for errors of writing the file."""

    def __init__(self, response: BinaryIO, url: str) -> None:
        self._response = response
        self._url = url

    def read(self, n: int) -> bytes:
        from http.client import HTTPException

        try:
            return self._response.read(n)
        except (OSError, HTTPException) as exc:
            raise FetchError(f"download of {self._url} cut short: {exc}") from None


def _stage(stream: BinaryIO | _ReadOrFetchError, folder: Path, s: ModelSet, f: ModelFile, label: str,
           quiet: bool, *, total: int | None = None) -> Path:
    """Write ``stream`` to a temporary file in ``folder`` (a progress bar on standard error) and
    return it once its SHA-1 and size are ``f``'s; on any failure the file is removed."""
    from ..progress import progress  # here: the engine imports this module, a fetch only needs tqdm

    fd, name = tempfile.mkstemp(dir=folder, prefix=f".{f.name}.", suffix=".part")
    tmp = Path(name)
    h = hashlib.sha1(usedforsecurity=False)
    size = 0
    bar = progress(range(0), total=total or f.size, desc=f"{s.name} {f.name}",
                   enabled=False if quiet else None)
    bar.unit, bar.unit_scale, bar.unit_divisor = "B", True, 1024  # bytes, as 1.4M
    try:
        with os.fdopen(fd, "wb") as out, bar:
            while chunk := stream.read(_CHUNK):
                h.update(chunk)
                out.write(chunk)
                size += len(chunk)
                bar.update(len(chunk))
        if h.hexdigest() != f.sha1 or size != f.size:
            raise ModelFileMismatch(
                f"{label} is not {s.title}'s {f.role}: SHA-1 {h.hexdigest()} ({size} bytes), expected "
                f"{f.sha1} ({f.size} bytes); nothing was written")
        tmp.chmod(0o644)  # mkstemp's 0600 would hide a shared models folder's files from others
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return tmp


def _place(tmp: Path, target: Path, sha1: str) -> None:
    """Give the checked file ``tmp`` the name ``target`` without replacing a file that appeared
    there meanwhile (a hard link fails when the name is taken); a file of the same bytes that
    appeared is kept."""
    try:
        os.link(tmp, target)
    except FileExistsError:
        if _sha1(target) != sha1:
            raise FileExistsError(f"{target} appeared while fetching, with other bytes; it is not "
                                  "overwritten") from None
    except OSError:  # no hard links on this file system: rename, having checked the name is free
        if target.exists():
            raise FileExistsError(f"{target} appeared while fetching; it is not overwritten") from None
        os.replace(tmp, target)
    tmp.unlink(missing_ok=True)
