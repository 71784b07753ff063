"""`proxima robustness` on the real LASER clips with the shipped model, kept small (one
effect, a window limit, two short live streams): the JSON has the named fields, the PNG
is drawn, heavy jitter scores below clean, and the same seed gives the same numbers."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from proxima.cli import app
from proxima.evaluation.latency import build_streams
from proxima.evaluation.robustness import (
    RobustnessConfig,
    RobustnessError,
    capture_rng,
    captured_stream,
    captured_windows,
    command_figures,
)
from proxima.evaluation.scoring import score_commands
from proxima.gesture.capture import condition

SHIPPED = Path(__file__).resolve().parents[2] / "models" / "gesture-default.pt"
LIVE_KEYS = {"command_precision", "command_recall", "command_recall_script", "wrong_per_hour",
             "wrong_acting_per_hour", "p95_onset_to_command_s"}  # fmt: skip


@pytest.fixture(scope="module")
def small_run(tmp_path_factory, laser_dir: Path) -> tuple[dict, Path]:
    out = tmp_path_factory.mktemp("robust") / "r.json"
    result = CliRunner().invoke(
        app,
        ["robustness", "--checkpoint", str(SHIPPED), "--data", str(laser_dir),
         "--split", "temporal", "--json", str(out), "--condition", "jitter",
         "--repeats", "1", "--limit", "400", "--live-streams", "2", "--live-segments", "4"],
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    return json.loads(out.read_text()), out


def test_the_command_writes_the_named_fields_and_a_png(small_run) -> None:
    result, out = small_run
    assert out.with_suffix(".png").stat().st_size > 10_000
    assert result["command"].startswith("proxima robustness --checkpoint")
    clean = result["clean"]
    assert 0 < clean["windows"] <= 400 and {"accuracy", "macro_f1", "per_view"} <= set(clean)
    levels = result["conditions"]["jitter"]
    assert [r["level"] for r in levels] == [1, 2, 3]
    assert all(0 < r["windows"] <= 400 and r["macro_f1"] is not None for r in levels)
    assert levels[2]["capture"]["jitter"] == pytest.approx(6.4, abs=0.05)
    live = result["live"]
    for name in ("clean", "field"):
        assert set(live[name]) >= LIVE_KEYS, live[name]
        assert live[name]["expected_commands"] > 0
        assert live[name]["expected_by_script"] > 0
        assert live[name]["re_arms"] + live[name]["wrong_arming"] <= live[name]["wrong"]
        assert all(set(v) >= LIVE_KEYS for v in live[name]["per_view"].values())
    assert live["streams"]["count"] == 2 and live["field_condition"]["level"] == 1
    assert live["field"]["fps"][1] <= 30.0
    # the engine's default clock follows the model's training windows
    assert result["window_clock"] == result["training_clock"] == "poses"


def test_heavy_jitter_scores_below_clean(small_run) -> None:
    result, _ = small_run
    clean = result["clean"]["accuracy"]
    assert clean > 0.8  # the shipped model on the held-out parts, as recorded
    assert result["conditions"]["jitter"][2]["accuracy"] < clean - 0.1


def test_the_draws_are_repeatable_and_independent_of_the_rest(laser_clips) -> None:
    from proxima.gesture.windows import split_clips

    test = split_clips(laser_clips, "temporal").test[:4]
    config = RobustnessConfig(repeats=1)
    model = condition("field", 1)
    a = captured_windows(test, model, "field", 1, config, 60)
    b = captured_windows(test, model, "field", 1, config, 60)
    np.testing.assert_array_equal(a["xyz"], b["xyz"])
    # The first clip's draw does not depend on which clips come after it.
    c = captured_windows(test[:1], model, "field", 1, config, 60)
    n = len(c["labels"])
    np.testing.assert_array_equal(a["xyz"][:n], c["xyz"])
    other = captured_windows(test, model, "field", 1, RobustnessConfig(repeats=1, seed=1), 60)
    assert not np.array_equal(a["xyz"][:n], other["xyz"][:n])


def test_a_captured_stream_keeps_its_script(laser_clips) -> None:
    (stream,) = build_streams(laser_clips, [1000], 4, "test", 3.0, 4.0)
    cap = captured_stream(stream, condition("fps", 3), capture_rng(0, "x", 3, 0, 0))
    assert cap.fps == 10.0 and cap.segments == stream.segments
    assert len(cap.frames) == pytest.approx(len(stream.frames) / 3, rel=0.05)
    assert cap.duration_s == pytest.approx(stream.duration_s, abs=0.1)


def test_bad_requests_name_the_problem(tmp_path: Path) -> None:
    with pytest.raises(RobustnessError, match="unknown condition"):
        RobustnessConfig(conditions=("fog",))
    with pytest.raises(RobustnessError, match="live level"):
        RobustnessConfig(live_level=4)
    result = CliRunner().invoke(
        app, ["robustness", "--checkpoint", str(SHIPPED), "--window-clock", "sundial",
              "--json", str(tmp_path / "r.json")],
    )  # fmt: skip
    assert result.exit_code != 0 and "window_clock" in result.output
    assert not (tmp_path / "r.json").exists()


def test_recall_against_the_script_counts_what_a_missed_arming_blocked() -> None:
    script = [{"gesture": g, "onset_t": 4.0 * k} for k, g in
              enumerate(["have_command", "move_ahead", "land", "wave_off", "hover"])]  # fmt: skip
    # Control never armed: the run's own arming expects have_command alone (one miss);
    # the operator asked for four commands (hover came after wave_off disarmed).
    figures = command_figures(score_commands(script, [], 20.0, arming=[]),
                              score_commands(script, [], 20.0))  # fmt: skip
    assert (figures["command_recall"], figures["expected_commands"]) == (0.0, 1)
    assert (figures["command_recall_script"], figures["expected_by_script"]) == (0.0, 4)
    assert figures["blocked_while_disarmed"] == 4
    # Armed at 1 s and everything came: both recalls are 1.
    cmds = [{"t": 1.0 + 4 * k, "command": g, "stream": "a"} for k, g in
            enumerate(["have_command", "move_ahead", "land", "wave_off"])]  # fmt: skip
    armed = score_commands(script, cmds, 20.0, arming=[(1.0, True), (13.0, False)])
    figures = command_figures(armed, score_commands(script, cmds, 20.0))
    assert figures["command_recall"] == figures["command_recall_script"] == 1.0


def test_an_ensemble_is_scored_on_its_members_mean_probabilities(laser_clips, tmp_path) -> None:
    """`--checkpoint A,B`: the window figures of the members' mean probabilities (a model
    with itself scores as the model alone), through the CLI too."""
    from proxima.evaluation.robustness import score_condition
    from proxima.gesture.classifier import GestureClassifier
    from proxima.gesture.ensemble import EnsembleClassifier
    from proxima.gesture.windows import split_clips

    data = Path(__file__).resolve().parents[2] / "tests" / "data"
    names = ("gesture-capture-60.pt", "gesture-no-capture.pt")
    a, b = (GestureClassifier.load(data / n) for n in names)
    test = split_clips(laser_clips, "temporal", 60).test
    config = RobustnessConfig(repeats=1, limit=240)
    w = captured_windows(test, condition("field", 3), "field", 3, config, 60, "poses")
    alone = score_condition(a, test, w)
    assert score_condition(EnsembleClassifier([a, a]), test, w) == alone
    pair = score_condition(EnsembleClassifier([a, b]), test, w)
    mean = EnsembleClassifier([a, b]).predict(w["xyz"], w["aspect"])  # both T = 1
    assert pair["accuracy"] == round(float(np.mean(mean.argmax(1) == w["labels"])), 4)
    assert pair["accuracy"] != alone["accuracy"]
    out = tmp_path / "ens.json"
    result = CliRunner().invoke(
        app, ["robustness", "--checkpoint", ",".join(str(data / n) for n in names),
              "--split", "temporal", "--json", str(out), "--condition", "roll", "--repeats", "1",
              "--limit", "60", "--no-live"],
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    assert json.loads(out.read_text())["model"] == "tcn+tcn"
