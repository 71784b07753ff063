"""A federated run's parameters, one dataclass shared by the ServerApp, the ClientApp,
the simulation, the deployment runner and the console.

Each field is declared once here with its bounds (pydantic `Field` constraints in the
annotation): `FLConfig` checks them when built, the console's request schema
(`proxima.api.schemas.TrainingStart`) uses the same annotated types, and the console's
form reads them from `/api/config` (`field_schema`). Flower passes run config as flat
`key = value` pairs with hyphenated keys (`[tool.flwr.app.config]` in
`flower-app/pyproject.toml`, overridable per run; a test checks it equals the defaults
here); the field `local_epochs` is the run-config key `local-epochs`. A bad parameter
stops a run before any drone trains, with the key named.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields
from functools import cache
from pathlib import Path
from typing import Annotated, Any, Literal, get_args, get_origin, get_type_hints

from pydantic import ConfigDict, Field, TypeAdapter, ValidationError

from proxima.gesture.windows import MIN_WINDOW, WINDOW

Strategy = Literal["fedavg", "fedprox", "fedadam", "fedavgm", "scaffold"]
Partition = Literal["view", "iid", "dirichlet"]
STRATEGIES: tuple[str, ...] = get_args(Strategy)
PARTITIONS: tuple[str, ...] = get_args(Partition)
# pipelines without fitted statistics (docs/gesture.md), so no drone scales on its own
SCALE_FREE_PIPELINES = ("body", "body-image", "body-smooth-z")
VIEWS = ("f", "l", "r")
VIEW_NAMES = {"f": "front", "l": "left", "r": "right"}
APP_DIR = Path(__file__).resolve().parent / "flower-app"

# The parameters a supervisor sets on the console's form, with their bounds.
Rounds = Annotated[int, Field(ge=1, le=500, description="federated rounds")]
LocalEpochs = Annotated[int, Field(ge=1, le=100, description="epochs each drone trains a round")]
BatchSize = Annotated[int, Field(ge=1, le=4096, description="local batch size")]
LearningRate = Annotated[float, Field(ge=1e-6, le=1, description="local learning rate")]
FractionFit = Annotated[float, Field(gt=0, le=1, description="share of drones asked per round")]
MinClients = Annotated[int, Field(ge=1, le=100, description="drones a round waits for")]
Positive = Annotated[float, Field(gt=0)]
AtLeastOne = Annotated[int, Field(ge=1)]


class ConfigError(ValueError):
    """A run parameter that cannot be used; the message names the key."""


@dataclass
class FLConfig:
    """Everything one federated run needs besides the drones themselves.

    Raises:
        ConfigError: (constructor) a value of the wrong type or out of its bounds, named
            by its run-config key.
    """

    rounds: Rounds = 5
    local_epochs: LocalEpochs = 1
    batch_size: BatchSize = 64
    learning_rate: LearningRate = 2e-3
    lr_decay: Annotated[float, Field(gt=0, le=1)] = 1.0  # local lr x lr_decay per round
    fraction_fit: FractionFit = 1.0
    fraction_evaluate: Annotated[float, Field(ge=0, le=1)] = 0.0  # federated evaluation
    min_clients: MinClients = 2
    strategy: Strategy = "fedavg"
    proximal_mu: Annotated[float, Field(ge=0)] = 0.01  # FedProx only
    # FedAvgM's, and SCAFFOLD's global step eta_g: new = old + eta_g (average - old)
    server_learning_rate: Positive = 1.0
    server_eta: Positive = 1e-2  # FedAdam's server step size
    server_momentum: Annotated[float, Field(ge=0, lt=1)] = 0.9  # FedAvgM only
    partition: Partition = "view"
    num_drones: AtLeastOne = 3
    dirichlet_alpha: Positive = 0.5
    include_samples: bool = True
    model: str = "tcn"
    pipeline: str = "body"
    stride: AtLeastOne = 4  # frames between training windows (as centralised training)
    # frames a window holds (`proxima train --window`): the streams' models' length, or
    # promotion refuses the run's model
    window: Annotated[int, Field(ge=MIN_WINDOW, le=WINDOW)] = WINDOW
    test_stride: AtLeastOne = 3  # frames between held-out test windows
    max_gap: Annotated[int, Field(ge=0)] = 5
    patience: AtLeastOne = 12  # local early stopping (epochs without a better val loss)
    # the weights a drone sends: those after its last local epoch ("last"), its best
    # epoch's by its own small validation tail ("best"; 1 point worse, docs/federated.md),
    # or the mean of its weights after each epoch of the second half of the round ("mean")
    local_weights: Literal["best", "last", "mean"] = "last"
    # the global model the run ends with: the last round's, or the round's whose model the
    # drones' validation windows score best (lowest loss; needs fraction-evaluate > 0):
    # the federated twin of centralised training's early stopping on its validation parts
    keep_round: Literal["best", "last"] = "last"
    mirror: bool = False  # mirroring on the drones; no gain measured (docs/federated.md)
    # moving gestures' clips start with at most half a window of opening rest, as in
    # centralised training (gesture/idle.py): windows of rest carry no gesture
    trim_idle: bool = True
    # local epochs on capture-noised, One-Euro-smoothed windows (gesture/robust.py; the
    # partitions carry no history, so without the frame-rate and loss effects), or "none"
    augment: Literal["none", "capture"] = "capture"
    seed: int = 0
    threads: AtLeastOne = 1  # torch threads per client
    round_timeout_s: Positive = 600.0  # a drone that has not answered by then is dropped
    wait_timeout_s: Positive = 120.0  # how long to wait for `min_clients` drones
    data: str = ""  # data folders for the held-out test set, ";"-separated ("" = default)
    run_id: str = ""
    db: str = ""  # SQLite file the ServerApp records rounds in ("" = nowhere)
    models_dir: str = ""  # where the global model is saved ("" = not saved)
    # a checkpoint the global model starts from instead of the seeded fresh model (e.g.
    # the synthetic operator's model, docs/synth.md); same model and pipeline as the run
    init: str = ""

    def __post_init__(self) -> None:
        self.validate()

    def validate(self) -> None:
        """Check (and coerce, e.g. "3" -> 3) every field; raises ConfigError naming the
        first bad key."""
        for name, adapter in _adapters().items():
            value = getattr(self, name)
            if isinstance(value, bool) and _base_type(name) in (int, float):
                raise ConfigError(f"run config {_key(name)!r}: expected a number, got {value!r}")
            try:
                setattr(self, name, adapter.validate_python(value))
            except ValidationError as exc:
                what = "; ".join(e["msg"] for e in exc.errors())
                raise ConfigError(f"run config {_key(name)!r}: {what} (got {value!r})") from None
        if self.pipeline not in SCALE_FREE_PIPELINES:
            raise ConfigError(
                f"run config 'pipeline': only the scale-free pipelines "
                f"({', '.join(SCALE_FREE_PIPELINES)}) are supported for federated runs: the "
                f"'paper' MinMax pipeline would scale each drone with statistics only it has "
                f"(got {self.pipeline!r})"
            )
        if self.keep_round == "best" and self.fraction_evaluate == 0:
            raise ConfigError(
                "run config 'keep-round': 'best' picks the round by federated evaluation, "
                "so 'fraction-evaluate' must be above 0"
            )
        from proxima.gesture.models import MODELS

        if self.model not in MODELS:
            raise ConfigError(
                f"run config 'model': must be one of {', '.join(MODELS)} (got {self.model!r})"
            )

    @staticmethod
    def field_schema(name: str) -> dict[str, Any]:
        """The JSON schema of one field (type, bounds, choices), for forms.

        Raises:
            KeyError: no such field.
        """
        return _adapters()[name].json_schema()

    # Flower run config <-> dataclass -------------------------------------------------

    def to_run_config(self) -> dict[str, bool | int | float | str]:
        """Flat hyphenated keys, as `[tool.flwr.app.config]` and `flwr run -c` use."""
        return {_key(k): v for k, v in asdict(self).items()}

    @classmethod
    def from_run_config(cls, run_config: dict[str, Any]) -> FLConfig:
        """Build from Flower's run config (hyphenated or underscored keys).

        Raises:
            ConfigError: an unknown key, a value of the wrong type, or a bad value.
        """
        known = {f.name for f in fields(cls)}
        values: dict[str, Any] = {}
        for key, value in run_config.items():
            name = key.replace("-", "_")
            if name not in known:
                raise ConfigError(f"run config {key!r}: unknown key")
            values[name] = value
        return cls(**values)

    def data_specs(self) -> list[str] | None:
        return [s for s in self.data.split(";") if s] or None


def _key(name: str) -> str:
    """A field's run-config key (`local_epochs` -> `local-epochs`)."""
    return name.replace("_", "-")


@cache
def _hints() -> dict[str, Any]:
    return get_type_hints(FLConfig, include_extras=True)


def _base_type(name: str) -> Any:
    hint = _hints()[name]
    return get_args(hint)[0] if get_origin(hint) is Annotated else hint


@cache
def _adapters() -> dict[str, TypeAdapter[Any]]:
    """One validator per field, from its annotation (numbers given as text are accepted,
    as `flwr run -c` may pass them)."""
    lax = ConfigDict(coerce_numbers_to_str=True)
    return {name: TypeAdapter(hint, config=lax) for name, hint in _hints().items()}


def view_of(partition_id: int) -> str:
    """The LASER camera view a drone holds under the `view` partition (f, l, r, f, ...)."""
    return VIEWS[partition_id % len(VIEWS)]


def default_drone_name(partition_id: int, num_drones: int) -> str:
    """`front`, `left`, `right` for three drones; `drone-N` beyond."""
    if num_drones <= len(VIEWS):
        return VIEW_NAMES[view_of(partition_id)]
    return f"drone-{partition_id}"
