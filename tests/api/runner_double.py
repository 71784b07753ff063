"""A `TrainingRunner` (proxima.api.interfaces) that trains nothing, for tests where a
request must never start real federated training (the schemathesis run): parameters are
checked as the real runner checks them (`config_from_params`, FLConfig's bounds, the
minimum number of clients against the fleet), and each accepted run is recorded as
running until `cancel_run` (or as completed at once, with `finish_at_once`)."""

from __future__ import annotations

import threading
import time
import uuid
from typing import Any

from proxima.federated.config import FLConfig
from proxima.federated.runner import config_from_params


class NoTrainingRunner:
    def __init__(self, clients: list[str], *, finish_at_once: bool = False) -> None:
        self.defaults = FLConfig()
        self._clients = list(clients)
        self.finish_at_once = finish_at_once
        self.runs: dict[str, dict[str, Any]] = {}
        self._lock = threading.Lock()

    @property
    def clients(self) -> list[str]:
        return list(self._clients)

    def start_run(self, params: dict[str, Any]) -> str:
        cfg = config_from_params(params, self.defaults)
        if cfg.min_clients > len(self._clients):
            raise ValueError(f"min_clients {cfg.min_clients} > {len(self._clients)} drones")
        with self._lock:
            if any(r["status"] == "running" for r in self.runs.values()):
                raise RuntimeError("a run is still in progress")
            run_id = uuid.uuid4().hex[:12]
            status = "completed" if self.finish_at_once else "running"
            self.runs[run_id] = {
                "id": run_id,
                "status": status,
                "params": cfg.to_run_config(),
                "started_by": str(params.get("started_by", "")),
                "created_at": time.time(),
                "rounds_total": cfg.rounds,
                "rounds_done": cfg.rounds if self.finish_at_once else 0,
            }
            return run_id

    def cancel_run(self, run_id: str) -> bool:
        with self._lock:
            run = self.runs.get(run_id)
            if run is None or run["status"] != "running":
                return False
            run["status"] = "stopped"
            return True

    def list_runs(self) -> list[dict[str, Any]]:
        with self._lock:
            return sorted(self.runs.values(), key=lambda r: r["created_at"], reverse=True)

    def get_run(self, run_id: str) -> dict[str, Any] | None:
        with self._lock:
            run = self.runs.get(run_id)
            return dict(run) if run is not None else None
