"""Find the MediaPipe pose model bundle (`.task`), downloading it only as a last resort.

Order: an explicit path (`--pose-model`, `[engine] pose_model`), then `models/*.task`
and the shared offline bundle `../shared/models/pose_landmarker_full.task` beside the
repository in a checkout, else beside the working directory, then the user cache, then
the official bundle downloaded into the user cache (never with `PROXIMA_OFFLINE` set).
The download is pinned to a versioned URL and its SHA-256, shows a progress bar and is
atomic: it is written to a temporary file in the cache directory and renamed only after
the checksum matched, so a crash or a bad download never leaves a half-written model.
"""

from __future__ import annotations

import hashlib
import os
import tempfile
import urllib.request
from pathlib import Path

from proxima.shipped import checkout_root, offline

# The official "full" bundle, version 1 (a versioned URL, unlike `latest`, never changes,
# so its checksum can be pinned).
OFFICIAL_MODEL_URL = (
    "https://storage.googleapis.com/mediapipe-models/pose_landmarker/"
    "pose_landmarker_full/float16/1/pose_landmarker_full.task"
)
OFFICIAL_MODEL_SHA256 = "5134a3aad27a58b93da0088d431f366da362b44e3ccfbe3462b3827a839011b1"
MODEL_FILENAME = "pose_landmarker_full.task"


class PoseModelError(RuntimeError):
    """No usable pose model: a given path is missing, or a download failed or did not
    match its checksum. The message says which and where."""


def cache_dir() -> Path:
    """Where downloaded models live: `$XDG_CACHE_HOME/proxima/models` (~/.cache/...)."""
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "proxima" / "models"


def sha256_of(path: Path) -> str:
    """Hex SHA-256 of a file, read in 1 MiB blocks."""
    digest = hashlib.sha256()
    with path.open("rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def _repo_model(repo_root: Path) -> Path | None:
    models = sorted((repo_root / "models").glob("*.task"))
    if not models:
        return None
    preferred = [m for m in models if m.name.startswith("pose_landmarker")]
    return (preferred or models)[0]


def download_model(
    dest: Path,
    url: str = OFFICIAL_MODEL_URL,
    sha256: str | None = OFFICIAL_MODEL_SHA256,
    *,
    progress: bool = True,
    timeout_s: float = 30.0,
) -> Path:
    """Download `url` to `dest` atomically, checking `sha256` when given.

    Raises:
        PoseModelError: the download failed or the checksum differs (nothing is left at
            `dest` in either case).
    """
    from rich.progress import (
        BarColumn,
        DownloadColumn,
        Progress,
        TimeRemainingColumn,
        TransferSpeedColumn,
    )

    dest.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp_name = tempfile.mkstemp(prefix=dest.name + ".", suffix=".part", dir=dest.parent)
    tmp = Path(tmp_name)
    digest = hashlib.sha256()
    try:
        with os.fdopen(fd, "wb") as out, urllib.request.urlopen(url, timeout=timeout_s) as resp:
            total = int(resp.headers.get("Content-Length") or 0) or None
            with Progress(
                "[progress.description]{task.description}",
                BarColumn(),
                DownloadColumn(),
                TransferSpeedColumn(),
                TimeRemainingColumn(),
                disable=not progress,
                transient=True,
            ) as bar:
                task = bar.add_task(f"pose model {dest.name}", total=total)
                while block := resp.read(1 << 16):
                    out.write(block)
                    digest.update(block)
                    bar.advance(task, len(block))
        if sha256 is not None and digest.hexdigest() != sha256.lower():
            raise PoseModelError(
                f"downloaded {url} has SHA-256 {digest.hexdigest()}, expected {sha256}; "
                "not installed"
            )
        tmp.replace(dest)
    except PoseModelError:
        tmp.unlink(missing_ok=True)
        raise
    except OSError as exc:  # URLError, HTTPError and timeouts are OSErrors
        tmp.unlink(missing_ok=True)
        raise PoseModelError(f"cannot download the pose model from {url}: {exc}") from exc
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return dest


def resolve_pose_model(
    path: str | Path | None = None,
    *,
    repo_root: Path | None = None,
    download: bool | None = None,
) -> Path:
    """Return the pose model to use (see the module docstring for the order). `repo_root`
    replaces the checkout or working directory searched; `download` defaults to on
    unless `PROXIMA_OFFLINE` is set.

    Raises:
        PoseModelError: `path` is given but missing, or nothing is found and the
            download is off or fails.
    """
    if path is not None:
        p = Path(path).expanduser()
        if not p.is_file():
            raise PoseModelError(f"pose model {p} does not exist")
        return p
    root = repo_root or checkout_root() or Path.cwd()
    found = _repo_model(root)
    if found is not None:
        return found
    shared = root.parent / "shared" / "models" / MODEL_FILENAME
    if shared.is_file():
        return shared
    cached = cache_dir() / MODEL_FILENAME
    if cached.is_file():
        return cached
    if download is None and offline():
        raise PoseModelError(
            f"no pose model: none given, none in {root / 'models'}, none at {shared} or "
            f"{cached}, and PROXIMA_OFFLINE forbids downloading it; name one with "
            "--pose-model or [engine] pose_model"
        )
    if download is False:
        raise PoseModelError(
            f"no pose model: none given, none in {root / 'models'}, none at {shared} or "
            f"{cached}, and downloading is off"
        )
    return download_model(cached)
