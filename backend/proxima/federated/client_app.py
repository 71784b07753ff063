"""The Flower ClientApp: a drone's side of a run.

Thin: the run config arrives with every message (so the simulation and the deployment
engine behave alike), the drone's own facts come from its node config (`partition-id`,
`num-partitions`, and on real drones `drone`, `data`, `samples-db`), and the work is
`task.train_local` / `task.Scorer` on the drone's `data.drone_data`. Only weights and
numbers leave the drone, never landmarks. Its reply carries a `report` ConfigRecord
with the drone's name and notes (e.g. a corrupt sample it skipped).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from flwr.app import ArrayRecord, ConfigRecord, Context, Message, MetricRecord, RecordDict
from flwr.clientapp import ClientApp

from proxima.federated.config import FLConfig, default_drone_name
from proxima.federated.data import DroneData, drone_data
from proxima.federated.task import (
    Scorer,
    arrays_of,
    get_weights,
    named_arrays,
    new_model,
    next_control,
    set_weights,
    train_local,
)

# Keys the server adds to the run config in its messages (not FLConfig fields).
_SERVER_KEYS = ("server-round",)
# SCAFFOLD: the fleet's control variate in the server's message, and the drone's own,
# kept in the node's state between rounds and sent back for the fleet's average.
CONTROL = "control"
_OWN_CONTROL = "scaffold-control"


@dataclass(frozen=True)
class Node:
    """What a drone knows about itself (Flower's node config)."""

    partition_id: int
    num_partitions: int
    drone: str
    data: tuple[str, ...]
    samples_db: str

    @classmethod
    def from_context(cls, context: Context, cfg: FLConfig) -> Node:
        nc = dict(context.node_config)
        pid = int(nc.get("partition-id", 0))
        num = int(nc.get("num-partitions", cfg.num_drones))
        data = str(nc.get("data", "")) or cfg.data
        return cls(
            partition_id=pid,
            num_partitions=num,
            drone=str(nc.get("drone", "")) or default_drone_name(pid, num),
            data=tuple(s for s in data.split(";") if s),
            samples_db=str(nc.get("samples-db", "")),
        )


def config_of(msg: Message) -> FLConfig:
    config = msg.content.config_records["config"]
    rc = {k: v for k, v in config.items() if k not in _SERVER_KEYS}
    return FLConfig.from_run_config(rc)


_CACHE: dict[tuple[str, Node], DroneData] = {}


def _local(msg: Message, context: Context) -> tuple[FLConfig, Node, DroneData]:
    """The run config, this drone's facts, and its data (built once per run and process:
    samples can change between runs, so the run id is part of the key)."""
    cfg = config_of(msg)
    node = Node.from_context(context, cfg)
    if node.num_partitions != cfg.num_drones:  # the federation decides how many share
        cfg = replace(cfg, num_drones=node.num_partitions)
    key = "|".join(
        str(getattr(cfg, k))
        for k in (
            "run_id",
            "partition",
            "num_drones",
            "dirichlet_alpha",
            "seed",
            "stride",
            "max_gap",
            "include_samples",
            "data",
        )
    )
    if (key, node) not in _CACHE:
        while len(_CACHE) >= 8:
            _CACHE.pop(next(iter(_CACHE)))
        _CACHE[(key, node)] = drone_data(
            cfg, node.partition_id, node.drone, node.data or None, node.samples_db or None
        )
    return cfg, node, _CACHE[(key, node)]


def _arrays(msg: Message) -> dict[str, np.ndarray]:
    """The global weights a message carries, as numpy arrays."""
    return named_arrays(msg.content.array_records["arrays"])


def _int(value: object) -> int:
    """A run-config number (Flower types record values as any of its value kinds)."""
    if not isinstance(value, int | float | str):
        raise TypeError(f"expected a number, got {type(value).__name__}")
    return int(value)


def _reply(
    msg: Message, node: Node, data: DroneData, arrays: ArrayRecord | None, metrics: dict[str, float]
) -> Message:
    content = RecordDict({"metrics": MetricRecord(dict(metrics))})
    if arrays is not None:
        content["arrays"] = arrays
    content["report"] = ConfigRecord({"drone": node.drone, "notes": "\n".join(data.notes)})
    return Message(content=content, reply_to=msg)


app = ClientApp()


@app.train()
def train(msg: Message, context: Context) -> Message:
    """Local epochs from the global weights; reply with the new weights and metrics."""
    cfg, node, data = _local(msg, context)
    if not len(data.fit):
        raise RuntimeError(f"drone {node.drone}: no training windows in its data")
    model, pipeline = new_model(cfg)
    set_weights(model, _arrays(msg))
    server_round = _int(msg.content.config_records["config"].get("server-round", 0))
    scaffold = cfg.strategy == "scaffold"
    correction = _correction(msg, context) if scaffold else None
    start = get_weights(model)
    res = train_local(
        model, pipeline, data.fit, data.val, cfg, server_round, node.partition_id, correction
    )
    control = None
    if scaffold:
        control = arrays_of(next_control(start, get_weights(model), res.steps, res.lr, correction))
        context.state[_OWN_CONTROL] = control
    metrics = {
        "num-examples": res.num_examples,
        "train_loss": res.train_loss,
        "val_loss": res.val_loss,
        "val_accuracy": res.val_accuracy,
        "seconds": res.seconds,
        "samples_used": data.samples_used,
    }
    reply = _reply(msg, node, data, ArrayRecord(model.state_dict()), metrics)
    if control is not None:
        reply.content[CONTROL] = control
    return reply


def _correction(msg: Message, context: Context) -> dict[str, np.ndarray] | None:
    """c - c_i: the fleet's variate from the message less this drone's from its state;
    None before the first round has made one (a drone that joins later has c_i = 0)."""
    fleet = msg.content.array_records.get(CONTROL)
    if fleet is None:
        return None
    own = context.state.array_records.get(_OWN_CONTROL)
    mine = named_arrays(own) if own is not None else {}
    return {k: v - mine.get(k, 0.0) for k, v in named_arrays(fleet).items()}


@app.evaluate()
def evaluate(msg: Message, context: Context) -> Message:
    """The global model on this drone's validation windows."""
    cfg, node, data = _local(msg, context)
    loss, acc = Scorer(cfg, data.val)(_arrays(msg))
    metrics = {"num-examples": max(len(data.val), 1), "loss": loss, "accuracy": acc, "seconds": 0.0}
    return _reply(msg, node, data, None, metrics)
