"""PoseEstimator on real photos shipped in pip packages, and the model resolution chain
(including a real HTTP download from a local server)."""

from __future__ import annotations

import functools
import http.server
import os
import threading
from collections.abc import Iterator
from pathlib import Path

import cv2
import matplotlib
import numpy as np
import pytest

from proxima.pose import PoseEstimator, PoseModelError, operator_visible, resolve_pose_model
from proxima.pose.model import MODEL_FILENAME, download_model, sha256_of
from proxima.types import Pose

skimage_data = pytest.importorskip("skimage.data")

SHARED_MODEL = Path(__file__).resolve().parents[2].parent / "shared/models" / MODEL_FILENAME
SHARED_SHA256 = "5feb12c325d23763b40149bccbf6bfd2f550c71351dc787c2463971c5054199e"


def _rgb_to_bgr(img: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(img[:, :, ::-1])


@pytest.fixture(scope="module")
def estimator() -> Iterator[PoseEstimator]:
    with PoseEstimator(num_poses=2) as est:
        yield est


@pytest.fixture
def fresh() -> Iterator[PoseEstimator]:
    """A new estimator per test: VIDEO mode tracks across calls, photos are unrelated."""
    with PoseEstimator(num_poses=2) as est:
        yield est


def test_grace_hopper_portrait(fresh: PoseEstimator) -> None:
    path = Path(matplotlib.get_data_path()) / "sample_data" / "grace_hopper.jpg"
    img = cv2.imread(str(path))
    poses = fresh.estimate(img, 0.0)
    assert len(poses) == 1
    pose = poses[0]
    assert isinstance(pose, Pose) and type(pose.xyz) is np.ndarray
    assert pose.image_size == (img.shape[1], img.shape[0])
    assert pose.t == 0.0
    nose, l_sh, r_sh = pose.xyz[0], pose.xyz[11], pose.xyz[12]
    assert 0.35 < nose[0] < 0.7 and 0.2 < nose[1] < 0.5  # face in the upper middle
    assert nose[1] < min(l_sh[1], r_sh[1])  # head above shoulders
    assert l_sh[0] > r_sh[0]  # her left shoulder is on the image's right
    assert (pose.visibility[[0, 2, 5, 11, 12]] > 0.9).all()
    # A head-and-shoulders portrait: no feet in view, so the operator is not "visible".
    assert (pose.visibility[27:33] < 0.5).all()
    assert not operator_visible(pose)


def test_astronaut(fresh: PoseEstimator) -> None:
    img = _rgb_to_bgr(skimage_data.astronaut())
    poses = fresh.estimate(img, 0.0)
    assert poses, "no pose found on the astronaut photo"
    best = max(poses, key=lambda p: float(p.visibility[:13].mean()))
    nose = best.xyz[0]
    assert 0.3 < nose[0] < 0.65 and 0.1 < nose[1] < 0.45
    assert nose[1] < best.xyz[11, 1] and nose[1] < best.xyz[12, 1]


@pytest.mark.parametrize("name", ["grass", "rocket"])
def test_no_person_gives_no_pose(fresh: PoseEstimator, name: str) -> None:
    img = getattr(skimage_data, name)()
    img = cv2.cvtColor(img, cv2.COLOR_GRAY2BGR) if img.ndim == 2 else _rgb_to_bgr(img)
    assert fresh.estimate(img, 0.0) == []


def test_video_mode_tracks_over_repeated_and_equal_timestamps(estimator: PoseEstimator) -> None:
    img = cv2.imread(str(Path(matplotlib.get_data_path()) / "sample_data" / "grace_hopper.jpg"))
    first = estimator.estimate(img, 10.0)
    again = estimator.estimate(img, 10.0)  # same t: nudged, not refused
    later = estimator.estimate(img, 10.033)
    assert len(first) == len(again) == len(later) == 1
    np.testing.assert_allclose(first[0].xyz[:, :2], later[0].xyz[:, :2], atol=0.02)


def test_bad_input_and_closed_estimator() -> None:
    est = PoseEstimator()
    with pytest.raises(ValueError, match="HxWx3 uint8"):
        est.estimate(np.zeros((10, 10), np.uint8), 0.0)
    est.close()
    est.close()
    with pytest.raises(ValueError, match="closed"):
        est.estimate(np.zeros((10, 10, 3), np.uint8), 0.0)


def test_model_resolution_order(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # Explicit path wins; a missing one is an error naming it.
    assert resolve_pose_model(SHARED_MODEL) == SHARED_MODEL
    with pytest.raises(PoseModelError, match=r"nope\.task does not exist"):
        resolve_pose_model(tmp_path / "nope.task")
    # The real repository resolves to models/*.task or ../shared/models.
    resolved = resolve_pose_model()
    assert resolved.suffix == ".task" and resolved.is_file()
    # A repo with models/*.task uses it.
    repo = tmp_path / "work" / "repo"
    (repo / "models").mkdir(parents=True)
    (repo / "models" / "pose_landmarker_lite.task").write_bytes(b"x")
    assert resolve_pose_model(repo_root=repo).name == "pose_landmarker_lite.task"
    # Without one, ../shared/models beside the repo.
    bare = tmp_path / "w2" / "repo"
    bare.mkdir(parents=True)
    shared = tmp_path / "w2" / "shared" / "models"
    shared.mkdir(parents=True)
    (shared / MODEL_FILENAME).write_bytes(b"y")
    assert resolve_pose_model(repo_root=bare) == shared / MODEL_FILENAME
    # Nothing anywhere and no download: a clear error.
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    lonely = tmp_path / "w3" / "repo"
    lonely.mkdir(parents=True)
    with pytest.raises(PoseModelError, match="downloading is off"):
        resolve_pose_model(repo_root=lonely, download=False)


@pytest.fixture
def model_server() -> Iterator[str]:
    """A real HTTP server on 127.0.0.1 serving the shared model directory."""
    handler = functools.partial(
        http.server.SimpleHTTPRequestHandler, directory=str(SHARED_MODEL.parent)
    )
    handler.log_message = lambda *a, **k: None  # type: ignore[attr-defined]
    httpd = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=httpd.serve_forever, daemon=True)
    thread.start()
    yield f"http://127.0.0.1:{httpd.server_address[1]}/{MODEL_FILENAME}"
    httpd.shutdown()
    httpd.server_close()


def test_download_checks_sha256_and_is_atomic(tmp_path: Path, model_server: str) -> None:
    dest = tmp_path / "cache" / MODEL_FILENAME
    with pytest.raises(PoseModelError, match="SHA-256"):
        download_model(dest, model_server, "0" * 64, progress=False)
    assert not dest.exists() and os.listdir(dest.parent) == []  # nothing half-written
    with pytest.raises(PoseModelError, match="cannot download"):
        download_model(dest, model_server + ".missing", None, progress=False)
    assert os.listdir(dest.parent) == []
    got = download_model(dest, model_server, SHARED_SHA256, progress=False)
    assert got == dest and sha256_of(dest) == SHARED_SHA256
    with PoseEstimator(dest) as est:  # the downloaded bundle loads and runs
        assert est.estimate(np.zeros((64, 64, 3), np.uint8), 0.0) == []


def test_unloadable_model_is_a_clear_error(tmp_path: Path) -> None:
    junk = tmp_path / "junk.task"
    junk.write_bytes(b"not a model")
    with pytest.raises(PoseModelError, match=r"junk\.task"):
        PoseEstimator(junk)
