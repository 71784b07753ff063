"""Drones: configuration, newest telemetry, and the two-step emergency stop (both steps
recorded in the audit log)."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter, HTTPException, status

from proxima.api.deps import AuditDep, ConsoleDep, CurrentUser, SupervisorUser
from proxima.api.errors import errors
from proxima.api.schemas import DroneOut, EstopConfirm
from proxima.api.services import Console
from proxima.store.audit import AuditAction, AuditOutcome

router = APIRouter(prefix="/drones", tags=["drones"])


def drone_list(console: Console) -> list[DroneOut]:
    live = console.live.drones()
    driving_stream = console.live.driving_stream
    streams_of: dict[str, list[str]] = {}
    driving_drone = None
    for s in console.settings.streams:
        streams_of.setdefault(s.drone, []).append(s.name)
        if s.name == driving_stream:
            driving_drone = s.drone
    out = []
    for d in console.settings.drones:
        out.append(
            DroneOut(
                name=d.name,
                connection=d.connection,
                sysid=d.sysid,
                home=d.home,
                configured=True,
                streams=streams_of.get(d.name, []),
                driving=driving_drone == d.name,
                state=live.pop(d.name, None),
            )
        )
    for name, state in sorted(live.items()):
        out.append(
            DroneOut(
                name=name,
                connection="",
                sysid=0,
                home=(0.0, 0.0, 0.0),
                configured=False,
                streams=streams_of.get(name, []),
                driving=driving_drone == name,
                state=state,
            )
        )
    return out


def _known(console: Console, name: str) -> None:
    if name not in {d.name for d in drone_list(console)}:
        raise HTTPException(status.HTTP_404_NOT_FOUND, f"no drone {name!r}")


def _estop(console: Console) -> Any:
    if console.estop is None:
        raise HTTPException(
            status.HTTP_503_SERVICE_UNAVAILABLE,
            "no drone link runs in this server: emergency stop is unavailable",
        )
    return console.estop


@router.get("")
def list_drones(_: CurrentUser, console: ConsoleDep) -> list[DroneOut]:
    return drone_list(console)


@router.get("/{name}", responses=errors(404))
def get_drone(name: str, _: CurrentUser, console: ConsoleDep) -> DroneOut:
    for d in drone_list(console):
        if d.name == name:
            return d
    raise HTTPException(status.HTTP_404_NOT_FOUND, f"no drone {name!r}")


@router.post("/{name}/emergency-stop", responses=errors(404, 503))
def request_emergency_stop(
    name: str, user: SupervisorUser, console: ConsoleDep, audit: AuditDep
) -> dict[str, Any]:
    """Step one: nothing is stopped; returns a confirmation id that expires soon."""
    _known(console, name)
    estop = _estop(console)
    try:
        step = estop.request(name, user.username)
    except KeyError as exc:
        raise HTTPException(status.HTTP_404_NOT_FOUND, f"no drone {exc}") from None
    audit(AuditAction.DRONE_STOP_REQUEST, actor=user.username, target=name)
    return {"drone": name, "confirmed": False, **step}


@router.post("/{name}/emergency-stop/confirm", responses=errors(404, 409, 503))
def confirm_emergency_stop(
    name: str, body: EstopConfirm, user: SupervisorUser, console: ConsoleDep, audit: AuditDep
) -> dict[str, Any]:
    """Step two: with the id from step one, stop the drone; 409 for a used, wrong or
    expired id (nothing is sent)."""
    _known(console, name)
    estop = _estop(console)
    try:
        result = estop.confirm(name, body.confirmation_id, user.username)
    except PermissionError as exc:
        audit(
            AuditAction.DRONE_STOP,
            actor=user.username,
            target=name,
            outcome=AuditOutcome.REFUSED,
            reason=str(exc),
        )
        raise HTTPException(status.HTTP_409_CONFLICT, str(exc)) from None
    except KeyError as exc:
        raise HTTPException(status.HTTP_404_NOT_FOUND, f"no drone {exc}") from None
    outcome = AuditOutcome.OK if result.get("ok") else AuditOutcome.FAILED
    audit(
        AuditAction.DRONE_STOP,
        actor=user.username,
        target=name,
        outcome=outcome,
        result=str(result.get("detail", "")),
        log_id=result.get("log_id"),
    )
    return {"drone": name, "confirmed": True, **result}


@router.post("/{name}/resume", responses=errors(404, 409, 503))
def resume_drone(
    name: str, user: SupervisorUser, console: ConsoleDep, audit: AuditDep
) -> dict[str, Any]:
    """Clear a confirmed emergency stop: gesture control may be armed again by the next
    have_command (nothing is sent to the vehicle); 409 when the drone is not stopped."""
    _known(console, name)
    estop = _estop(console)
    try:
        result = estop.resume(name, user.username)
    except ValueError as exc:
        audit(AuditAction.DRONE_RESUME, actor=user.username, target=name,
              outcome=AuditOutcome.REFUSED, reason=str(exc))  # fmt: skip
        raise HTTPException(status.HTTP_409_CONFLICT, str(exc)) from None
    except KeyError as exc:
        raise HTTPException(status.HTTP_404_NOT_FOUND, f"no drone {exc}") from None
    audit(AuditAction.DRONE_RESUME, actor=user.username, target=name, log_id=result.get("log_id"))
    return {"drone": name, **result}
