"""Where training data comes from: an explicit path, `PROXIMA_DATA`, the `../shared`
copy beside the repository (in a checkout) or beside the working directory, the user
cache, or a verified download into the user cache (never with `PROXIMA_OFFLINE` set).

Downloads use the data sets' pinned upstream commits and the SHA-256 list shipped with
the package; files land in a temporary folder and are moved into place only when every
checksum matches, so a failed or corrupt download leaves nothing half-written.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import tempfile
import urllib.request
from dataclasses import dataclass
from pathlib import Path
from urllib.parse import quote

from proxima.gesture.clip import DataError
from proxima.shipped import checkout_root, offline

_CHECKSUMS = Path(__file__).with_name("checksums")


@dataclass(frozen=True)
class DatasetInfo:
    name: str
    shared_dir: str  # folder name under ../shared/datasets
    base_url: str  # upstream raw URL at a pinned commit; files are appended to it
    env_url: str  # environment variable that overrides base_url (mirrors, tests)


DATASETS = {
    "laser": DatasetInfo(
        "laser",
        "laser-uav-gesture",
        "https://raw.githubusercontent.com/LASER-Robotics/uav_gesture_control_federated_learning/"
        "f505511ea18ce2864db152169a2c5c516d339fb4/dataset/",
        "PROXIMA_LASER_URL",
    ),
    "uav-gesture": DatasetInfo(
        "uav-gesture",
        "uav-gesture",
        "https://raw.githubusercontent.com/asankagp/UAV-GESTURE/"
        "0fd4b2f0b63d53ab1aad2c7889728eb21b5e9eaa/UAVGESTURE/",
        "PROXIMA_UAVGESTURE_URL",
    ),
}


def cache_dir() -> Path:
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "proxima" / "datasets"


def shared_dataset_dir(name: str) -> Path | None:
    """The `../shared/datasets/<folder>` copy beside the repository (in a checkout) or
    beside the working directory, if present."""
    info = DATASETS[name]
    for root in (checkout_root(), Path.cwd()):
        if root is None:
            continue
        candidate = root.parent / "shared" / "datasets" / info.shared_dir
        if candidate.is_dir():
            return candidate
    return None


def checksums(name: str) -> dict[str, str]:
    """Relative path -> SHA-256 for every file of a data set, as shipped."""
    table: dict[str, str] = {}
    text = (_CHECKSUMS / f"{DATASETS[name].shared_dir}.sha256").read_text()
    for line in text.splitlines():
        if line.strip():
            digest, rel = line.split(maxsplit=1)
            table[rel.strip()] = digest
    return table


def sha256(path: Path) -> str:
    h = hashlib.sha256()
    with path.open("rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def download_dataset(name: str, dest: Path | None = None, base_url: str | None = None) -> Path:
    """Download every file of data set `name` into `dest` (default: the user cache) with
    a progress bar, verify each against the shipped SHA-256 list, then move the complete
    folder into place.

    Raises:
        DataError: a file could not be fetched or its checksum differs; nothing is left
            at `dest` in that case.
    """
    from rich.progress import Progress

    info = DATASETS[name]
    dest = dest or cache_dir() / info.shared_dir
    base_url = base_url or os.environ.get(info.env_url) or info.base_url
    table = checksums(name)
    dest.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{dest.name}-", dir=dest.parent))
    try:
        with Progress(transient=True) as progress:
            task = progress.add_task(f"Downloading {name}", total=len(table))
            for rel, digest in table.items():
                target = tmp / rel
                target.parent.mkdir(parents=True, exist_ok=True)
                url = base_url + quote(rel)
                try:
                    with urllib.request.urlopen(url, timeout=30) as r, target.open("wb") as f:
                        shutil.copyfileobj(r, f)
                except OSError as exc:
                    raise DataError(f"{url}: download failed ({exc})") from exc
                if sha256(target) != digest:
                    raise DataError(f"{url}: SHA-256 mismatch, the download is corrupt")
                progress.advance(task)
        (tmp / "SHA256SUMS").write_text(
            "".join(f"{d}  {r}\n" for r, d in table.items()), encoding="utf-8"
        )
        if dest.exists():
            shutil.rmtree(dest)
        tmp.rename(dest)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)
    return dest


SYNTH_PREFIX = "synth:"
SAMPLES_PREFIX = "samples:"  # the console's kept samples (console_samples.py)


def resolve_dataset(spec: str | Path | None = None) -> Path:
    """A data folder from `--data` (a path, the names `laser` / `uav-gesture`, or
    `synth:DIR` for a synthetic data set made by `proxima synth`), else `PROXIMA_DATA`,
    else the LASER set in ../shared, else the cache, else a download. `samples:DB`
    gives the console database file DB (its kept samples, console_samples.py).

    Raises:
        DataError: an explicit path that does not exist, a `synth:` folder that holds no
            synthetic data set, a `samples:` file that does not exist, a failed download,
            or no copy found while `PROXIMA_OFFLINE` forbids the download.
    """
    spec = spec or os.environ.get("PROXIMA_DATA") or "laser"
    name = str(spec)
    if name.startswith(SAMPLES_PREFIX):
        from proxima.gesture.console_samples import resolve_samples_db

        return resolve_samples_db(name)
    if name.startswith(SYNTH_PREFIX):
        from proxima.synth.dataset import MANIFEST, is_synth_dir

        path = Path(name.removeprefix(SYNTH_PREFIX)).expanduser()
        if not path.is_dir():
            raise DataError(f"{path}: synthetic data folder does not exist "
                            "(make it with `proxima synth --out DIR`)")  # fmt: skip
        if not is_synth_dir(path):
            raise DataError(
                f"{path}: not a synthetic data set (no {MANIFEST} from `proxima synth`)"
            )
        return path
    if name not in DATASETS:
        path = Path(spec).expanduser()
        if not path.exists():
            raise DataError(f"{path}: data folder does not exist")
        return path
    shared = shared_dataset_dir(name)
    if shared is not None:
        return shared
    cached = cache_dir() / DATASETS[name].shared_dir
    if cached.is_dir():
        return cached
    if offline():
        raise DataError(
            f"no {name} data set: none in ../shared/datasets beside the repository or the "
            f"working directory, none at {cached}, and PROXIMA_OFFLINE forbids downloading "
            "it; name a folder with --data or PROXIMA_DATA"
        )
    return download_dataset(name)


def resolve_laser_dir(path: str | Path | None = None) -> Path:
    """The LASER folder to use (see `resolve_dataset`)."""
    return resolve_dataset(path or os.environ.get("PROXIMA_DATA") or "laser")
