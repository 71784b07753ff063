"""Per-command evidence thresholds (evaluation.robust_training.tune_by_command) on real
stitched held-out streams under the `field` condition: the search keeps its starting
setting unless a change ranks better, and its result scores as it says."""

from pathlib import Path

import pytest

from proxima.control import ControlSettings
from proxima.engine.config import EngineSettings
from proxima.evaluation.latency import evaluate_config, rank
from proxima.evaluation.robust_training import (
    decision_streams,
    pool,
    recognitions,
    tune_by_command,
)
from proxima.gesture.capture import condition
from proxima.gesture.ensemble import load_checkpoint
from proxima.types import GESTURES

SHIPPED = Path(__file__).resolve().parents[2] / "models" / "gesture-default.pt"


@pytest.mark.slow
def test_per_command_thresholds_never_rank_below_the_shared_one(laser_clips) -> None:
    clf = load_checkpoint(SHIPPED)
    streams = decision_streams(laser_clips, [0], 5, condition("field", 1))
    sets = [(streams, recognitions(streams, clf, EngineSettings()))]
    base = ControlSettings(decision="evidence", evidence_threshold=8.0)
    best, rows = tune_by_command(sets, base, passes=1, factors=(0.5, 2.0))
    start = pool([evaluate_config(s, r, base) for s, r in sets])
    assert rank(best) >= rank({**start})
    assert rows[0] == best and len(rows) == 1 + len(GESTURES) * 2
    table = best["evidence_threshold_by_command"]
    assert set(table) <= set(GESTURES) and all(v > 0 for v in table.values())
    chosen = base.model_copy(update={"evidence_threshold_by_command": table})
    again = pool([evaluate_config(s, r, chosen) for s, r in sets])
    assert again["wrong"] == best["wrong"] and again["hit_rate"] == best["hit_rate"]


def test_whole_stream_capture_keeps_the_script_at_the_drawn_frame_rate(laser_clips) -> None:
    """`whole_stream`: the same script of gestures, stitched from the clips as recorded
    and captured in one draw as `proxima robustness` captures its live streams: below
    30 fps under `field`."""
    model = condition("field", 1)
    per_clip = decision_streams(laser_clips, [3, 4], 4, model)
    whole = decision_streams(laser_clips, [3, 4], 4, model, whole_stream=True)
    for a, b in zip(per_clip, whole, strict=True):
        assert a.view == b.view and a.fps == 30.0 and 15.0 <= b.fps <= 30.0
        assert [g.gesture for g in a.segments] == [g.gesture for g in b.segments]
        last = b.segments[-1].end_t
        assert abs((b.frames[-1] - 1) / b.fps - last) < 1.0  # the script's times kept
    assert any(b.fps < 30.0 for b in whole)
