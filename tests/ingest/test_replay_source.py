"""replay:PATH[@FPS] over real LASER dataset CSVs, stitched files and malformed CSVs."""

from __future__ import annotations

import csv
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from proxima.ingest import (
    FrameSource,
    InvalidTransition,
    LandmarkCsvError,
    SourceError,
    StateChange,
    open_source,
    parse_replay_uri,
    read_landmark_csv,
    write_landmark_csv,
)
from proxima.types import StreamState

LASER = Path(__file__).resolve().parents[2].parent / "shared" / "datasets" / "laser-uav-gesture"
GAPPY = LASER / "DJI_0171_move_upward_r.MP4.csv"  # 19 gaps in counter_frame
FRONT = LASER / "DJI_0146_have_command_f.MP4.csv"


def _parse_with_csv_module(path: Path) -> dict[int, np.ndarray]:
    """An independent reading of the file: counter_frame -> (33, 4) x, y, z, visibility."""
    rows: dict[int, np.ndarray] = {}
    with path.open(newline="") as fh:
        for rec in csv.DictReader(fh):
            cf = int(rec["counter_frame"])
            arr = rows.setdefault(cf, np.zeros((33, 4)))
            arr[int(rec["i"])] = [float(rec[k]) for k in ("x", "y", "z", "visibility")]
    return rows


def test_replay_reproduces_landmarks_and_times_with_gaps() -> None:
    expected = _parse_with_csv_module(GAPPY)
    changes: list[StateChange] = []
    with open_source(f"replay:{GAPPY}@15", realtime=False, on_state=changes.append) as src:
        assert isinstance(src, FrameSource)
        assert src.uri == f"replay:{GAPPY}@15"
        assert src.state is StreamState.CONNECTING
        frames = list(src)
    assert len(frames) == len(expected)
    for frame, (cf, arr) in zip(frames, sorted(expected.items()), strict=True):
        assert frame.image is None and frame.pose is not None
        assert frame.index == cf - 1
        assert frame.t == pytest.approx((cf - 1) / 15)
        assert frame.pose.t == frame.t
        np.testing.assert_allclose(frame.pose.xyz, arr[:, :3], atol=1e-6)
        np.testing.assert_allclose(frame.pose.visibility, arr[:, 3], atol=1e-6)
    steps = np.diff([f.index for f in frames])
    assert (steps > 1).sum() == 19  # the gaps show as gaps in index and time
    assert [(c.previous, c.state) for c in changes] == [
        (StreamState.CONNECTING, StreamState.LIVE),
        (StreamState.LIVE, StreamState.ENDED),
    ]
    assert src.state is StreamState.ENDED and src.error is None


def test_default_fps_is_30_and_realtime_paces_to_stream_time(tmp_path: Path) -> None:
    track = read_landmark_csv(FRONT)
    short = tmp_path / "short.csv"
    write_landmark_csv(short, track.frames[:16], track.xyz[:16], track.visibility[:16])
    src = open_source(f"replay:{short}")
    start = time.monotonic()
    frames = list(src)
    elapsed = time.monotonic() - start
    assert [f.t for f in frames] == pytest.approx([i / 30 for i in range(16)])
    assert elapsed >= 15 / 30 - 0.02  # paced: the last frame is 0.5 s of stream time in
    start = time.monotonic()
    assert len(list(open_source(f"replay:{short}", realtime=False))) == 16
    assert time.monotonic() - start < elapsed


def test_stitched_file_round_trips(tmp_path: Path) -> None:
    a = read_landmark_csv(FRONT)
    b = read_landmark_csv(GAPPY)
    frames = np.concatenate([a.frames, a.frames[-1] + 30 + b.frames])  # a 1 s hole between
    xyz = np.concatenate([a.xyz, b.xyz])
    vis = np.concatenate([a.visibility, b.visibility])
    out = tmp_path / "stitched.csv"
    write_landmark_csv(out, frames, xyz, vis)
    assert not list(tmp_path.glob("*.part"))
    got = list(open_source(f"replay:{out}@30", realtime=False))
    assert [f.index + 1 for f in got] == frames.tolist()
    np.testing.assert_allclose(np.stack([f.pose.xyz for f in got]), xyz, atol=1e-6)
    np.testing.assert_allclose(np.stack([f.pose.visibility for f in got]), vis, atol=1e-6)
    hole = got[len(a)].t - got[len(a) - 1].t
    assert hole == pytest.approx(31 / 30)


def test_close_from_another_thread_ends_a_realtime_replay() -> None:
    src = open_source(f"replay:{FRONT}")  # ~25 s of stream at 30 fps
    got: list[int] = []
    reader = threading.Thread(target=lambda: got.extend(f.index for f in src))
    reader.start()
    time.sleep(0.3)
    src.close()
    reader.join(timeout=2)
    assert not reader.is_alive()
    assert 0 < len(got) < 100
    assert src.state is StreamState.ENDED


def test_state_transitions_are_enforced() -> None:
    src = open_source(f"replay:{FRONT}", realtime=False)
    with pytest.raises(InvalidTransition):
        src._set_state(StreamState.STALLED)  # connecting -> stalled is not allowed
    src.close()
    with pytest.raises(InvalidTransition):
        src._set_state(StreamState.LIVE)  # ended is final
    src.close()  # closing twice is fine
    assert list(src) == []


def test_replay_uri_parsing(tmp_path: Path) -> None:
    assert parse_replay_uri("a/b.csv@12.5") == ("a/b.csv", 12.5)
    assert parse_replay_uri("a/b.csv") == ("a/b.csv", 30.0)
    assert parse_replay_uri("me@host/b.csv") == ("me@host/b.csv", 30.0)
    with pytest.raises(SourceError, match="FPS"):
        parse_replay_uri("b.csv@0")


@pytest.mark.parametrize(
    "uri, message",
    [
        ("replay:", "unknown source"),
        ("ftp://x/y", "unknown source scheme 'ftp'"),
        ("webcam:abc", "camera number"),
        ("rtsp:nohost", "bad RTSP URL"),
        ("nonsense", "unknown source"),
    ],
)
def test_bad_uris(uri: str, message: str) -> None:
    with pytest.raises(SourceError, match=message):
        open_source(uri)


HEADER = ",counter_frame,i,x,y,z,visibility\n"


def _frame_rows(cf: int, start_row: int = 0, skip: int | None = None) -> str:
    return "".join(f"{start_row + i},{cf},{i},0.5,0.5,0.0,0.9\n" for i in range(33) if i != skip)


@pytest.mark.parametrize(
    "text, line, problem",
    [
        ("frame,x,y\n1,2,3\n", 1, "header lacks column(s) counter_frame, i, z, visibility"),
        (HEADER, 2, "no landmark rows"),
        (
            HEADER + _frame_rows(1).replace("0,1,0,0.5,0.5,", "0,1,0,abc,0.5,", 1),
            2,
            "x is not a number: 'abc'",
        ),
        (HEADER + _frame_rows(1) + "33,2,0,0.5\n", 35, "expected 7 fields"),
        (
            HEADER + _frame_rows(1, skip=7) + _frame_rows(2),
            2,
            "has 32 rows, needs 33 (missing i=[7])",
        ),
        (HEADER + _frame_rows(2) + _frame_rows(1), 35, "counter_frame 1 after 2"),
        (HEADER + _frame_rows(1).replace(",0.9\n", ",1.7\n", 1), 2, "visibility must be in [0, 1]"),
        (HEADER + _frame_rows(0), 2, "counter_frame must be an integer >= 1"),
        (
            HEADER + _frame_rows(1).replace("5,1,5,", "5,1,40,", 1),
            7,
            "landmark index i must be 0..32",
        ),
        (HEADER + _frame_rows(1).replace("5,1,5,", "5,1,4,", 1), 2, "repeats a landmark index"),
        (HEADER + _frame_rows(1).replace("0.0,0.9", "nan,0.9", 1), 2, "z is not finite"),
    ],
)
def test_malformed_csv_names_file_line_and_problem(
    tmp_path: Path, text: str, line: int, problem: str
) -> None:
    bad = tmp_path / "bad.csv"
    bad.write_text(text)
    with pytest.raises(LandmarkCsvError) as info:
        open_source(f"replay:{bad}")
    assert str(info.value).startswith(f"{bad}:{line}: ")
    assert problem in str(info.value)
    assert isinstance(info.value, SourceError)


def test_missing_empty_and_binary_csv(tmp_path: Path) -> None:
    with pytest.raises(LandmarkCsvError, match="no such file"):
        open_source(f"replay:{tmp_path / 'nope.csv'}")
    empty = tmp_path / "empty.csv"
    empty.write_text("")
    with pytest.raises(LandmarkCsvError, match="empty file"):
        open_source(f"replay:{empty}")
    binary = tmp_path / "blob.csv"
    binary.write_bytes(bytes(range(256)) * 4)
    with pytest.raises(LandmarkCsvError, match=str(binary)):
        open_source(f"replay:{binary}")


def test_extra_columns_are_ignored(tmp_path: Path) -> None:
    lines = FRONT.read_text().splitlines()
    labelled = tmp_path / "labelled.csv"
    labelled.write_text(
        "\n".join([lines[0] + ",gesture"] + [line + ",have_command" for line in lines[1:]])
    )
    a = read_landmark_csv(FRONT)
    b = read_landmark_csv(labelled)
    np.testing.assert_array_equal(a.frames, b.frames)
    np.testing.assert_array_equal(a.xyz, b.xyz)
