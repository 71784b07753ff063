"""Scoring commands against a stitched stream's ground truth (the latency benchmark's
judge): every kind of outcome, and the per-gesture latency figures."""

from __future__ import annotations

import numpy as np
import pytest

from proxima.control import ControlSettings
from proxima.control.arbiter import Sight
from proxima.control.controller import CommandController, StreamUpdate
from proxima.evaluation.replay import Run
from proxima.evaluation.scoring import Score, latency_figures, score_commands

SEGMENTS = [
    {"gesture": "have_command", "onset_t": 0.0},
    {"gesture": "move_ahead", "onset_t": 4.0},
    {"gesture": "land", "onset_t": 8.0},
    {"gesture": "hover", "onset_t": 12.0},
    {"gesture": "slow_down", "onset_t": 16.0},
]


def cmd(t: float, name: str, stream: str = "main") -> dict:
    return {"t": t, "command": name, "stream": stream}


def test_every_outcome_is_counted_and_latencies_are_kept_per_gesture() -> None:
    commands = [
        cmd(2.0, "have_command"),  # hit, 2.0 s
        cmd(5.5, "move_ahead"),  # hit, 1.5 s
        cmd(6.0, "move_ahead"),  # repeat in the same segment
        cmd(12.5, "land"),  # late hit: land's segment ended at 12.0; 4.5 s after its onset
        cmd(17.0, "hover"),  # hover's segment had none, but slow_down's has begun: late
        cmd(18.0, "move_upward"),  # wrong: nobody performed it
        cmd(19.0, "hover", stream=""),  # the safety hover: counted apart
    ]
    score = score_commands(SEGMENTS, commands, duration_s=20.0)
    assert (score.hits, score.late, score.repeats, score.wrong, score.safety) == (2, 2, 1, 1, 1)
    assert score.missed_by_gesture == {"slow_down": 1}
    assert score.wrong_by_pair == {"slow_down->move_upward": 1}
    assert score.latencies == pytest.approx([2.0, 1.5, 4.5, 5.0])
    summary = score.summary()
    by_gesture = summary["latency_by_gesture"]
    assert list(by_gesture) == ["have_command", "hover", "land", "move_ahead"]
    assert by_gesture["land"] == {
        "commands": 1,
        "median_s": 4.5,
        "p95_s": 4.5,
        "within_2_5_s": 0.0,
    }
    assert by_gesture["move_ahead"]["median_s"] == 1.5
    assert summary["expected_commands"] == 5
    assert summary["on_time_rate"] == pytest.approx(2 / 5)


def test_gestures_performed_while_disarmed_are_blocked_not_missed() -> None:
    # The run never armed: only have_command was expected, and it was missed.
    score = score_commands(SEGMENTS, [], duration_s=20.0, arming=[])
    assert (score.expected, score.missed, score.blocked) == (1, 1, 4)
    assert score.summary()["latency_by_gesture"] == {}


def test_merged_scores_pool_their_latencies_per_gesture() -> None:
    a = score_commands(SEGMENTS, [cmd(1.0, "have_command")], 20.0)
    b = score_commands(SEGMENTS, [cmd(3.0, "have_command"), cmd(5.0, "move_ahead")], 20.0)
    a.merge(b)
    assert a.latency_by_gesture == {"have_command": [1.0, 3.0], "move_ahead": [1.0]}
    assert a.summary()["latency_by_gesture"]["have_command"]["median_s"] == 2.0


def test_latency_figures_of_no_commands_are_empty() -> None:
    assert latency_figures([]) == {
        "commands": 0,
        "median_s": None,
        "p95_s": None,
        "within_2_5_s": None,
    }


def test_wrong_commands_split_by_what_they_do_to_the_drone() -> None:
    # The real controller decides; the run records the arming each command was sent in.
    controller = CommandController(["main"], "drone", ControlSettings())
    run = Run()
    actions = [
        (0, 3, "have_command"),  # arms (right)
        (5, 8, "move_ahead"),  # right
        (11, 13, "have_command"),  # during hover, control armed: a re-arm, nothing moves
        (14, 16, "move_upward"),  # during hover: a wrong motion
        (17, 20, "wave_off"),  # right; disarms
        (23, 25, "have_command"),  # during move_ahead, disarmed: arms wrongly
        (27, 30, "move_ahead"),  # right (control is armed now)
    ]
    for start, stop, action in actions:
        for t in np.arange(start, stop, 0.1):
            for event in controller.process(StreamUpdate("main", float(t), Sight.FULL, action)):
                run.add(event)
    assert [(c["command"], c["armed"]) for c in run.commands] == [
        ("have_command", False),
        ("move_ahead", True),
        ("have_command", True),
        ("move_upward", True),
        ("wave_off", True),
        ("have_command", False),
        ("move_ahead", True),
    ]
    script = [("have_command", 0), ("move_ahead", 4), ("hover", 10), ("wave_off", 16.5)]
    segments = [{"gesture": g, "onset_t": t} for g, t in [*script, ("move_ahead", 22)]]
    score = score_commands(segments, run.commands, 36.0, run.arming)
    assert (score.wrong, score.re_arms, score.wrong_arming, score.wrong_acting) == (3, 1, 1, 1)
    summary = score.summary()
    assert summary["wrong_per_hour"] == pytest.approx(300.0)
    assert summary["wrong_acting_per_hour"] == pytest.approx(100.0)
    merged = Score().merge(score).merge(score)
    assert (merged.re_arms, merged.wrong_arming, merged.wrong_acting) == (2, 2, 2)
    # Commands that do not say their arming are all counted as acting.
    bare = [{k: v for k, v in c.items() if k != "armed"} for c in run.commands]
    assert score_commands(segments, bare, 36.0, run.arming).wrong_acting == 3
