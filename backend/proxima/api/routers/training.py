"""Federated training runs: start one, list past ones, read one's metrics.

The runs themselves belong to the federated subsystem, behind the TrainingRunner
interface; their per-round metrics reach the browser as bus events through the hub."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter, HTTPException, status

from proxima.api.deps import ConsoleDep, CurrentUser, SupervisorUser
from proxima.api.interfaces import TrainingRunner
from proxima.api.schemas import TrainingStart
from proxima.api.services import Console

router = APIRouter(prefix="/training/runs", tags=["training"])


def _runner(console: Console) -> TrainingRunner:
    if console.training is None:
        raise HTTPException(
            status.HTTP_503_SERVICE_UNAVAILABLE,
            "no federated training runner in this server",
        )
    return console.training


@router.get("")
def list_runs(_: CurrentUser, console: ConsoleDep) -> list[dict[str, Any]]:
    if console.training is None:
        return []
    return console.training.list_runs()


@router.post("", status_code=status.HTTP_202_ACCEPTED)
def start_run(body: TrainingStart, user: SupervisorUser, console: ConsoleDep) -> dict[str, Any]:
    runner = _runner(console)
    try:
        params = body.model_dump(exclude_none=True)
        run_id = runner.start_run({**params, "started_by": user.username})
    except ValueError as exc:
        raise HTTPException(status.HTTP_422_UNPROCESSABLE_CONTENT, str(exc)) from None
    except RuntimeError as exc:  # e.g. a run is already going
        raise HTTPException(status.HTTP_409_CONFLICT, str(exc)) from None
    return {"id": run_id}


@router.get("/{run_id}")
def get_run(run_id: str, _: CurrentUser, console: ConsoleDep) -> dict[str, Any]:
    run = _runner(console).get_run(run_id)
    if run is None:
        raise HTTPException(status.HTTP_404_NOT_FOUND, f"no run {run_id!r}")
    return run
