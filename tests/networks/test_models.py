"""wmiltrack.networks.files and ``wmiltrack models``: where the networks' files are found, and fetching
them (from a folder, or over HTTP from a server on 127.0.0.1) with their SHA-1 checked.

Most tests replace the two NanoTrack sets by sets of small generated files; the tests marked by
the ``shared_models`` fixture fetch the real files, served from ``../shared/models`` or
``$WMILTRACK_TEST_MODELS`` (skipped without them, failing under ``CI``). No test contacts any host but 127.0.0.1.
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import http.server
import os
import pickle
import threading
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO_ROOT

from wmiltrack.cli import build_parser, main
from wmiltrack.networks.files import (
    MODELS,
    MODELS_ENV,
    MODELS_URL_ENV,
    FetchError,
    ModelFile,
    ModelFileMismatch,
    ModelFilesMissing,
    fetch,
    find_files,
    look_up_files,
    models_dir,
    nanotrack_files,
)
from wmiltrack.progress import NO_PROGRESS_ENV, progress

COMMIT = "248663fde6bf7c40190cf10ee396d5662919ecd3"
#: The repository's raw-file URL paths of the four files, and where ../shared/models/nanotrack
#: keeps each (written out here, not derived from wmiltrack.networks.files, so that a wrong pin fails).
REPO_FILES = {
    f"/HonglinChu/SiamTrackers/{COMMIT}/NanoTrack/models/nanotrackv2/nanotrack_backbone_sim.onnx":
        "v2/nanotrack_backbone_sim.onnx",
    f"/HonglinChu/SiamTrackers/{COMMIT}/NanoTrack/models/nanotrackv2/nanotrack_head_sim.onnx":
        "v2/nanotrack_head_sim.onnx",
    f"/HonglinChu/SiamTrackers/{COMMIT}/NanoTrack/models/nanotrackv3/nanotrack_backbone.onnx":
        "v3/nanotrack_backbone.onnx",
    f"/HonglinChu/SiamTrackers/{COMMIT}/NanoTrack/models/nanotrackv3/nanotrack_head.onnx":
        "v3/nanotrack_head.onnx",
}
NANO_ENV = ("WMILTRACK_NANO_BACKBONE", "WMILTRACK_NANO_HEAD")


@pytest.fixture(autouse=True)
def _isolated(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """No user setting reaches a test, the user's cache folder is a temporary one, and a
    download a test did not point at its own server goes to a closed port of 127.0.0.1."""
    for name in (MODELS_ENV, *NANO_ENV):
        monkeypatch.delenv(name, raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    monkeypatch.setenv(MODELS_URL_ENV, "http://127.0.0.1:9")  # the discard port: refused
    monkeypatch.setenv(NO_PROGRESS_ENV, "1")


# -- generated stand-ins for the two sets ------------------------------------------------------
@pytest.fixture()
def fake(monkeypatch: pytest.MonkeyPatch) -> dict[str, dict[str, bytes]]:
    """Both NanoTrack sets with their real names and repository paths but small generated
    contents (their SHA-1 and sizes pinned in their place): ``{set name: {role: bytes}}``."""
    contents: dict[str, dict[str, bytes]] = {}
    rng = np.random.default_rng(0)
    for k, (name, s) in enumerate(list(MODELS.items())):
        files, data = {}, {}
        for i, (role, f) in enumerate(s.files.items()):
            data[role] = rng.bytes(3000 + 500 * k + 100 * i)
            files[role] = ModelFile(role, f.path, hashlib.sha1(data[role]).hexdigest(), len(data[role]))
        monkeypatch.setitem(MODELS, name, dataclasses.replace(s, files=files))
        contents[name] = data
    return contents


def write_set(folder: Path, name: str, data: dict[str, bytes]) -> dict[str, Path]:
    """Write set ``name``'s files into ``folder``; their paths by role."""
    folder.mkdir(parents=True, exist_ok=True)
    out = {}
    for role, f in MODELS[name].files.items():
        out[role] = folder / f.name
        out[role].write_bytes(data[role])
    return out


def listing(folder: Path) -> list[str]:
    """Every file and folder under ``folder`` (hidden temporary files included)."""
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*")) if folder.exists() else []


# -- a local HTTP server -----------------------------------------------------------------------
class Served:
    """What the test server serves: URL path -> bytes, and whether to alter them on the way."""

    def __init__(self, files: dict[str, bytes]) -> None:
        self.files = files
        self.alter = False
        self.requests: list[str] = []


@pytest.fixture()
def server() -> Iterator[tuple[str, Served]]:
    """An HTTP server on 127.0.0.1 (a free port, its own thread), stopped after the test:
    ``(base URL, Served)``; the test fills ``Served.files``."""
    served = Served({})

    class Handler(http.server.BaseHTTPRequestHandler):
        def do_GET(self) -> None:  # noqa: N802 (http.server's name)
            served.requests.append(self.path)
            data = served.files.get(self.path)
            if data is None:
                self.send_error(404)
                return
            if served.alter:  # one byte changed in the middle
                data = data[: len(data) // 2] + bytes([data[len(data) // 2] ^ 0xFF]) + data[len(data) // 2 + 1:]
            self.send_response(200)
            self.send_header("Content-Length", str(len(data)))
            self.end_headers()
            self.wfile.write(data)

        def log_message(self, *args: object) -> None:
            pass

    httpd = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Handler)
    thread = threading.Thread(target=httpd.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{httpd.server_address[1]}", served
    finally:
        httpd.shutdown()
        httpd.server_close()
        thread.join()


def serve_fake(served: Served, fake: dict[str, dict[str, bytes]]) -> None:
    for path in REPO_FILES:
        version = "v2" if "nanotrackv2" in path else "v3"
        role = "backbone" if "backbone" in path else "head"
        served.files[path] = fake[f"nanotrack-{version}"][role]


@pytest.fixture(scope="session")
def shared_models(nanotrack_models: dict[str, tuple[Path, Path]],
                  tmp_path_factory: pytest.TempPathFactory) -> Path:
    """NanoTrack's real files (conftest's ``nanotrack_models``: ``$WMILTRACK_TEST_MODELS`` or
    ``../shared/models/nanotrack``; skipped when missing, a failure under CI), linked into a
    folder with ``v2/`` and ``v3/`` as ``shared/models/nanotrack`` lays them out."""
    root = tmp_path_factory.mktemp("shared_models")
    for version, files in nanotrack_models.items():
        (root / version).mkdir()
        for path in files:
            (root / version / path.name).symlink_to(path.resolve())
    return root


# -- the registry and the models folder --------------------------------------------------------
def test_the_sets_pin_the_repository_commit_and_paths() -> None:
    assert list(MODELS) == ["nanotrack-v2", "nanotrack-v3"]
    urls = []
    for s in MODELS.values():
        assert (s.repository, s.commit) == ("HonglinChu/SiamTrackers", COMMIT)
        assert list(s.files) == ["backbone", "head"]
        for role, f in s.files.items():
            assert f.role == role and len(f.sha1) == 40 and int(f.sha1, 16) >= 0 and f.size > 0
            urls.append(s.url(role, "http://mirror.example/x/"))
    assert urls == [f"http://mirror.example/x{p}" for p in REPO_FILES]
    assert MODELS["nanotrack-v3"].url("head", None).startswith("http://127.0.0.1:9/")  # $WMILTRACK_MODELS_URL
    assert pickle.loads(pickle.dumps(MODELS)) == MODELS  # a tracker holding a set can be copied


def test_the_default_url_is_githubs_raw_files(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv(MODELS_URL_ENV)
    assert MODELS["nanotrack-v3"].url("backbone") == (
        f"https://raw.githubusercontent.com/HonglinChu/SiamTrackers/{COMMIT}/"
        "NanoTrack/models/nanotrackv3/nanotrack_backbone.onnx")


def test_models_dir_is_the_variable_else_the_cache_folder_and_is_not_created(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    assert models_dir() == tmp_path / "cache" / "wmiltrack" / "models"
    monkeypatch.setenv("XDG_CACHE_HOME", "relative/cache")  # invalid by the XDG rule: ignored
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert models_dir() == tmp_path / "home" / ".cache" / "wmiltrack" / "models"
    monkeypatch.delenv("XDG_CACHE_HOME")
    assert models_dir() == tmp_path / "home" / ".cache" / "wmiltrack" / "models"
    monkeypatch.setenv(MODELS_ENV, str(tmp_path / "mine"))
    assert models_dir() == tmp_path / "mine"
    with pytest.raises(ModelFilesMissing):
        nanotrack_files()
    assert listing(tmp_path) == []  # looking created nothing


# -- lookup ------------------------------------------------------------------------------------
def test_lookup_order_given_paths_then_variables_then_models_folder(
        tmp_path: Path, fake: dict[str, dict[str, bytes]], monkeypatch: pytest.MonkeyPatch) -> None:
    folder = write_set(models_dir() / "nanotrack-v3", "nanotrack-v3", fake["nanotrack-v3"])
    assert nanotrack_files() == (folder["backbone"], folder["head"])
    assert nanotrack_files("v3") == find_files("nanotrack-v3")
    env = write_set(tmp_path / "env", "nanotrack-v3", fake["nanotrack-v3"])
    monkeypatch.setenv("WMILTRACK_NANO_BACKBONE", str(env["backbone"]))
    assert nanotrack_files() == (env["backbone"], folder["head"])
    given = write_set(tmp_path / "given", "nanotrack-v3", fake["nanotrack-v3"])
    assert nanotrack_files(backbone=str(given["backbone"])) == (given["backbone"], folder["head"])
    assert nanotrack_files(head=given["head"]) == (env["backbone"], given["head"])
    assert [p.origin for p in look_up_files("nanotrack-v3", {"head": given["head"]})] == [
        "$WMILTRACK_NANO_BACKBONE", "head="]


def test_a_given_path_that_is_no_file_is_an_error_without_falling_back(
        tmp_path: Path, fake: dict[str, dict[str, bytes]], monkeypatch: pytest.MonkeyPatch) -> None:
    write_set(models_dir() / "nanotrack-v3", "nanotrack-v3", fake["nanotrack-v3"])  # would be found
    with pytest.raises(ModelFilesMissing, match=r"the backbone: backbone=.*nope\.onnx is not a file") as e:
        nanotrack_files(backbone=tmp_path / "nope.onnx")
    assert [p.role for p in e.value.problems] == ["backbone"]
    monkeypatch.setenv("WMILTRACK_NANO_HEAD", str(tmp_path))  # a folder, not a file
    with pytest.raises(ModelFilesMissing, match=rf"the head: WMILTRACK_NANO_HEAD={tmp_path} is not a file"):
        nanotrack_files()


def test_the_missing_files_error_says_everything_in_one_message(tmp_path: Path) -> None:
    with pytest.raises(ModelFilesMissing) as e:
        nanotrack_files("v3")
    msg = str(e.value)
    assert isinstance(e.value, FileNotFoundError) and "\n" not in msg
    folder = tmp_path / "cache" / "wmiltrack" / "models"
    for part in ("nanotrack_backbone.onnx is not in", "nanotrack_head.onnx is not in",
                 str(folder / "nanotrack-v3"), "backbone=FILE", "head=FILE", "--nano-backbone FILE",
                 "--nano-head FILE", "WMILTRACK_NANO_BACKBONE", "WMILTRACK_NANO_HEAD",
                 "`wmiltrack models fetch nanotrack-v3`", "--from DIR", "WMILTRACK_MODELS"):
        assert part in msg, part
    assert [p.role for p in e.value.problems] == ["backbone", "head"]
    again = pickle.loads(pickle.dumps(e.value))  # raised in a worker process, reported in the parent
    assert type(again) is ModelFilesMissing and str(again) == msg and again.problems == e.value.problems
    with pytest.raises(ModelFilesMissing, match="nanotrack_backbone_sim.onnx is not in .*nanotrack-v2"):
        nanotrack_files("v2")


def test_the_options_the_message_names_are_the_command_lines() -> None:
    track = next(a for a in build_parser()._actions if getattr(a, "choices", None)).choices["track"]  # noqa: SLF001
    options = {o for a in track._actions for o in a.option_strings}  # noqa: SLF001
    for s in MODELS.values():
        assert set(s.options.values()) <= options


def test_bad_versions_and_roles_are_refused() -> None:
    with pytest.raises(ValueError, match="'v4'.*'v2', 'v3'"):
        nanotrack_files("v4")
    with pytest.raises(ValueError, match="no model set 'nanotrack'; the sets are nanotrack-v2, nanotrack-v3"):
        look_up_files("nanotrack")
    with pytest.raises(ValueError, match=r"no file \['neck'\]"):
        look_up_files("nanotrack-v3", {"neck": "x.onnx"})


def test_another_sets_or_roles_file_is_an_error(
        tmp_path: Path, fake: dict[str, dict[str, bytes]], monkeypatch: pytest.MonkeyPatch) -> None:
    v2 = write_set(tmp_path / "v2", "nanotrack-v2", fake["nanotrack-v2"])
    v3 = write_set(tmp_path / "v3", "nanotrack-v3", fake["nanotrack-v3"])
    with pytest.raises(ModelFilesMissing, match="is NanoTrack v2's backbone, not NanoTrack v3's backbone"):
        nanotrack_files("v3", backbone=v2["backbone"], head=v3["head"])
    with pytest.raises(ModelFilesMissing, match="is NanoTrack v3's head, not NanoTrack v3's backbone"):
        nanotrack_files("v3", backbone=v3["head"], head=v3["head"])
    monkeypatch.setenv("WMILTRACK_NANO_BACKBONE", str(v2["backbone"]))  # set for opencv:Nano (v2)
    monkeypatch.setenv("WMILTRACK_NANO_HEAD", str(v2["head"]))
    assert nanotrack_files("v2") == (v2["backbone"], v2["head"])
    with pytest.raises(ModelFilesMissing, match="WMILTRACK_NANO_HEAD=.* is NanoTrack v2's head"):
        nanotrack_files("v3")
    own = tmp_path / "own.onnx"  # a file of no known set (one's own training): taken as given
    own.write_bytes(b"x" * 10)
    assert nanotrack_files("v3", backbone=own, head=own) == (own, own)


def test_a_models_folder_file_with_other_bytes_is_an_error(fake: dict[str, dict[str, bytes]]) -> None:
    folder = write_set(models_dir() / "nanotrack-v3", "nanotrack-v3", fake["nanotrack-v3"])
    folder["head"].write_bytes(fake["nanotrack-v3"]["head"][:-1])  # cut short
    sha1 = MODELS["nanotrack-v3"].files["head"].sha1
    with pytest.raises(ModelFilesMissing, match=rf"is not NanoTrack v3's head \(SHA-1 [0-9a-f]{{40}}, "
                       rf"expected {sha1}\): remove it and fetch again") as e:
        nanotrack_files()
    assert [p.role for p in e.value.problems] == ["head"]


# -- fetching from a folder ---------------------------------------------------------------------
@pytest.mark.parametrize("layout", ["", "v3", "nanotrack-v3", "nanotrackv3", "NanoTrack/models/nanotrackv3"])
def test_fetch_from_a_local_folder(tmp_path: Path, fake: dict[str, dict[str, bytes]], layout: str,
                                   capsys: pytest.CaptureFixture[str]) -> None:
    write_set(tmp_path / "copy" / layout, "nanotrack-v3", fake["nanotrack-v3"])
    paths = fetch("nanotrack-v3", source=tmp_path / "copy")
    assert paths == list(nanotrack_files()) == [models_dir() / "nanotrack-v3" / n
                                                 for n in ("nanotrack_backbone.onnx", "nanotrack_head.onnx")]
    assert [p.read_bytes() for p in paths] == list(fake["nanotrack-v3"].values())
    assert listing(models_dir()) == ["nanotrack-v3", "nanotrack-v3/nanotrack_backbone.onnx",
                                     "nanotrack-v3/nanotrack_head.onnx"]
    assert capsys.readouterr().err.count("(SHA-1 checked)") == 2
    assert fetch("nanotrack-v3", source=tmp_path / "copy") == paths  # again: kept
    assert capsys.readouterr().err.count("kept ") == 2


def test_fetch_refuses_a_wrong_local_copy_and_a_missing_one(
        tmp_path: Path, fake: dict[str, dict[str, bytes]]) -> None:
    files = write_set(tmp_path / "copy", "nanotrack-v3", fake["nanotrack-v3"])
    files["head"].write_bytes(b"not the head")
    with pytest.raises(ModelFileMismatch, match="NanoTrack v3's head in .* has other bytes"):
        fetch("nanotrack-v3", source=tmp_path / "copy")
    files["head"].unlink()
    with pytest.raises(FileNotFoundError, match="NanoTrack v3's head nanotrack_head.onnx is not in"):
        fetch("nanotrack-v3", source=tmp_path / "copy")
    with pytest.raises(NotADirectoryError, match="is not a folder"):
        fetch("nanotrack-v3", source=files["backbone"])
    assert listing(tmp_path / "cache") == []  # nothing written, no folder made


def test_fetch_never_overwrites_a_different_file(tmp_path: Path, fake: dict[str, dict[str, bytes]]) -> None:
    write_set(tmp_path / "copy", "nanotrack-v3", fake["nanotrack-v3"])
    mine = models_dir() / "nanotrack-v3" / "nanotrack_head.onnx"
    mine.parent.mkdir(parents=True)
    mine.write_bytes(b"the user's own file")
    with pytest.raises(FileExistsError, match="is not NanoTrack v3's head .* not overwritten"):
        fetch("nanotrack-v3", source=tmp_path / "copy")
    assert mine.read_bytes() == b"the user's own file"
    assert listing(mine.parent) == ["nanotrack_head.onnx"]  # the backbone was not written either


def test_fetch_into_a_given_folder(tmp_path: Path, fake: dict[str, dict[str, bytes]]) -> None:
    write_set(tmp_path / "copy" / "v2", "nanotrack-v2", fake["nanotrack-v2"])
    paths = fetch("nanotrack-v2", source=tmp_path / "copy", dest=tmp_path / "dest", quiet=True)
    assert paths == [tmp_path / "dest" / "nanotrack-v2" / f.name for f in MODELS["nanotrack-v2"].files.values()]
    assert all(p.stat().st_mode & 0o777 == 0o644 for p in paths)


# -- fetching over HTTP (generated files) -----------------------------------------------------------
def test_fetch_downloads_and_checks(server: tuple[str, Served], fake: dict[str, dict[str, bytes]]) -> None:
    url, served = server
    serve_fake(served, fake)
    paths = fetch("nanotrack-v3", base_url=url)
    assert [p.read_bytes() for p in paths] == list(fake["nanotrack-v3"].values())
    assert served.requests == [p for p in REPO_FILES if "nanotrackv3" in p]
    assert fetch("nanotrack-v3", base_url=url) == paths and len(served.requests) == 2  # kept: no request


def test_altered_bytes_leave_nothing_behind(server: tuple[str, Served], fake: dict[str, dict[str, bytes]],
                                            tmp_path: Path) -> None:
    url, served = server
    serve_fake(served, fake)
    served.alter = True
    with pytest.raises(ModelFileMismatch, match=r"nanotrack_backbone.onnx is not NanoTrack v3's backbone: "
                       r"SHA-1 [0-9a-f]{40} \(3500 bytes\).*nothing was written"):
        fetch("nanotrack-v3", base_url=url)
    assert listing(tmp_path / "cache") == []
    # the head alone altered: the good backbone is not put in place either (a set goes in whole)
    served.alter = False
    head = next(p for p in REPO_FILES if "nanotrackv3/nanotrack_head" in p)
    served.files[head] = served.files[head][:-1] + b"!"
    with pytest.raises(ModelFileMismatch, match="is not NanoTrack v3's head"):
        fetch("nanotrack-v3", base_url=url)
    assert listing(tmp_path / "cache") == []


def test_http_errors_are_fetch_errors(server: tuple[str, Served], tmp_path: Path) -> None:
    url, _ = server  # serves nothing: 404
    with pytest.raises(FetchError, match=r"could not download .*nanotrack_backbone.onnx: HTTP 404"):
        fetch("nanotrack-v3", base_url=url)
    with pytest.raises(FetchError, match="could not download http://127.0.0.1:9/.*--from DIR"):
        fetch("nanotrack-v3")  # $WMILTRACK_MODELS_URL: a closed port
    assert listing(tmp_path / "cache") == []


# -- the command line ---------------------------------------------------------------------------------
def test_cli_exit_codes(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["models"]) == 2
    assert "list" in capsys.readouterr().err
    for argv in (["models", "fetch", "nanotrack-v4"], ["models", "path"], ["models", "get"]):
        with pytest.raises(SystemExit) as e:
            main(argv)
        assert e.value.code == 2, argv
    capsys.readouterr()
    assert main(["models", "fetch", "nanotrack-v3", "--from", str(tmp_path / "none")]) == 2
    assert "--from" in capsys.readouterr().err
    (tmp_path / "file").write_text("x")
    assert main(["models", "fetch", "nanotrack-v3", "--dest", str(tmp_path / "file")]) == 2
    assert main(["models", "fetch", "nanotrack-v3"]) == 1  # the closed port
    assert "could not download" in capsys.readouterr().err
    assert main(["models", "path", "nanotrack-v3"]) == 1
    err = capsys.readouterr().err
    assert err.startswith("wmiltrack: error: NanoTrack v3's model files") and err.count("\n") == 1
    assert listing(tmp_path / "cache") == []


def test_cli_fetch_from_list_and_path(tmp_path: Path, fake: dict[str, dict[str, bytes]],
                                      capsys: pytest.CaptureFixture[str]) -> None:
    write_set(tmp_path / "copy" / "nanotrack-v3", "nanotrack-v3", fake["nanotrack-v3"])
    assert main(["models", "list"]) == 0
    out = capsys.readouterr().out
    assert out.count("missing: ") == 4 and "present:" not in out
    assert main(["models", "fetch", "nanotrack-v3", "--from", str(tmp_path / "copy")]) == 0
    fetched = capsys.readouterr().out.split()
    assert main(["models", "path", "nanotrack-v3"]) == 0
    assert capsys.readouterr().out.split() == fetched == [str(p) for p in nanotrack_files()]
    assert main(["models", "list"]) == 0
    out = capsys.readouterr().out
    assert out.count("missing: ") == 2 and out.count("present: ") == 2
    assert f"models folder: {models_dir()} (the user's cache folder" in out
    # a fetch into another folder says how to use it
    assert main(["models", "fetch", "nanotrack-v3", "--from", str(tmp_path / "copy"),
                 "--dest", str(tmp_path / "elsewhere")]) == 0
    assert f"set WMILTRACK_MODELS={tmp_path / 'elsewhere'}" in capsys.readouterr().err


def test_cli_fetch_shows_a_progress_bar(server: tuple[str, Served], fake: dict[str, dict[str, bytes]],
                                        monkeypatch: pytest.MonkeyPatch,
                                        capsys: pytest.CaptureFixture[str]) -> None:
    url, served = server
    serve_fake(served, fake)
    monkeypatch.setenv(MODELS_URL_ENV, url)
    monkeypatch.delenv(NO_PROGRESS_ENV)
    # (a local fetch ends before the bar's usual half-second delay: draw it from the start)
    monkeypatch.setattr("wmiltrack.progress.progress", functools.partial(progress, delay=0.0))
    assert main(["models", "fetch", "nanotrack-v2"]) == 0
    err = capsys.readouterr().err
    assert "nanotrack-v2 nanotrack_head_sim.onnx: 100%" in err and err.count("(SHA-1 checked)") == 2


# -- NanoTrack's real files, served like the repository -------------------------------------------
def test_the_pinned_sha1s_are_the_shared_files(shared_models: Path) -> None:
    for s in MODELS.values():
        for f in s.files.values():
            data = (shared_models / s.version / f.name).read_bytes()
            assert (hashlib.sha1(data).hexdigest(), len(data)) == (f.sha1, f.size)


def test_cli_fetches_the_real_files_over_http(shared_models: Path, server: tuple[str, Served],
                                              tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                              capsys: pytest.CaptureFixture[str]) -> None:
    url, served = server
    served.files = {path: (shared_models / rel).read_bytes() for path, rel in REPO_FILES.items()}
    monkeypatch.setenv(MODELS_URL_ENV, url)
    served.alter = True
    assert main(["models", "fetch", "nanotrack-v3", "--dest", str(tmp_path / "m")]) == 1
    assert "is not NanoTrack v3's backbone" in capsys.readouterr().err
    assert listing(tmp_path / "m") == []
    served.alter = False
    for name in ("nanotrack-v3", "nanotrack-v2"):
        assert main(["models", "fetch", name, "--dest", str(tmp_path / "m")]) == 0
    assert len(served.requests) == 1 + 4
    monkeypatch.setenv(MODELS_ENV, str(tmp_path / "m"))
    capsys.readouterr()
    for version in ("v2", "v3"):
        assert main(["models", "path", f"nanotrack-{version}"]) == 0
        paths = [Path(p) for p in capsys.readouterr().out.split()]
        assert paths == list(nanotrack_files(version))
        assert [p.read_bytes() for p in paths] == [(shared_models / version / p.name).read_bytes()
                                                   for p in paths]


def test_fetch_from_the_shared_copy(shared_models: Path, tmp_path: Path,
                                    monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv(MODELS_ENV, str(tmp_path / "m"))
    for name in MODELS:
        paths = fetch(name, source=shared_models, quiet=True)
        assert paths == list(find_files(name))
        assert [hashlib.sha1(p.read_bytes()).hexdigest() for p in paths] == [
            f.sha1 for f in MODELS[name].files.values()]


def test_the_real_file_tests_look_where_the_variable_says(tmp_path: Path) -> None:
    """``WMILTRACK_TEST_MODELS`` decides where the real files are looked for: pointed at an
    empty folder, the real-file tests skip (naming the variable) instead of reading
    ``../shared``."""
    import subprocess
    import sys

    env = {k: v for k, v in os.environ.items() if k != "CI"}
    env["WMILTRACK_TEST_MODELS"] = str(tmp_path)
    r = subprocess.run([sys.executable, "-m", "pytest", "-q", "-rs", "-p", "no:cacheprovider",
                        "tests/networks/test_models.py", "-k", "the_pinned_sha1s_are_the_shared_files"],
                       capture_output=True, text=True, cwd=REPO_ROOT, env=env, timeout=300, check=False)
    assert "1 skipped" in r.stdout and "WMILTRACK_TEST_MODELS" in r.stdout, r.stdout


def test_a_progress_bar_in_a_log_file_is_never_left_at_0(tmp_path: Path, fake: dict[str, dict[str, bytes]],
                                                        monkeypatch: pytest.MonkeyPatch) -> None:
    """Standard error a file (a log): a bar is drawn only once it has something to show (the
    progress helper's delay), so no bar of a finished file stays at 0 %."""
    monkeypatch.delenv(NO_PROGRESS_ENV)
    write_set(tmp_path / "copy", "nanotrack-v3", fake["nanotrack-v3"])
    log = tmp_path / "log.txt"
    with log.open("w") as err:
        monkeypatch.setattr("sys.stderr", err)
        fetch("nanotrack-v3", source=tmp_path / "copy")
    text = log.read_text()
    assert text.count("(SHA-1 checked)") == 2
    assert "  0%|" not in text or text.count("100%|") >= 2, text
