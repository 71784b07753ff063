"""Flower strategies with the guard rails a fleet of drones needs.

`guarded(cfg, recorder)` returns Flower's own FedAvg (the paper's sample-weighted
average), FedProx, FedAdam or FedAvgM, or `Scaffold` (FedAvg plus SCAFFOLD's control
variates, which Flower does not ship), subclassed with a mixin that:
- waits for the drones a round needs, reporting "waiting for N drones" through the
  recorder, and gives up with `DronesMissing` after `wait_timeout_s` (Flower's own
  sampling would wait forever);
- records every drone's result per round (ok with its metrics, failed with the reason:
  an error reply, or no reply before the round's timeout);
- rejects updates that would poison the average: missing or extra arrays, a wrong
  shape, non-finite values, or a missing / non-positive sample count;
- leaves a drone that failed a round out of the next one, so a dead drone costs one
  round timeout rather than one per round (the SuperLink drops it from its node list
  once its heartbeats stop, about a minute later);
- averages the replies in one order (by drone name), not in the order they arrive, so a
  run's seed fixes its global model.
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterable
from typing import Any, Protocol

import numpy as np
from flwr.app import ArrayRecord, ConfigRecord, Message, MetricRecord
from flwr.serverapp import Grid
from flwr.serverapp.strategy import FedAdam, FedAvg, FedAvgM, FedProx

from proxima.federated.config import FLConfig
from proxima.federated.task import arrays_of, named_arrays

REQUIRED_METRICS = ("num-examples", "train_loss", "val_loss", "val_accuracy", "seconds")


class DronesMissing(RuntimeError):
    """Fewer drones connected than a round needs, for longer than the wait timeout."""


class Recorder(Protocol):
    def client_result(self, server_round: int, client: str, **fields: Any) -> None: ...

    def status(self, status: str, detail: str = "", **extra: Any) -> None: ...


class _FilteredGrid:
    """A Grid whose node list leaves some nodes out (everything else passes through)."""

    def __init__(self, grid: Grid, exclude: set[int]) -> None:
        self._grid = grid
        # A snapshot: Flower's sampler waits (without a timeout) until enough nodes are
        # listed, so the list it sees must not shrink between our check and its call.
        self._nodes = [n for n in grid.get_node_ids() if n not in exclude]

    def get_node_ids(self) -> list[int]:
        return list(self._nodes)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._grid, name)


def check_update(
    content: Any, reference: dict[str, tuple[int, ...]], control: bool = False
) -> str | None:
    """Why a training reply cannot be averaged, or None if it can. With `control`
    (SCAFFOLD) the reply also carries a "control" ArrayRecord: a subset of the model's
    arrays (its parameters), same shapes, finite."""
    records = dict(content.array_records)
    if control:
        if "control" not in records:
            return "SCAFFOLD reply without its 'control' ArrayRecord"
        for key, arr in records.pop("control").items():
            a = arr.numpy()
            if key not in reference or tuple(a.shape) != reference[key]:
                return f"control {key!r} does not match a model array"
            if not np.issubdtype(a.dtype, np.number) or not np.isfinite(a).all():
                return f"control {key!r} has non-finite values"
    arrays = list(records.values())
    metrics = list(content.metric_records.values())
    if len(arrays) != 1 or len(metrics) != 1:
        return (
            f"expected one ArrayRecord and one MetricRecord, got {len(arrays)} and {len(metrics)}"
        )
    record: ArrayRecord = arrays[0]
    keys = set(record.keys())
    if keys != set(reference):
        missing, extra = sorted(set(reference) - keys), sorted(keys - set(reference))
        return f"arrays do not match the model: missing {missing[:3]}, unexpected {extra[:3]}"
    for key, arr in record.items():
        a = arr.numpy()
        if tuple(a.shape) != reference[key]:
            return f"array {key!r} has shape {tuple(a.shape)}, the model's is {reference[key]}"
        if not np.issubdtype(a.dtype, np.number) or not np.isfinite(a).all():
            return f"array {key!r} has non-finite values"
    m: MetricRecord = metrics[0]
    missing_m = [k for k in REQUIRED_METRICS if k not in m]
    if missing_m:
        return f"metrics lack {missing_m}"
    n = m["num-examples"]
    if isinstance(n, list) or not math.isfinite(float(n)) or float(n) <= 0:
        return f"num-examples must be a positive number, got {n!r}"
    return None


def _drone(msg: Message, names: dict[int, str]) -> str:
    node = msg.metadata.src_node_id
    if msg.has_content():
        for rec in msg.content.config_records.values():
            if isinstance(rec.get("drone"), str):
                names[node] = str(rec["drone"])
                return names[node]
    return names.get(node, f"node-{node}")


def _notes(msg: Message) -> str:
    for rec in msg.content.config_records.values():
        if isinstance(rec.get("notes"), str):
            return str(rec["notes"])
    return ""


class GuardedMixin:
    """Mixed in before a Flower strategy class (see module docstring)."""

    recorder: Recorder
    wait_timeout_s: float
    round_timeout_s: float

    def setup_guard(
        self, recorder: Recorder, wait_timeout_s: float, round_timeout_s: float
    ) -> None:
        self.recorder = recorder
        self.wait_timeout_s = wait_timeout_s
        self.round_timeout_s = round_timeout_s
        self.names: dict[int, str] = {}
        self.reference: dict[str, tuple[int, ...]] = {}
        self.sent: dict[tuple[int, str], set[int]] = {}  # (round, phase) -> nodes asked
        self.suspects: set[int] = set()  # failed last round: skipped once
        self.round_started: dict[int, float] = {}
        self.train_summary: dict[int, dict[str, Any]] = {}
        self.evaluate_summary: dict[int, dict[str, float | None]] = {}  # federated evaluation

    # waiting for drones ----------------------------------------------------------------

    def _wait_for(self, grid: Grid, needed: int) -> None:
        deadline = time.monotonic() + self.wait_timeout_s
        announced = -1
        while True:
            connected = len(list(grid.get_node_ids()))
            if connected >= needed:
                if announced >= 0:
                    self.recorder.status("running", f"{connected} drones connected")
                return
            if connected != announced:
                self.recorder.status(
                    "waiting",
                    f"waiting for {needed - connected} more drone(s): {connected} of {needed} "
                    f"connected (timeout {self.wait_timeout_s:.0f} s)",
                    connected=connected,
                    needed=needed,
                )
                announced = connected
            if time.monotonic() > deadline:
                raise DronesMissing(
                    f"only {connected} of {needed} drones connected after "
                    f"{self.wait_timeout_s:.0f} s"
                )
            time.sleep(0.5)

    def _grid_for_round(self, grid: Grid, needed: int) -> Grid:
        self._wait_for(grid, needed)
        usable = [n for n in grid.get_node_ids() if n not in self.suspects]
        exclude = self.suspects if len(usable) >= needed else set()
        self.suspects = set()
        return _FilteredGrid(grid, exclude)  # type: ignore[return-value]

    # training --------------------------------------------------------------------------

    def configure_train(
        self, server_round: int, arrays: ArrayRecord, config: ConfigRecord, grid: Grid
    ) -> Iterable[Message]:
        self.round_started[server_round] = time.monotonic()
        self.reference = {k: tuple(a.numpy().shape) for k, a in arrays.items()}
        needed = max(self.min_available_nodes, self.min_train_nodes)  # type: ignore[attr-defined]
        filtered = self._grid_for_round(grid, needed)
        messages = list(super().configure_train(server_round, arrays, config, filtered))  # type: ignore[misc]
        self.sent[(server_round, "train")] = {m.metadata.dst_node_id for m in messages}
        return messages

    def aggregate_train(
        self, server_round: int, replies: Iterable[Message]
    ) -> tuple[ArrayRecord | None, MetricRecord | None]:
        replies = list(replies)
        accepted = self._screen(server_round, "train", replies, check=True)
        # Replies come in the order drones finish; the weighted sums are floating point,
        # so average in one fixed order (by drone) to make a seed give one model.
        accepted.sort(key=lambda m: (_drone(m, self.names), m.metadata.src_node_id))
        if not accepted:
            self.train_summary[server_round] = {"ok": 0, "failed": len(replies)}
            return None, None
        arrays, metrics = super().aggregate_train(server_round, accepted)  # type: ignore[misc]
        self.train_summary[server_round] = {
            "ok": len(accepted),
            "failed": len(self.sent.get((server_round, "train"), ())) - len(accepted),
            "train_loss": _f(metrics.get("train_loss")) if metrics else None,
        }
        return arrays, metrics

    # evaluation --------------------------------------------------------------------------

    def configure_evaluate(
        self, server_round: int, arrays: ArrayRecord, config: ConfigRecord, grid: Grid
    ) -> Iterable[Message]:
        if self.fraction_evaluate == 0.0:  # type: ignore[attr-defined]
            return []
        live = _FilteredGrid(grid, set(self.suspects))
        if len(live.get_node_ids()) < max(1, self.min_evaluate_nodes):  # type: ignore[attr-defined]
            return []
        messages = list(super().configure_evaluate(server_round, arrays, config, live))  # type: ignore[misc]
        self.sent[(server_round, "evaluate")] = {m.metadata.dst_node_id for m in messages}
        return messages

    def aggregate_evaluate(
        self, server_round: int, replies: Iterable[Message]
    ) -> MetricRecord | None:
        accepted = self._screen(server_round, "evaluate", list(replies), check=False)
        if not accepted:
            return None
        metrics = super().aggregate_evaluate(server_round, accepted)  # type: ignore[misc]
        if metrics is not None:  # the mean over the drones' validation windows
            self.evaluate_summary[server_round] = {
                "val_loss": _f(metrics.get("loss")),
                "val_accuracy": _f(metrics.get("accuracy")),
            }
        return metrics

    # screening -----------------------------------------------------------------------------

    def _screen(
        self, server_round: int, phase: str, replies: list[Message], check: bool
    ) -> list[Message]:
        accepted: list[Message] = []
        answered: set[int] = set()
        for msg in replies:
            node = msg.metadata.src_node_id
            answered.add(node)
            drone = _drone(msg, self.names)
            if msg.has_error():
                self.suspects.add(node)
                self.recorder.client_result(
                    server_round,
                    drone,
                    phase=phase,
                    status="failed",
                    detail=f"error reply (code {msg.error.code}): {msg.error.reason}"[:2000],
                )
                continue
            control = getattr(self, "uses_control", False)
            problem = check_update(msg.content, self.reference, control) if check else None
            if not check and len(msg.content.metric_records) != 1:
                problem = "expected one MetricRecord"
            if problem:
                self.recorder.client_result(
                    server_round, drone, phase=phase, status="rejected", detail=problem
                )
                continue
            m = next(iter(msg.content.metric_records.values()))
            self.recorder.client_result(
                server_round,
                drone,
                phase=phase,
                status="ok",
                loss=_f(m.get("val_loss" if phase == "train" else "loss")),
                accuracy=_f(m.get("val_accuracy" if phase == "train" else "accuracy")),
                train_loss=_f(m.get("train_loss")),
                samples=int(_f(m["num-examples"]) or 0),
                duration_s=_f(m.get("seconds")),
                detail=_notes(msg),
            )
            accepted.append(msg)
        for node in self.sent.get((server_round, phase), set()) - answered:
            self.suspects.add(node)
            self.recorder.client_result(
                server_round,
                self.names.get(node, f"node-{node}"),
                phase=phase,
                status="failed",
                detail=f"no reply within the round timeout "
                f"({self.round_timeout_s:.0f} s): drone lost or too slow",
            )
        return accepted


def _f(value: Any) -> float | None:
    if value is None or isinstance(value, list):
        return None
    return float(value)


class Scaffold(FedAvgM):
    """FedAvg plus SCAFFOLD's control variates (Karimireddy et al. 2020), for drones that
    each see one view: every drone replies with its control variate c_i (its mean AdamW
    step of the round, `task.next_control`, under "control"); the fleet's c is the
    sample-weighted average of each drone's latest c_i, sent with the next round's
    weights; each drone then corrects every local step by -lr (c - c_i)
    (`task.control_step`). What leaves a drone is the size of the weights it already
    sends, and no data. SCAFFOLD's global step eta_g is Flower's FedAvgM server step
    (`server_learning_rate`, no momentum): the new weights are old + eta_g (average -
    old); 1 keeps the plain average."""

    uses_control = True

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.controls: dict[int, tuple[float, dict[str, np.ndarray]]] = {}

    def fleet_control(self) -> dict[str, np.ndarray] | None:
        if not self.controls:
            return None
        total = sum(n for n, _ in self.controls.values())
        keys = next(iter(self.controls.values()))[1].keys()
        return {
            k: np.sum([n * c[k] for n, c in self.controls.values()], axis=0) / total for k in keys
        }

    def configure_train(
        self, server_round: int, arrays: ArrayRecord, config: ConfigRecord, grid: Grid
    ) -> Iterable[Message]:
        messages = list(super().configure_train(server_round, arrays, config, grid))
        fleet = self.fleet_control()
        if fleet is not None:
            record = arrays_of(fleet)
            for msg in messages:  # Flower's messages share one RecordDict
                msg.content["control"] = record
        return messages

    def aggregate_train(
        self, server_round: int, replies: Iterable[Message]
    ) -> tuple[ArrayRecord | None, MetricRecord | None]:
        replies = list(replies)
        for msg in replies:  # FedAvg averages exactly one ArrayRecord: take ours out
            if msg.has_error() or "control" not in msg.content.array_records:
                continue
            record = msg.content.array_records["control"]
            del msg.content["control"]
            n = float(next(iter(msg.content.metric_records.values()))["num-examples"])  # type: ignore[arg-type]
            self.controls[msg.metadata.src_node_id] = (n, named_arrays(record))
        return super().aggregate_train(server_round, replies)


BASES = {
    "fedavg": FedAvg,
    "fedprox": FedProx,
    "fedadam": FedAdam,
    "fedavgm": FedAvgM,
    "scaffold": Scaffold,
}


def guarded(cfg: FLConfig, recorder: Recorder) -> FedAvg:
    """The run's strategy: Flower's class for `cfg.strategy` with the guard mixin."""
    base = BASES[cfg.strategy]
    cls = type(f"Guarded{base.__name__}", (GuardedMixin, base), {})
    common: dict[str, Any] = dict(
        fraction_train=cfg.fraction_fit,
        fraction_evaluate=cfg.fraction_evaluate,
        min_train_nodes=cfg.min_clients,
        min_evaluate_nodes=cfg.min_clients if cfg.fraction_evaluate > 0 else 0,
        min_available_nodes=cfg.min_clients,
    )
    if cfg.strategy == "fedprox":
        common["proximal_mu"] = cfg.proximal_mu
    elif cfg.strategy == "fedadam":
        common.update(eta=cfg.server_eta, eta_l=cfg.learning_rate)
    elif cfg.strategy == "fedavgm":
        common.update(
            server_learning_rate=cfg.server_learning_rate, server_momentum=cfg.server_momentum
        )
    elif cfg.strategy == "scaffold":
        common["server_learning_rate"] = cfg.server_learning_rate
    strategy = cls(**common)
    strategy.setup_guard(recorder, cfg.wait_timeout_s, cfg.round_timeout_s)
    return strategy
