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


def test_an_ensemble_file_holds_its_members_and_splits_back(laser_clips, tmp_path) -> None:
    """`proxima ensemble join` writes one file that `load_checkpoint` reads as the same
    ensemble (same probabilities); `split` writes the members back as one-model files;
    a one-model loader refuses the ensemble by name, and a mixed set is refused."""
    from typer.testing import CliRunner

    from proxima.cli import app
    from proxima.gesture.ensemble import load_checkpoint, save_ensemble

    clip = next(c for c in laser_clips if c.gesture == "wave_off" and len(c) >= 80)
    xyz = np.stack([clip.xyz[i : i + 60] for i in (0, 10, 20)])
    joined = EnsembleClassifier.load(MEMBERS).predict(xyz, clip.aspect)
    out = tmp_path / "ens.pt"
    runner = CliRunner()
    r = runner.invoke(app, ["ensemble", "join", *map(str, MEMBERS), "--out", str(out)])
    assert r.exit_code == 0, r.output
    ens = load_checkpoint(out)
    assert isinstance(ens, EnsembleClassifier) and len(ens.members) == 2
    assert ens.metadata["members"] == [str(m) for m in MEMBERS]
    assert ens.members[1].metadata == GestureClassifier.load(MEMBERS[1]).metadata
    np.testing.assert_allclose(ens.predict(xyz, clip.aspect), joined, atol=1e-6)
    with pytest.raises(ValueError, match=r"ens\.pt: an ensemble of 2 models"):
        GestureClassifier.load(out)

    r = runner.invoke(app, ["ensemble", "split", str(out), "--out-dir", str(tmp_path / "m")])
    assert r.exit_code == 0, r.output
    for i, src in enumerate(MEMBERS):
        back = load_checkpoint(tmp_path / "m" / f"ens-m{i}.pt")
        assert isinstance(back, GestureClassifier)
        want = GestureClassifier.load(src).predict(xyz, clip.aspect)
        np.testing.assert_allclose(back.predict(xyz, clip.aspect), want, atol=1e-6)
    r = runner.invoke(app, ["ensemble", "split", str(MEMBERS[0]), "--out-dir", str(tmp_path)])
    assert r.exit_code == 2 and "one model, not an ensemble" in r.output

    short = GestureClassifier.load(MEMBERS[0])
    short.window = 30
    with pytest.raises(ValueError, match="window 30 / 60"):
        save_ensemble(tmp_path / "bad.pt", [GestureClassifier.load(MEMBERS[1]), short], {})
    with pytest.raises(ValueError, match="at least two members"):
        save_ensemble(tmp_path / "bad.pt", [short], {})
    assert not (tmp_path / "bad.pt").exists()


def test_a_broken_ensemble_file_is_refused_by_name(tmp_path) -> None:
    """A member with a field missing, or no members, is a clear error naming the file
    and the member, never a crash."""
    import torch

    from proxima.gesture.classifier import ENSEMBLE_FORMAT
    from proxima.gesture.ensemble import load_checkpoint

    good = GestureClassifier.load(MEMBERS[0]).blob()
    broken = {k: v for k, v in good.items() if k != "state_dict"}
    path = tmp_path / "broken.pt"
    torch.save({"format": ENSEMBLE_FORMAT, "members": [good, broken], "metadata": {}}, path)
    with pytest.raises(ValueError, match=r"broken\.pt member 1: a malformed .*state_dict"):
        load_checkpoint(path)
    torch.save({"format": ENSEMBLE_FORMAT, "metadata": {}}, path)
    with pytest.raises(ValueError, match="without its members"):
        load_checkpoint(path)
    with pytest.raises(ValueError, match="an ensemble of 0 models"):
        GestureClassifier.load(path)
