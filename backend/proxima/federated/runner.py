"""The run coordinator: starts federated runs in the background, persists them, and
turns their progress into bus events for the console.

`FederatedRunner` is the console's `TrainingRunner` (start_run / list_runs / get_run)
and also what `proxima fl deploy-local` uses. On the deployment engine the ServerApp is
another process (started by the SuperLink), so the coordinator follows a run through
the database it writes (rounds, per-drone results, "waiting for N drones") and through
Flower's own run status (a ServerApp that crashed before writing anything still ends
the run as failed, with its log). On the simulation engine the run is in-process.

Promotion of a run's model into the live engine is a separate, explicit call
(`promote`), never a side effect of a run finishing.
"""

from __future__ import annotations

import logging
import shutil
import threading
import time
from collections.abc import Callable
from dataclasses import fields
from pathlib import Path
from typing import Any

from proxima.events import EventBus
from proxima.federated.config import ConfigError, FLConfig
from proxima.federated.deploy import DeploymentError, Drone, LocalFederation, default_drones
from proxima.federated.events import TrainingRoundEvent, TrainingRunEvent
from proxima.federated.settings import DeploymentSettings
from proxima.federated.simulate import new_run_id
from proxima.store.training import FINISHED, TrainingStore

log = logging.getLogger(__name__)

# Console parameter names that differ from FLConfig's.
ALIASES = {"started_by": None, "engine": None}


def config_from_params(params: dict[str, Any], base: FLConfig | None = None) -> FLConfig:
    """An FLConfig from the console's / CLI's parameters (FLConfig field names).

    Raises:
        ValueError: an unknown parameter or a bad value (named).
    """
    known = {f.name for f in fields(FLConfig)}
    values = {f.name: getattr(base, f.name) for f in fields(FLConfig)} if base else {}
    for key, value in params.items():
        name = key.replace("-", "_")
        if name in ALIASES:
            continue
        if name not in known:
            raise ValueError(f"unknown training parameter {key!r}")
        values[name] = value
    try:
        return FLConfig.from_run_config(values)
    except ConfigError as exc:
        raise ValueError(str(exc)) from None


class FederatedRunner:
    """Runs one federated run at a time, on Flower's Deployment Runtime (a SuperLink
    with one local SuperNode per drone, or the drones' own SuperNodes, started on first
    use and kept; secured as `security` says, by default TLS and SuperNode keys with a
    throwaway CA) or its Simulation Runtime (`flower_runtime`). The console's
    `TrainingRunner`. `close()` ends every Flower process it started."""

    def __init__(
        self,
        db_path: str | Path,
        models_dir: str | Path,
        *,
        bus: EventBus | None = None,
        workdir: str | Path | None = None,
        drones: list[Drone] | None = None,
        flower_runtime: str = "deployment",
        defaults: FLConfig | None = None,
        samples_db: str | Path | None = None,
        poll_s: float = 0.5,
        security: DeploymentSettings | None = None,
    ) -> None:
        if flower_runtime not in ("deployment", "simulation"):
            raise ValueError(
                f"flower_runtime must be deployment or simulation, got {flower_runtime!r}"
            )
        self.db_path = Path(db_path)
        self.store = TrainingStore(self.db_path)
        self.models_dir = Path(models_dir)
        self.bus = bus
        self.flower_runtime = flower_runtime
        self.defaults = defaults or FLConfig()
        self.workdir = Path(workdir) if workdir else self.db_path.parent / "federated"
        self.samples_db = str(samples_db) if samples_db else str(self.db_path)
        self._drones = drones
        self.security = security or DeploymentSettings()
        self.poll_s = poll_s
        self.federation: LocalFederation | None = None
        self._lock = threading.Lock()
        self._thread: threading.Thread | None = None
        self._active: str | None = None
        self._stop = threading.Event()
        self._closing = False
        self.listeners: list[Callable[[Any], None]] = []

    # the TrainingRunner interface ----------------------------------------------------------

    def start_run(self, params: dict[str, Any]) -> str:
        """Validate, record and start a run in the background; returns its id at once.

        Raises:
            ValueError: a bad parameter (named).
            RuntimeError: a run is already in progress.
        """
        cfg = config_from_params(params, self.defaults)
        fleet = len(self._drones) if self._drones else cfg.num_drones
        if self.flower_runtime == "deployment" and not self._drones:
            fleet = self.defaults.num_drones  # the default fleet is started once, so fixed
        if cfg.min_clients > fleet:
            raise ValueError(
                f"run config 'min-clients': {cfg.min_clients} is more than the {fleet} "
                "drones of this federation"
            )
        with self._lock:
            if self._thread is not None and self._thread.is_alive():
                raise RuntimeError(f"run {self._active} is still in progress")
            cfg.run_id = new_run_id()
            cfg.db = str(self.db_path.resolve())
            cfg.models_dir = str(self.models_dir.resolve())
            self.store.create_run(cfg.run_id, engine=self.flower_runtime,
                                  params=cfg.to_run_config(), rounds_total=cfg.rounds,
                                  started_by=str(params.get("started_by", "")))  # fmt: skip
            self._active = cfg.run_id
            self._stop.clear()
            deployment = self.flower_runtime == "deployment"
            target = self._deployment_run if deployment else self._simulation_run
            self._thread = threading.Thread(target=self._guard, args=(target, cfg),
                                            name=f"fl-run-{cfg.run_id}", daemon=True)  # fmt: skip
            self._thread.start()
        self._publish_run(cfg.run_id)
        return cfg.run_id

    @property
    def clients(self) -> list[str]:
        """The drones a deployment run trains on (the configured ones, else the default
        fleet of `defaults.num_drones`)."""
        drones = self._drones or default_drones(self.defaults.num_drones)
        return [d.name for d in drones]

    def cancel_run(self, run_id: str) -> bool:
        """Ask run `run_id` to stop if it is the one in progress (it ends as `stopped`)."""
        with self._lock:
            if self._active != run_id or not self.running:
                return False
            self._stop.set()
            return True

    def list_runs(self) -> list[dict[str, Any]]:
        return self.store.list_runs()

    def get_run(self, run_id: str) -> dict[str, Any] | None:
        return self.store.get_run(run_id)

    # control -------------------------------------------------------------------------------

    def status(self) -> dict[str, Any]:
        """Flower runtime, active run, and (deployment) which Flower processes are alive,
        how the link is secured and which SuperNode keys are registered."""
        fed = self.federation
        sec = self.security
        return {
            "engine": self.flower_runtime,
            "active_run": self._active if self.running else None,
            "superlink": fed.address if fed else None,
            "fleet_address": sec.fleet_address or None,
            "tls": sec.tls,
            "supernode_auth": sec.tls and sec.supernode_auth,
            "registered_nodes": dict(fed.node_ids) if fed else {},
            "processes": fed.alive() if fed else {},
            "pids": {n: p.pid for n, p in fed.procs.items()} if fed else {},
        }

    @property
    def running(self) -> bool:
        return self._thread is not None and self._thread.is_alive()

    def wait(self, timeout: float | None = None) -> dict[str, Any] | None:
        """Block until the current run ends (or `timeout`); returns its record."""
        if self._thread is not None:
            self._thread.join(timeout)
        return self.store.get_run(self._active) if self._active else None

    def stop_run(self) -> None:
        """Ask the current run to stop (it ends as `stopped`)."""
        self._stop.set()

    def close(self) -> None:
        """Stop the current run (recorded as `stopped`) and every Flower process this
        runner started, a `flwr` call in flight included; returns within seconds."""
        self._closing = True
        self._stop.set()
        with self._lock:
            fed, self.federation = self.federation, None
        if fed is not None:
            fed.stop()  # first: a run thread blocked on a `flwr` call returns at once
        if self._thread is not None:
            self._thread.join(timeout=10)
        if self._active is not None:
            self._finish(self._active, "stopped", "the console stopped")
            self._publish_run(self._active)

    def ensure_federation(self) -> LocalFederation:
        """Start the SuperLink (with the gateway and the local SuperNodes, as the
        security settings say) unless it is already up; a local SuperNode that has ended
        is started again.

        Raises:
            DeploymentError: a Flower process did not start; PKIError: a configured
                certificate or key file cannot be used.
        """
        with self._lock:
            if self._closing:
                raise DeploymentError("the runner is closed")
            fed = self.federation
            if fed is not None and fed.core_alive():
                fed.restart_dead_supernodes()
                return fed
            if fed is not None:
                fed.stop()
            drones: list[Drone] = []
            if self.security.local_supernodes:
                drones = self._drones or default_drones(
                    self.defaults.num_drones, self.defaults.data, self.samples_db
                )
            fed_dir = self.workdir / "deployment"
            shutil.rmtree(fed_dir, ignore_errors=True)
            fed = LocalFederation(fed_dir, drones, security=self.security)
            self.federation = fed
        try:
            fed.start()
        except BaseException:
            fed.stop()
            raise
        return fed

    # running -----------------------------------------------------------------------------

    def _guard(self, target: Callable[[FLConfig], None], cfg: FLConfig) -> None:
        try:
            target(cfg)
        except Exception as exc:
            if self._closing:  # the console is stopping: its processes went first
                self._finish(cfg.run_id, "stopped", "the console stopped")
            else:
                log.exception("federated run %s failed", cfg.run_id)
                self._finish(cfg.run_id, "failed", f"{type(exc).__name__}: {exc}")
        finally:
            self._publish_run(cfg.run_id)

    def _finish(self, run_id: str, status: str, detail: str) -> None:
        row = self.store.run_row(run_id)
        if row is not None and row["status"] not in FINISHED:
            self.store.update_run(run_id, status=status, detail=detail, finished_at=time.time())

    def _simulation_run(self, cfg: FLConfig) -> None:
        from proxima.federated.simulate import simulate

        self.store.delete_run(cfg.run_id)  # simulate() records the run itself
        simulate(cfg, store=self.store, on_round=lambda row: self._publish_round(cfg, row),
                 on_status=lambda *_: self._publish_run(cfg.run_id))  # fmt: skip

    def _deployment_run(self, cfg: FLConfig) -> None:
        fed = self.ensure_federation()
        if self._stop.is_set():
            self._finish(cfg.run_id, "stopped", "stopped by request before it was submitted")
            return
        flwr_id = fed.submit(cfg)
        self.store.update_run(cfg.run_id, flwr_run_id=flwr_id, started_at=time.time())
        seen, last_state = -1, ("pending", "")
        next_flower_check = 0.0
        while True:
            row = self.store.run_row(cfg.run_id) or {}
            state = (row.get("status", ""), row.get("detail", ""))
            if state != last_state:
                last_state = state
                self._publish_run(cfg.run_id)
            for rnd in self.store.rounds(cfg.run_id, after=seen):
                seen = rnd["round"]
                self._publish_round(cfg, rnd)
            if state[0] in FINISHED:
                return
            if self._stop.is_set():
                if self._closing:  # its processes are being ended: nothing to ask them
                    self._finish(cfg.run_id, "stopped", "the console stopped")
                    return
                fed.stop_run(flwr_id)
                self._finish(cfg.run_id, "stopped", "stopped by request")
                return
            if time.monotonic() >= next_flower_check:
                next_flower_check = time.monotonic() + 5.0
                flower = self._flower_status(fed, flwr_id)
                if flower.startswith("finished"):
                    time.sleep(self.poll_s)  # let the last rows land, then one more pass
                    for rnd in self.store.rounds(cfg.run_id, after=seen):
                        seen = rnd["round"]
                        self._publish_round(cfg, rnd)
                    ok = flower == "finished:completed"
                    self._finish(cfg.run_id, "completed" if ok else "failed",
                                 f"Flower run {flwr_id}: {flower}; SuperLink log: "
                                 f"{fed.logs.get('superlink')}")  # fmt: skip
                    return
            time.sleep(self.poll_s)

    def _flower_status(self, fed: LocalFederation, flwr_id: str) -> str:
        try:
            return str(fed.run_status(flwr_id).get("status", ""))
        except (DeploymentError, OSError) as exc:
            if not self._closing:
                log.warning("cannot read Flower's status of run %s: %s", flwr_id, exc)
            return ""

    # events ----------------------------------------------------------------------------------

    def _emit(self, event: Any) -> None:
        if self.bus is not None:
            self.bus.publish(event)
        for listener in self.listeners:
            listener(event)

    def _publish_round(self, cfg: FLConfig, rnd: dict[str, Any]) -> None:
        self._emit(TrainingRoundEvent(
            t=time.time(), run_id=cfg.run_id, round=rnd["round"], rounds_total=cfg.rounds,
            global_accuracy=rnd.get("global_accuracy"), global_loss=rnd.get("global_loss"),
            train_loss=rnd.get("train_loss"), duration_s=float(rnd.get("duration_s") or 0.0),
            clients=tuple(rnd.get("clients", ())),
        ))  # fmt: skip

    def _publish_run(self, run_id: str) -> None:
        row = self.store.run_row(run_id)
        if row is None:
            return
        self._emit(TrainingRunEvent(
            t=time.time(), run_id=run_id, status=row["status"], detail=row["detail"],
            rounds_done=row["rounds_done"], rounds_total=row["rounds_total"],
            checkpoint=row["checkpoint"], final_accuracy=row["final_accuracy"],
        ))  # fmt: skip


def promote(store: TrainingStore, run_id: str, promoter: Any) -> dict[str, Any]:
    """Put a run's global model into the live engine through a `ModelPromoter`
    (e.g. proxima.api.promote.EnginePromoter): an explicit action, recorded on the run.

    Raises:
        KeyError: no such run; ValueError: the run has no usable checkpoint.
    """
    run = store.run_row(run_id)
    if run is None:
        raise KeyError(f"no training run {run_id!r}")
    ckpt = run.get("checkpoint")
    if not ckpt or not Path(ckpt).is_file():
        raise ValueError(f"run {run_id} has no checkpoint (status {run['status']})")
    result = promoter.promote(str(ckpt))
    store.update_run(run_id, promoted_at=time.time())
    return {"run_id": run_id, "checkpoint": ckpt, **result}
