"""The ensemble classifier on real LASER windows: the mean of its members' calibrated
probabilities, usable wherever the engine takes a classifier."""

from pathlib import Path

import numpy as np
import pytest

from proxima.gesture.classifier import GestureClassifier
from proxima.gesture.ensemble import EnsembleClassifier
from proxima.types import GESTURES

ROOT = Path(__file__).resolve().parents[2]
MEMBERS = (  # two real models of one window length (tests/data/README.md)
    ROOT / "tests" / "data" / "gesture-capture-60.pt",
    ROOT / "tests" / "data" / "gesture-no-capture.pt",
)


def test_the_ensemble_is_the_mean_of_its_members(laser_clips) -> None:
    clip = next(c for c in laser_clips if c.gesture == "hover" and len(c) >= 80)
    xyz = np.stack([clip.xyz[i : i + 60] for i in (0, 10, 20)])
    members = [GestureClassifier.load(p) for p in MEMBERS]
    ens = EnsembleClassifier(members)
    probs = ens.predict(xyz, aspect=clip.aspect)
    assert probs.shape == (3, len(GESTURES))
    np.testing.assert_allclose(probs.sum(1), 1.0, atol=1e-5)
    mean = np.mean([m.predict(xyz, aspect=clip.aspect) for m in members], axis=0)
    np.testing.assert_allclose(probs, mean, atol=1e-6)
    assert ens.window == 60 and ens.labels == tuple(GESTURES)
    assert EnsembleClassifier.load(MEMBERS).predict(xyz, clip.aspect).shape == (3, 13)


def test_members_must_agree_on_the_window() -> None:
    a, b = (GestureClassifier.load(p) for p in MEMBERS)
    b.window = 30
    with pytest.raises(ValueError, match="window 30 / 60"):
        EnsembleClassifier([a, b])
    with pytest.raises(ValueError, match="at least one"):
        EnsembleClassifier([])


def test_the_engine_runs_an_ensemble_named_by_comma_joined_checkpoints(
    laser_clips, tmp_path
) -> None:
    """`--checkpoint A,B` through the real engine on a replayed held-out stream: each
    gesture event carries the ensemble's mean probability, not a member's."""
    import json

    from typer.testing import CliRunner

    from proxima.cli import app
    from proxima.engine import load_classifier
    from proxima.evaluation.latency import build_streams

    ens = load_classifier(",".join(map(str, MEMBERS)))
    assert isinstance(ens, EnsembleClassifier) and len(ens.members) == 2
    (stream,) = build_streams(laser_clips, [1003], 3, "test", 3.0, 4.0)
    source = tmp_path / "s.csv"
    stream.write(source)
    runs = {}
    for name, ckpt in (("ens", ",".join(map(str, MEMBERS))), ("one", str(MEMBERS[0]))):
        events = tmp_path / f"{name}.jsonl"
        args = ["recognize", "--checkpoint", ckpt, "--source", f"replay:{source}@30"]
        result = CliRunner().invoke(app, [*args, "--events", str(events)])
        assert result.exit_code == 0, result.output
        rows = [json.loads(line) for line in events.read_text().splitlines()]
        runs[name] = [e for e in rows if e["type"] == "gesture"]
    assert runs["ens"] and len(runs["ens"]) == len(runs["one"])
    assert any(
        a["confidence"] != b["confidence"] for a, b in zip(runs["ens"], runs["one"], strict=True)
    )
