"""Federated training runs: start one, cancel it, list past ones, read one's metrics;
starting and cancelling are recorded in the audit log.

The runs themselves belong to the federated subsystem, behind the TrainingRunner
interface; their per-round metrics reach the browser as bus events through the hub.
A run's parameters are bounded by its schema (`FLConfig`'s bounds); on top of that, its
minimum number of clients may not exceed the drones of the federation, which the schema
cannot know (409)."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter, HTTPException, status

from proxima.api.deps import AuditDep, ConsoleDep, CurrentUser, SupervisorUser
from proxima.api.errors import errors
from proxima.api.interfaces import TrainingRunner
from proxima.api.schemas import RunRef, TrainingStart
from proxima.api.services import Console
from proxima.store.audit import AuditAction, AuditOutcome

router = APIRouter(prefix="/training/runs", tags=["training"])


def _runner(console: Console) -> TrainingRunner:
    if console.training is None:
        raise HTTPException(
            status.HTTP_503_SERVICE_UNAVAILABLE,
            "no federated training runner in this server",
        )
    return console.training


def min_clients_problem(runner: TrainingRunner, min_clients: int | None) -> str | None:
    """Why a run with this minimum number of clients could never start, or None."""
    wanted = min_clients if min_clients is not None else runner.defaults.min_clients
    clients = runner.clients
    if wanted <= len(clients):
        return None
    return (
        f"min_clients {wanted} is more than the {len(clients)} drones of this federation "
        f"({', '.join(clients)}): each round would wait for drones that do not exist"
    )


@router.get("")
def list_runs(_: CurrentUser, console: ConsoleDep) -> list[dict[str, Any]]:
    if console.training is None:
        return []
    return console.training.list_runs()


@router.post("", status_code=status.HTTP_202_ACCEPTED, responses=errors(409, 503))
def start_run(
    body: TrainingStart, user: SupervisorUser, console: ConsoleDep, audit: AuditDep
) -> RunRef:
    """Start a federated run in the background; 409 while another runs or when
    `min_clients` is more than the drones of the federation."""
    runner = _runner(console)
    params = body.model_dump(exclude_none=True)

    def refuse(code: int, reason: str) -> HTTPException:
        audit(
            AuditAction.RUN_START,
            actor=user.username,
            outcome=AuditOutcome.REFUSED,
            reason=reason,
            params=params,
        )
        return HTTPException(code, reason)

    problem = min_clients_problem(runner, body.min_clients)
    if problem is not None:
        raise refuse(status.HTTP_409_CONFLICT, problem)
    try:
        run_id = runner.start_run({**params, "started_by": user.username})
    except ValueError as exc:  # a bound the schema does not express (none should be left)
        raise refuse(status.HTTP_422_UNPROCESSABLE_CONTENT, str(exc)) from None
    except RuntimeError as exc:  # a run is already going
        raise refuse(status.HTTP_409_CONFLICT, str(exc)) from None
    audit(AuditAction.RUN_START, actor=user.username, target=run_id, params=params)
    return RunRef(id=run_id)


@router.get("/{run_id}", responses=errors(404, 503))
def get_run(run_id: str, _: CurrentUser, console: ConsoleDep) -> dict[str, Any]:
    run = _runner(console).get_run(run_id)
    if run is None:
        raise HTTPException(status.HTTP_404_NOT_FOUND, f"no run {run_id!r}")
    return run


@router.post(
    "/{run_id}/cancel", status_code=status.HTTP_202_ACCEPTED, responses=errors(404, 409, 503)
)
def cancel_run(run_id: str, user: SupervisorUser, console: ConsoleDep, audit: AuditDep) -> RunRef:
    """Ask a running run to stop (it ends as `stopped`, reported on the WebSocket);
    409 when it is not running."""
    runner = _runner(console)
    if runner.get_run(run_id) is None:
        raise HTTPException(status.HTTP_404_NOT_FOUND, f"no run {run_id!r}")
    if not runner.cancel_run(run_id):
        audit(
            AuditAction.RUN_CANCEL,
            actor=user.username,
            target=run_id,
            outcome=AuditOutcome.REFUSED,
            reason="not running",
        )
        raise HTTPException(status.HTTP_409_CONFLICT, f"run {run_id!r} is not running")
    audit(AuditAction.RUN_CANCEL, actor=user.username, target=run_id)
    return RunRef(id=run_id)
