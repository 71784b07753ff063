"""SCAFFOLD: the drift correction's gradient, the control variates' screening, and one
drone's two rounds through the real ClientApp and the Scaffold strategy on LASER data."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from fl_helpers import fast_config
from flwr.app import Array, ArrayRecord, ConfigRecord, Context, MetricRecord, RecordDict
from flwr.supercore.task_identity import TaskIdentity

from proxima.federated import client_app
from proxima.federated.config import ConfigError, FLConfig
from proxima.federated.data import drone_data
from proxima.federated.recorder import RunRecorder
from proxima.federated.strategy import Scaffold, check_update, guarded
from proxima.federated.task import (
    LocalResult,
    control_step,
    get_weights,
    new_model,
    next_control,
    train_local,
)
from proxima.gesture.train import TrainConfig, evaluate_loss, validation_features


def test_the_correction_moves_every_step_by_lr_times_c_minus_ci() -> None:
    model, _ = new_model(fast_config(strategy="scaffold"))
    before = get_weights(model)
    rng = np.random.default_rng(0)
    corr = {n: rng.normal(size=v.shape).astype(np.float32) for n, v in before.items()}
    step = control_step(corr, lr=0.01)
    assert step is not None and control_step(None, 0.01) is None
    step(model)
    after = get_weights(model)
    for n in before:
        assert np.allclose(before[n] - after[n], 0.01 * corr[n], atol=1e-6)
    with pytest.raises(ValueError, match="lack parameter"):
        control_step({"stem.0.weight": corr["stem.0.weight"]}, 0.01)(model)  # type: ignore[misc]


def test_a_drones_control_variate_is_its_mean_step_less_the_correction() -> None:
    """Option II on a real local round: with no variates yet c_i = (x - y_i) / (K lr);
    with them, the correction the drone applied is taken back out."""
    cfg = fast_config(strategy="scaffold")
    data = drone_data(cfg, 0, "front")
    model, pipeline = new_model(cfg)
    start = get_weights(model)
    res = train_local(model, pipeline, data.fit, data.val, cfg, 1, 0)
    end = get_weights(model)
    assert res.steps == -(-len(data.fit) // cfg.batch_size) * res.epochs  # 1 epoch, kept
    c1 = next_control(start, end, res.steps, res.lr, None)
    for n in start:
        assert np.allclose(c1[n], (start[n] - end[n]) / (res.steps * res.lr), atol=1e-6)
    correction = {n: 1 - v for n, v in c1.items()}  # a fleet's c of 1 less c_i
    c2 = next_control(start, end, res.steps, res.lr, correction)
    assert all(np.allclose(c2[n], 2 * c1[n] - 1, atol=1e-5) for n in c1)


def _metrics(n: float = 100) -> MetricRecord:
    return MetricRecord({"num-examples": n, "train_loss": 1.0, "val_loss": 1.0,
                         "val_accuracy": 0.5, "seconds": 1.0})  # fmt: skip


def test_screening_checks_the_control_record() -> None:
    model, _ = new_model(fast_config())
    weights = {k: v.numpy().copy() for k, v in model.state_dict().items()}
    reference = {k: tuple(v.shape) for k, v in weights.items()}

    def reply(control: dict[str, np.ndarray] | None) -> RecordDict:
        rd = RecordDict({"arrays": ArrayRecord({k: Array(v) for k, v in weights.items()}),
                         "metrics": _metrics()})  # fmt: skip
        if control is not None:
            rd["control"] = ArrayRecord({k: Array(v) for k, v in control.items()})
        return rd

    first = next(iter(weights))
    assert check_update(reply({first: weights[first]}), reference, control=True) is None
    assert "without its 'control'" in check_update(reply(None), reference, control=True)
    nan = np.full_like(weights[first], np.nan)
    assert "non-finite" in check_update(reply({first: nan}), reference, control=True)
    assert "does not match" in check_update(reply({"extra": nan}), reference, control=True)
    # FedAvg's screening is unchanged: one ArrayRecord only
    assert "one ArrayRecord" in check_update(reply({first: weights[first]}), reference)


class _Grid:
    """The two calls FedAvg's sampling makes of Flower's Grid."""

    def __init__(self, nodes: list[int]) -> None:
        self.nodes = nodes

    def get_node_ids(self) -> list[int]:
        return list(self.nodes)


@pytest.fixture
def task_identity():
    """Flower builds messages inside a running app; stand in for its process identity."""
    saved = (TaskIdentity._run_id, TaskIdentity._node_id, TaskIdentity._task_id)
    TaskIdentity.run_id, TaskIdentity.node_id, TaskIdentity.task_id = 1, 1, 1
    yield
    TaskIdentity._run_id, TaskIdentity._node_id, TaskIdentity._task_id = saved


def test_two_rounds_of_one_drone_through_the_client_app_and_strategy(task_identity) -> None:
    cfg = fast_config(strategy="scaffold")
    model, _ = new_model(cfg)
    arrays = ArrayRecord(model.state_dict())
    config = ConfigRecord(cfg.to_run_config())
    strategy = Scaffold(min_train_nodes=1, min_available_nodes=1)
    context = Context(run_id=1, node_id=7, node_config={"partition-id": 0, "num-partitions": 3},
                      state=RecordDict(), run_config={})  # fmt: skip

    (first,) = strategy.configure_train(1, arrays, config, _Grid([7]))  # type: ignore[arg-type]
    assert "control" not in first.content.array_records  # no fleet control before round 1
    reply = client_app.train(first, context)
    own = {k: a.numpy() for k, a in context.state.array_records["scaffold-control"].items()}
    sent = {k: a.numpy() for k, a in reply.content.array_records["control"].items()}
    assert own.keys() == sent.keys() and all(np.array_equal(own[k], sent[k]) for k in own)
    assert any(np.abs(v).sum() > 0 for v in own.values())

    new_arrays, _ = strategy.aggregate_train(1, [reply])
    assert new_arrays is not None and "control" not in reply.content.array_records
    fleet = strategy.fleet_control()
    assert fleet is not None and all(np.allclose(fleet[k], own[k]) for k in own)

    (second,) = strategy.configure_train(2, new_arrays, config, _Grid([7]))  # type: ignore[arg-type]
    assert set(second.content.array_records) == {"arrays", "control"}
    correction = client_app._correction(second, context)
    assert correction is not None
    assert all(np.allclose(correction[k], 0, atol=1e-6) for k in own)  # one drone: c == c_i
    reply2 = client_app.train(second, context)
    shapes = {k: tuple(v.shape) for k, v in model.state_dict().items()}
    assert check_update(reply2.content, shapes, control=True) is None


def test_the_server_step_scales_the_averaged_move(task_identity) -> None:
    """eta_g = 2: the fleet's new weights are old + 2 (average - old), on a real reply."""
    cfg = fast_config(strategy="scaffold")
    model, _ = new_model(cfg)
    arrays = ArrayRecord(model.state_dict())
    old = {k: a.numpy().copy() for k, a in arrays.items()}
    strategy = Scaffold(server_learning_rate=2.0, min_train_nodes=1, min_available_nodes=1)
    context = Context(run_id=1, node_id=7, node_config={"partition-id": 0, "num-partitions": 3},
                      state=RecordDict(), run_config={})  # fmt: skip
    (msg,) = strategy.configure_train(1, arrays, ConfigRecord(cfg.to_run_config()), _Grid([7]))  # type: ignore[arg-type]
    reply = client_app.train(msg, context)
    local = {k: a.numpy().copy() for k, a in reply.content.array_records["arrays"].items()}
    new_arrays, _ = strategy.aggregate_train(1, [reply])
    assert new_arrays is not None
    new = {k: a.numpy() for k, a in new_arrays.items()}
    assert any(not np.allclose(local[k], old[k]) for k in old)
    for k in old:
        assert np.allclose(new[k], old[k] + 2 * (local[k] - old[k]), atol=1e-5)


def test_local_weights_last_sends_the_last_epochs_weights_not_the_best_ones() -> None:
    """`local-weights = last` (the default): a drone trains all its local epochs and sends
    the weights after the last one (with that epoch's validation figures and step count);
    `best` sends the epoch its own validation tail liked best."""
    assert FLConfig.from_run_config({"local-weights": "best"}).local_weights == "best"
    assert FLConfig().local_weights == "last"
    assert FLConfig.from_run_config({"local-weights": "mean"}).local_weights == "mean"
    with pytest.raises(ConfigError, match="'local-weights'"):
        FLConfig.from_run_config({"local-weights": "first"})
    data = drone_data(fast_config(), 0, "front")
    for keep in ("best", "last"):
        cfg = fast_config(strategy="scaffold", local_epochs=3, patience=1, local_weights=keep)
        model, pipeline = new_model(cfg)
        res = train_local(model, pipeline, data.fit, data.val, cfg, 1, 0)
        tc = TrainConfig(seed=cfg.seed + 1000, augment=cfg.augment)  # fit's validation draw
        loss, _ = evaluate_loss(model, validation_features(pipeline, data.val, tc), data.val.labels)
        assert loss == pytest.approx(res.val_loss, rel=1e-5)  # the sent weights' own loss
        if keep == "last":
            assert res.epochs == 3  # patience 1 could stop `best` early; `last` runs all
            assert res.steps == -(-len(data.fit) // cfg.batch_size) * 3


def test_local_weights_mean_sends_the_mean_of_the_rounds_second_half() -> None:
    """`local-weights = mean`: with 4 local epochs the drone sends the mean of its weights
    after epochs 3 and 4 (the same seeded run, which averaging does not change), with
    those weights' own validation loss and the step count of epoch 3.5."""
    data = drone_data(fast_config(), 0, "front")

    def run(epochs: int, keep: str) -> tuple[dict[str, np.ndarray], LocalResult]:
        cfg = fast_config(strategy="scaffold", local_epochs=epochs, local_weights=keep)
        model, pipeline = new_model(cfg)
        res = train_local(model, pipeline, data.fit, data.val, cfg, 1, 0)
        return {k: v.detach().numpy().copy() for k, v in model.state_dict().items()}, res

    after3, _ = run(3, "last")
    after4, _ = run(4, "last")
    mean, res = run(4, "mean")
    assert any(not np.allclose(after3[k], after4[k]) for k in after4)
    for k in mean:
        assert np.allclose(mean[k], (after3[k] + after4[k]) / 2, atol=1e-6)
    cfg = fast_config(strategy="scaffold", local_epochs=4, local_weights="mean")
    model, pipeline = new_model(cfg)
    model.load_state_dict({k: torch.from_numpy(v) for k, v in mean.items()})
    tc = TrainConfig(seed=cfg.seed + 1000, augment=cfg.augment)  # fit's validation draw
    loss, _ = evaluate_loss(model, validation_features(pipeline, data.val, tc), data.val.labels)
    assert loss == pytest.approx(res.val_loss, rel=1e-5)
    assert res.epochs == 4
    assert res.steps == round(3.5 * -(-len(data.fit) // cfg.batch_size))


def test_the_average_does_not_depend_on_the_order_the_drones_answer(task_identity) -> None:
    """Replies arrive in any order; the guarded strategy sorts them by drone before
    averaging, so one seed gives one global model (floating-point sums are not
    associative)."""
    cfg = fast_config()
    model, _ = new_model(cfg)
    arrays = ArrayRecord(model.state_dict())
    config = ConfigRecord(cfg.to_run_config())
    grid = _Grid([1, 2, 3])
    sent = list(guarded(cfg, RunRecorder("t", 1)).configure_train(1, arrays, config, grid))  # type: ignore[arg-type]
    replies = []
    for pid, msg in enumerate(sent):
        context = Context(run_id=1, node_id=pid + 1, state=RecordDict(), run_config={},
                          node_config={"partition-id": pid, "num-partitions": 3})  # fmt: skip
        replies.append(client_app.train(msg, context))

    def average(order: list[int]) -> dict[str, np.ndarray]:
        strategy = guarded(cfg, RunRecorder("t", 1))
        strategy.configure_train(1, arrays, config, grid)  # type: ignore[arg-type]
        new, _ = strategy.aggregate_train(1, [replies[i] for i in order])
        assert new is not None
        return {k: a.numpy() for k, a in new.items()}

    forward, backward = average([0, 1, 2]), average([2, 0, 1])
    assert all(np.array_equal(forward[k], backward[k]) for k in forward)
