"""Bus events of federated runs, for the console's live curves and run list.

`training_round`: the global model after a round (accuracy and loss on the held-out set)
and every drone's result in it (ok, failed or rejected, with loss, accuracy, samples,
seconds). `training_run`: a run changed state: pending, waiting (for drones: `connected`
of `needed`), running, completed, failed or stopped, with a human-readable `detail`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from proxima.types import Event


@dataclass(frozen=True, kw_only=True)
class TrainingRoundEvent(Event):
    run_id: str
    round: int
    rounds_total: int
    global_accuracy: float | None
    global_loss: float | None
    train_loss: float | None = None
    duration_s: float = 0.0
    clients: tuple[dict, ...] = ()  # {drone, phase, status, loss, accuracy, samples, ...}
    type: str = field(default="training_round", init=False)


@dataclass(frozen=True, kw_only=True)
class TrainingRunEvent(Event):
    run_id: str
    status: str
    detail: str = ""
    rounds_done: int = 0
    rounds_total: int = 0
    connected: int | None = None  # drones connected, while waiting
    needed: int | None = None  # drones the run needs
    checkpoint: str | None = None
    final_accuracy: float | None = None
    type: str = field(default="training_run", init=False)
