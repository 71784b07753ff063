"""Collects a run's rounds and per-drone results as the ServerApp produces them: kept in
memory (for the simulate command's JSON), written to SQLite when the run has a database
(how the console hears of deployment runs, whose ServerApp is another process), and
handed to optional callbacks (progress bars, in-process event publishing)."""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable
from typing import Any

from proxima.store.training import TrainingStore

log = logging.getLogger(__name__)


def _clean(value: Any) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def kept_round_row(rounds: list[dict[str, Any]], kept: int | None) -> dict[str, Any]:
    """The record of round `kept` (the last round's when None or absent; {} if none)."""
    return next((r for r in rounds if r["round"] == kept), rounds[-1] if rounds else {})


class RunRecorder:
    """The strategy's `Recorder`: client results and statuses; rounds from the server."""

    def __init__(
        self,
        run_id: str,
        rounds_total: int,
        store: TrainingStore | None = None,
        on_round: Callable[[dict[str, Any]], None] | None = None,
        on_status: Callable[[str, str, dict[str, Any]], None] | None = None,
    ) -> None:
        self.run_id = run_id
        self.rounds_total = rounds_total
        self.store = store
        self.on_round = on_round
        self.on_status = on_status
        self.rounds: list[dict[str, Any]] = []
        self._clients: dict[int, list[dict[str, Any]]] = {}
        self.last_status = ""

    def client_result(self, server_round: int, client: str, **fields: Any) -> None:
        row = {"drone": client, **{k: _clean(v) for k, v in fields.items()}}
        self._clients.setdefault(server_round, []).append(row)
        if self.store is not None:
            self.store.add_client_result(self.run_id, server_round, client, **fields)

    def status(self, status: str, detail: str = "", **extra: Any) -> None:
        self.last_status = status
        log.info("run %s: %s %s", self.run_id, status, detail)
        if self.store is not None:
            self.store.update_run(self.run_id, status=status, detail=detail)
        if self.on_status is not None:
            self.on_status(status, detail, extra)

    def round_done(
        self,
        server_round: int,
        *,
        global_accuracy: float,
        global_loss: float,
        train_loss: float | None = None,
        clients_ok: int = 0,
        clients_failed: int = 0,
        duration_s: float = 0.0,
        val_loss: float | None = None,
        val_accuracy: float | None = None,
    ) -> dict[str, Any]:
        """Record the global model's score after a round (0: the initial model); `val_*`:
        the drones' federated evaluation of it, when the run has one."""
        row = {
            "round": server_round,
            "global_accuracy": _clean(float(global_accuracy)),
            "global_loss": _clean(float(global_loss)),
            "train_loss": _clean(train_loss),
            "val_loss": _clean(val_loss),
            "val_accuracy": _clean(val_accuracy),
            "clients_ok": clients_ok,
            "clients_failed": clients_failed,
            "duration_s": round(duration_s, 3),
            "clients": self._clients.get(server_round, []),
            "created_at": time.time(),
        }
        self.rounds.append(row)
        if self.store is not None:
            self.store.add_round(
                self.run_id,
                server_round,
                global_accuracy=global_accuracy,
                global_loss=global_loss,
                train_loss=train_loss,
                clients_ok=clients_ok,
                clients_failed=clients_failed,
                duration_s=duration_s,
            )
        if self.on_round is not None:
            self.on_round(row)
        return row
