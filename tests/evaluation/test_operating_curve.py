"""bench.operating_curve: an ensemble scored from its members' cached recognitions is the
ensemble the engine runs (`gesture.ensemble`), on a real held-out stream."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import pytest

from bench.operating_curve import CONDITIONS, curve, ensemble_sets
from proxima.engine import EngineSettings
from proxima.evaluation.robust_training import recognitions
from proxima.gesture.classifier import default_checkpoint
from proxima.gesture.ensemble import EnsembleClassifier

ROOT = Path(__file__).resolve().parents[2]
MEMBERS = [  # two real 60-frame models (tests/data/README.md)
    str(ROOT / "tests" / "data" / "gesture-capture-60.pt"),
    str(ROOT / "tests" / "data" / "gesture-no-capture.pt"),
]


@pytest.fixture(scope="module")
def args(tmp_path_factory: pytest.TempPathFactory) -> argparse.Namespace:
    return argparse.Namespace(
        tune_streams=0, streams=1, segments=3, whole_stream_capture=True,
        cache_dir=tmp_path_factory.mktemp("recs"),
    )  # fmt: skip


def test_the_ensemble_from_cached_recognitions_is_the_engines(args) -> None:
    merged = ensemble_sets(MEMBERS, args)
    assert sorted(args.cache_dir.iterdir())  # each member's recognitions were cached
    ensemble = EnsembleClassifier.load(MEMBERS)
    for cond in CONDITIONS:
        streams, recs = merged[cond]
        (direct,) = recognitions(streams, ensemble, EngineSettings())
        np.testing.assert_array_equal(recs[0].classified, direct.classified)
        np.testing.assert_allclose(recs[0].probs, direct.probs, atol=1e-5)
    rows = curve([(None, merged)], [20.0])
    assert rows[0]["threshold"] == 20.0
    for cond in CONDITIONS:
        assert 0.0 <= rows[0][cond]["by_script"] <= 1.0
        assert rows[0][cond]["wrong_acting_per_hour"] >= 0.0


def test_members_of_another_window_are_refused(args) -> None:
    with pytest.raises(ValueError, match="classify different frames"):
        ensemble_sets([MEMBERS[0], str(default_checkpoint())], args)


def test_per_view_figures_add_up_to_the_whole(args) -> None:
    """bench.rule_variants --per-view: the views' commands by the script are the whole
    run's, and the commands lost behind a missed arming are the gap between the script's
    count and the run's own."""
    from bench.rule_variants import per_view
    from proxima.control import ControlSettings
    from proxima.evaluation.latency import evaluate_config_by_script

    merged = ensemble_sets(MEMBERS, args)
    control = ControlSettings()
    for cond in CONDITIONS:
        streams, recs = merged[cond]
        own, script = evaluate_config_by_script(streams, recs, control)
        views = per_view(streams, recs, control)
        assert set(views) == {s.view for s in streams}
        assert sum(v["expected_by_script"] for v in views.values()) == script["expected_commands"]
        given = sum(v["hit_rate_by_script"] * v["expected_by_script"] for v in views.values())
        assert round(given) == script["hits"] + script["late_hits"]
        lost = sum(v["lost_disarmed"] for v in views.values())
        assert lost == script["expected_commands"] - own["expected_commands"] >= 0
