"""The download path, against a real HTTP server on 127.0.0.1 serving the shared files."""

from __future__ import annotations

import functools
import http.server
import threading
from pathlib import Path

import pytest

from proxima.gesture.clip import DataError
from proxima.gesture.data_source import checksums, download_dataset, resolve_dataset


@pytest.fixture
def http_root(tmp_path):
    root = tmp_path / "www"
    root.mkdir()
    handler = functools.partial(http.server.SimpleHTTPRequestHandler, directory=str(root))
    handler.log_message = lambda *a, **k: None  # type: ignore[method-assign]
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    yield root, f"http://127.0.0.1:{server.server_address[1]}/"
    server.shutdown()
    server.server_close()


def _publish(src: Path, root: Path) -> None:
    for rel in checksums("laser"):
        (root / rel).write_bytes((src / rel).read_bytes())


def test_download_verifies_and_lands_complete(laser_dir, http_root, tmp_path) -> None:
    root, url = http_root
    _publish(laser_dir, root)
    dest = tmp_path / "cache" / "laser-uav-gesture"
    got = download_dataset("laser", dest, url)
    assert got == dest
    assert len(list(dest.glob("*.MP4.csv"))) == 39
    assert resolve_dataset(dest) == dest


def test_corrupt_download_leaves_nothing(laser_dir, http_root, tmp_path) -> None:
    root, url = http_root
    _publish(laser_dir, root)
    victim = root / "DJI_0160_move_ahead_l.MP4.csv"
    victim.write_bytes(victim.read_bytes()[:-10])
    dest = tmp_path / "cache" / "laser-uav-gesture"
    with pytest.raises(DataError, match="SHA-256 mismatch"):
        download_dataset("laser", dest, url)
    assert not dest.exists()
    assert list((tmp_path / "cache").iterdir()) == []  # no temp folder left either


def test_failed_download_leaves_nothing(http_root, tmp_path) -> None:
    _, url = http_root  # serves nothing: 404
    dest = tmp_path / "cache" / "laser-uav-gesture"
    with pytest.raises(DataError, match="download failed"):
        download_dataset("laser", dest, url)
    assert not dest.exists()


def test_resolution_order(laser_dir, monkeypatch, tmp_path) -> None:
    monkeypatch.delenv("PROXIMA_DATA", raising=False)
    assert resolve_dataset(None) == laser_dir  # ../shared beside the repository
    monkeypatch.setenv("PROXIMA_DATA", str(tmp_path))
    assert resolve_dataset(None) == tmp_path
    assert resolve_dataset(str(laser_dir)) == laser_dir  # --data wins
    with pytest.raises(DataError, match="does not exist"):
        resolve_dataset(str(tmp_path / "nope"))
