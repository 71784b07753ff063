"""A federated run's parameters, one dataclass shared by the ServerApp, the ClientApp,
the simulation and the deployment runner.

Flower passes run config as flat `key = value` pairs with hyphenated keys
(`[tool.flwr.app.config]` in `flower-app/pyproject.toml`, overridable per run); the
field `local_epochs` is the run-config key `local-epochs`. Every value is checked here,
so a bad parameter stops a run before any drone trains, with the key named.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields
from pathlib import Path
from typing import Any

STRATEGIES = ("fedavg", "fedprox", "fedadam", "fedavgm")
PARTITIONS = ("view", "iid", "dirichlet")
VIEWS = ("f", "l", "r")
VIEW_NAMES = {"f": "front", "l": "left", "r": "right"}
APP_DIR = Path(__file__).resolve().parent / "flower-app"


class ConfigError(ValueError):
    """A run parameter that cannot be used; the message names the key."""


@dataclass
class FLConfig:
    """Everything one federated run needs besides the drones themselves."""

    rounds: int = 5
    local_epochs: int = 1
    batch_size: int = 64
    learning_rate: float = 2e-3
    lr_decay: float = 1.0  # local learning rate x lr_decay per round (1 = constant)
    fraction_fit: float = 1.0
    fraction_evaluate: float = 0.0  # federated evaluation of the global model on drones
    min_clients: int = 2
    strategy: str = "fedavg"
    proximal_mu: float = 0.01  # FedProx only
    server_learning_rate: float = 1.0  # FedAvgM only
    server_eta: float = 1e-2  # FedAdam's server step size
    server_momentum: float = 0.9  # FedAvgM only
    partition: str = "view"
    num_drones: int = 3
    dirichlet_alpha: float = 0.5
    include_samples: bool = True
    model: str = "tcn"
    pipeline: str = "body"
    stride: int = 4  # frames between training windows (as centralised training)
    test_stride: int = 3  # frames between held-out test windows
    max_gap: int = 5
    patience: int = 12  # local early stopping (epochs without a better validation loss)
    mirror: bool = False  # mirroring on the drones; no gain measured (docs/federated.md)
    seed: int = 0
    threads: int = 1  # torch threads per client
    round_timeout_s: float = 600.0  # a drone that has not answered by then is dropped
    wait_timeout_s: float = 120.0  # how long to wait for `min_clients` drones
    data: str = ""  # data folders for the held-out test set, ";"-separated ("" = default)
    run_id: str = ""
    db: str = ""  # SQLite file the ServerApp records rounds in ("" = nowhere)
    models_dir: str = ""  # where the global model is saved ("" = not saved)

    def __post_init__(self) -> None:
        self.validate()

    def validate(self) -> None:
        """Raises ConfigError naming the first bad key."""

        def need(ok: bool, key: str, what: str) -> None:
            if not ok:
                raise ConfigError(f"run config {key!r}: {what} (got {getattr(self, key)!r})")

        need(self.rounds >= 1, "rounds", "must be at least 1")
        need(self.local_epochs >= 1, "local_epochs", "must be at least 1")
        need(self.batch_size >= 1, "batch_size", "must be at least 1")
        need(0 < self.learning_rate <= 1, "learning_rate", "must be in (0, 1]")
        need(0 < self.lr_decay <= 1, "lr_decay", "must be in (0, 1]")
        need(0 < self.fraction_fit <= 1, "fraction_fit", "must be in (0, 1]")
        need(0 <= self.fraction_evaluate <= 1, "fraction_evaluate", "must be in [0, 1]")
        need(self.min_clients >= 1, "min_clients", "must be at least 1")
        need(self.strategy in STRATEGIES, "strategy", f"must be one of {', '.join(STRATEGIES)}")
        need(self.proximal_mu >= 0, "proximal_mu", "must be >= 0")
        need(self.server_learning_rate > 0, "server_learning_rate", "must be > 0")
        need(self.server_eta > 0, "server_eta", "must be > 0")
        need(0 <= self.server_momentum < 1, "server_momentum", "must be in [0, 1)")
        need(self.partition in PARTITIONS, "partition", f"must be one of {', '.join(PARTITIONS)}")
        need(self.num_drones >= 1, "num_drones", "must be at least 1")
        need(self.dirichlet_alpha > 0, "dirichlet_alpha", "must be > 0")
        need(self.stride >= 1, "stride", "must be at least 1")
        need(self.test_stride >= 1, "test_stride", "must be at least 1")
        need(self.max_gap >= 0, "max_gap", "must be >= 0")
        need(self.patience >= 1, "patience", "must be at least 1")
        need(self.threads >= 1, "threads", "must be at least 1")
        need(self.round_timeout_s > 0, "round_timeout_s", "must be > 0")
        need(self.wait_timeout_s > 0, "wait_timeout_s", "must be > 0")
        need(
            self.pipeline == "body",
            "pipeline",
            "only the scale-free 'body' pipeline is supported for federated runs: the "
            "'paper' MinMax pipeline would scale each drone with statistics only it has",
        )
        from proxima.gesture.models import MODELS

        need(self.model in MODELS, "model", f"must be one of {', '.join(MODELS)}")

    # Flower run config <-> dataclass -------------------------------------------------

    def to_run_config(self) -> dict[str, bool | int | float | str]:
        """Flat hyphenated keys, as `[tool.flwr.app.config]` and `flwr run -c` use."""
        return {k.replace("_", "-"): v for k, v in asdict(self).items()}

    @classmethod
    def from_run_config(cls, run_config: dict[str, Any]) -> FLConfig:
        """Build from Flower's run config (hyphenated or underscored keys).

        Raises:
            ConfigError: an unknown key, a value of the wrong type, or a bad value.
        """
        kinds = {f.name: f.type for f in fields(cls)}
        values: dict[str, Any] = {}
        for key, value in run_config.items():
            name = key.replace("-", "_")
            if name not in kinds:
                raise ConfigError(f"run config {key!r}: unknown key")
            values[name] = _coerce(key, value, kinds[name])
        return cls(**values)

    def data_specs(self) -> list[str] | None:
        return [s for s in self.data.split(";") if s] or None


def _coerce(key: str, value: Any, kind: Any) -> Any:
    kind = kind if isinstance(kind, str) else kind.__name__
    try:
        if kind == "bool":
            if isinstance(value, bool):
                return value
            if isinstance(value, str) and value.lower() in ("true", "false", "1", "0"):
                return value.lower() in ("true", "1")
            raise ValueError
        if kind == "int":
            if isinstance(value, bool) or (isinstance(value, float) and not value.is_integer()):
                raise ValueError
            return int(value)
        if kind == "float":
            if isinstance(value, bool):
                raise ValueError
            return float(value)
        return str(value)
    except (TypeError, ValueError):
        raise ConfigError(f"run config {key!r}: expected {kind}, got {value!r}") from None


def view_of(partition_id: int) -> str:
    """The LASER camera view a drone holds under the `view` partition (f, l, r, f, ...)."""
    return VIEWS[partition_id % len(VIEWS)]


def default_drone_name(partition_id: int, num_drones: int) -> str:
    """`front`, `left`, `right` for three drones; `drone-N` beyond."""
    if num_drones <= len(VIEWS):
        return VIEW_NAMES[view_of(partition_id)]
    return f"drone-{partition_id}"
