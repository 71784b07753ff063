"""Run config, partitions, console samples and update screening: real data, no engine."""

from __future__ import annotations

import tomllib

import numpy as np
import pytest
import torch
from fl_helpers import fast_config
from flwr.app import Array, ArrayRecord, MetricRecord, RecordDict

from proxima.federated.config import APP_DIR, ConfigError, FLConfig
from proxima.federated.data import drone_data, partition_windows, sample_clips
from proxima.federated.strategy import check_update
from proxima.federated.task import new_model, train_local


def test_flower_app_defaults_match_the_config() -> None:
    toml = tomllib.loads((APP_DIR / "pyproject.toml").read_text())
    assert toml["tool"]["flwr"]["app"]["config"] == FLConfig().to_run_config()
    comps = toml["tool"]["flwr"]["app"]["components"]
    assert comps == {"serverapp": "proxima.federated.server_app:app",
                     "clientapp": "proxima.federated.client_app:app"}  # fmt: skip


def test_bad_run_config_names_the_key() -> None:
    with pytest.raises(ConfigError, match="'local-epochs'"):
        FLConfig.from_run_config({"local-epochs": "many"})
    with pytest.raises(ConfigError, match="'strategy'"):
        FLConfig.from_run_config({"strategy": "fedsgd"})
    with pytest.raises(ConfigError, match="'rounds-x'"):
        FLConfig.from_run_config({"rounds-x": 3})
    with pytest.raises(ConfigError, match=r"'pipeline'.*scale-free"):
        FLConfig(pipeline="paper")  # MinMax statistics would be per drone
    assert FLConfig(pipeline="body-image").pipeline == "body-image"  # scale-free too
    cfg = FLConfig.from_run_config({"rounds": 7, "include-samples": "false", "strategy": "fedprox"})
    assert (cfg.rounds, cfg.include_samples, cfg.strategy) == (7, False, "fedprox")


@pytest.mark.slow
def test_the_mirror_key_turns_mirroring_on_in_the_drones_local_training(laser_clips) -> None:
    assert FLConfig.from_run_config({"mirror": "true"}).mirror
    assert not FLConfig().mirror  # measured without benefit (docs/federated.md)
    fit_w, val_w = partition_windows(fast_config(stride=24), 1, laser_clips)

    def weights(mirror: bool) -> list[torch.Tensor]:
        cfg = fast_config(stride=24, mirror=mirror)
        model, pipeline = new_model(cfg)
        train_local(model, pipeline, fit_w, val_w, cfg, server_round=1, partition_id=1)
        return [p.detach().clone() for p in model.parameters()]

    plain, again, mirrored = weights(False), weights(False), weights(True)
    assert all(torch.equal(a, b) for a, b in zip(plain, again, strict=True))  # seeded
    assert not all(torch.equal(a, b) for a, b in zip(plain, mirrored, strict=True))


def test_view_partition_gives_each_drone_one_camera_view(laser_clips) -> None:
    cfg = fast_config()
    names = []
    for pid, view in enumerate("flr"):
        fit, val = partition_windows(cfg, pid, laser_clips)
        assert len(fit) > 100 and len(val) > 0
        assert {n.rsplit("_", 1)[1] for n in fit.clip_names} == {view}
        assert set(np.unique(fit.labels)) == set(range(13))  # every gesture, one view
        names.append(set(fit.clip_names))
    assert not (names[0] & names[1]) and not (names[1] & names[2])


@pytest.mark.parametrize("partition", ["iid", "dirichlet"])
def test_window_partitions_are_disjoint_and_complete(laser_clips, partition) -> None:
    cfg = fast_config(partition=partition, dirichlet_alpha=0.3)
    shares = [partition_windows(cfg, pid, laser_clips)[0] for pid in range(3)]
    whole = partition_windows(FLConfig(**{**cfg.__dict__, "num_drones": 1}), 0, laser_clips)[0]
    assert sum(len(s) for s in shares) == len(whole)
    keys = [{(int(c), float(x)) for c, x in zip(s.clip, s.xyz[:, 0, 0, 0], strict=True)}
            for s in shares]  # fmt: skip
    assert not (keys[0] & keys[1]) and not (keys[0] & keys[2]) and not (keys[1] & keys[2])
    counts = np.array([np.bincount(s.labels, minlength=13) for s in shares])
    if partition == "iid":
        assert (counts.max(0) - counts.min(0) <= 1).all()  # every class dealt evenly
    else:
        assert (counts.max(0) - counts.min(0) > 5).any()  # skewed by Dirichlet


def test_corrupt_sample_is_reported_and_skipped(sample_store) -> None:
    db, good, bad = sample_store
    clips, notes = sample_clips(db, "front")
    assert [c.name for c in clips] == [f"sample-{good}"]
    assert len(notes) == 1 and notes[0].startswith(f"sample {bad} skipped")
    assert sample_clips(db, "left") == ([], [])
    cfg = fast_config(include_samples=True)
    with_samples = drone_data(cfg, 0, "front", None, db)
    without = drone_data(fast_config(), 0, "front", None, db)
    assert with_samples.samples_used == 1
    assert len(with_samples.fit) > len(without.fit)
    assert any(f"sample {bad} skipped" in n for n in with_samples.notes)


def _reply(arrays: dict[str, np.ndarray], n: float = 100) -> RecordDict:
    metrics = {"num-examples": n, "train_loss": 1.0, "val_loss": 1.0, "val_accuracy": 0.5,
               "seconds": 1.0}  # fmt: skip
    return RecordDict({"arrays": ArrayRecord({k: Array(v) for k, v in arrays.items()}),
                       "metrics": MetricRecord(metrics)})  # fmt: skip


def test_updates_that_would_poison_the_average_are_rejected() -> None:
    model, _ = new_model(FLConfig())
    weights = {k: v.numpy().copy() for k, v in model.state_dict().items()}
    reference = {k: tuple(v.shape) for k, v in weights.items()}
    assert check_update(_reply(weights), reference) is None
    first = next(iter(weights))
    nan = {**weights, first: np.full_like(weights[first], np.nan)}
    assert "non-finite" in check_update(_reply(nan), reference)
    wrong = {**weights, first: np.zeros((3, 3), np.float32)}
    assert "shape" in check_update(_reply(wrong), reference)
    missing = {k: v for k, v in weights.items() if k != first}
    assert "missing" in check_update(_reply(missing), reference)
    assert "num-examples" in check_update(_reply(weights, n=0), reference)


def test_init_starts_the_global_model_from_a_checkpoint(tmp_path, shipped_member) -> None:
    """`init`: round 0 is the checkpoint's model (scored on the real held-out windows),
    not the seeded fresh one; a checkpoint that does not fit stops the run, named (the
    shipped ensemble too: a run starts from one model)."""
    from proxima.federated.data import test_windows
    from proxima.federated.task import Scorer, get_weights, start_model
    from proxima.gesture.classifier import GestureClassifier, default_checkpoint

    shipped = shipped_member
    with pytest.raises(ConfigError, match=r"'init': .*an ensemble of \d+ models"):
        start_model(fast_config(init=str(default_checkpoint())))
    member = GestureClassifier.load(shipped)
    window, pipeline = member.window, member.pipeline.name
    assert pipeline == "body-smooth-z"  # the shipped members' features since 2026-12-07
    with pytest.raises(ConfigError, match=r"'init': .*'body-smooth-z' pipeline.*with 'body'"):
        start_model(fast_config(init=str(shipped), window=window, pipeline="body"))
    cfg = fast_config(init=str(shipped), window=window, pipeline=pipeline)
    model, _ = start_model(cfg)
    want = get_weights(GestureClassifier.load(shipped).model)
    got = get_weights(model)
    assert all(np.array_equal(got[k], want[k]) for k in want)
    scorer = Scorer(cfg, test_windows(cfg))
    _, fresh_acc = scorer(get_weights(new_model(cfg)[0]))
    _, init_acc = scorer(got)
    assert fresh_acc < 0.3 < 0.8 < init_acc  # the shipped model has seen these clips

    with pytest.raises(ConfigError, match=r"'init': .*missing.pt"):
        start_model(fast_config(init=str(tmp_path / "missing.pt")))
    with pytest.raises(ConfigError, match=r"'init': .* a tcn model .* this run trains paper-lstm"):
        start_model(fast_config(init=str(shipped), model="paper-lstm", window=window))
    # the start's window need not be the run's: a 60-frame run starts from it as well
    other, _ = start_model(fast_config(init=str(shipped), window=60, pipeline=pipeline))
    assert all(np.array_equal(get_weights(other)[k], want[k]) for k in want)


def test_the_window_key_sets_the_drones_window_length(laser_clips) -> None:
    with pytest.raises(ConfigError, match="'window'"):
        FLConfig.from_run_config({"window": 10})  # under 15 frames
    cfg = FLConfig.from_run_config({"window": 30, "stride": 24})
    fit_w, val_w = partition_windows(cfg, 0, laser_clips)
    assert fit_w.xyz.shape[1] == val_w.xyz.shape[1] == 30
    assert partition_windows(fast_config(stride=24), 0, laser_clips)[0].xyz.shape[1] == 60


def test_drones_train_without_windows_of_the_operator_standing_still(laser_clips) -> None:
    """As centralised training: slow_down's front clip opens with 1.5 s of rest, and no
    30-frame window of a drone's partition may lie wholly in it (gesture/idle.py)."""
    from proxima.gesture.idle import still_prefix

    def still_windows(trim: bool) -> int:
        cfg = FLConfig.from_run_config({"window": 30, "stride": 2, "trim-idle": trim})
        fit_w, _ = partition_windows(cfg, 0, laser_clips)  # drone 0: the front view
        k = fit_w.clip_names.index("DJI_0173_slow_down_f")
        return sum(still_prefix(w) == 30 for w in fit_w.xyz[fit_w.clip == k])

    assert FLConfig().trim_idle
    assert still_windows(False) >= 5 and still_windows(True) == 0
