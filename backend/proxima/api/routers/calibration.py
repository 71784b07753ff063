"""Guided calibration of one stream's camera: a session walks the gestures (a take of
each, the model's reading of it), trains in the background, shows the model before and
after on the takes' held-out parts, and promotes the result for that stream only
(proxima.api.calibration)."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

from fastapi import APIRouter, HTTPException, status

from proxima.api.calibration import CalibrationError, CalibrationSession
from proxima.api.deps import AuditDep, ConsoleDep, CurrentUser, SupervisorUser
from proxima.api.errors import errors
from proxima.api.events import ModelEvent
from proxima.api.routers.models import _name
from proxima.api.schemas import CalibrationRequest, PromoteRequest, TakeRequest
from proxima.api.services import Console
from proxima.gesture.take_calibration import HOLDOUT_FRACTION
from proxima.store.audit import AuditAction, AuditOutcome

router = APIRouter(prefix="/calibration", tags=["calibration"])


def _out(console: Console, s: CalibrationSession) -> dict[str, Any]:
    takes = []
    for g in s.gestures:
        t = s.takes[g]
        rec = console.recorder.get(t.recording) if t.recording else None
        progress = rec.to_dict() if rec is not None and t.state == "recording" else None
        if progress is not None and rec is not None and rec.state == "countdown":
            left = rec.countdown_s - (time.time() - rec.started)
            progress["countdown_left_s"] = round(max(left, 0.0), 1)
        takes.append(
            {
                "gesture": g,
                "description": t.description,
                "state": t.state,
                "sample_id": t.sample_id,
                "replaced": t.replaced,
                "frames": t.frames,
                "detail": t.detail,
                "reading": t.reading,
                "warn": t.warn,
                "recording": progress,
            }
        )
    model = s.model
    if not model and console.promoter is not None:
        model = console.promoter.active_checkpoint(s.stream) or ""
    return {
        "id": s.id,
        "stream": s.stream,
        "drone": s.drone,
        "by": s.user,
        "created": s.created,
        "gestures": s.gestures,
        "frames": s.frames,
        "countdown_s": s.countdown_s,
        "epochs": s.epochs,
        "holdout_fraction": HOLDOUT_FRACTION,
        "state": s.state,
        "detail": s.detail,
        "epoch": s.epoch,
        "member": s.member,
        "members": s.members,
        "loss": s.loss,
        "takes": takes,
        "done": sum(1 for t in s.takes.values() if t.sample_id is not None),
        "model": _name(console, model) if model else "",
        "candidate": _name(console, s.candidate) if s.candidate else "",
        "before": s.before,
        "after": s.after,
        "seconds": s.seconds,
        "concerns": console.calibration.concerns(s),
        "promoted_by": s.promoted_by,
        "promotion_available": console.promoter is not None,
    }


def _session(console: Console, session_id: str) -> CalibrationSession:
    s = console.calibration.get(session_id)
    if s is None:
        raise HTTPException(status.HTTP_404_NOT_FOUND, f"no calibration {session_id!r}")
    return s


@router.post("", status_code=status.HTTP_201_CREATED, responses=errors(404, 409))
def start(body: CalibrationRequest, user: SupervisorUser, console: ConsoleDep) -> dict[str, Any]:
    """A new calibration of one stream's camera: a take of each gesture (default all 13)."""
    try:
        s = console.calibration.start(stream=body.stream, user=user.username,
                                      gestures=body.gestures, frames=body.frames,
                                      countdown_s=body.countdown_s, epochs=body.epochs)  # fmt: skip
    except KeyError:
        raise HTTPException(status.HTTP_404_NOT_FOUND, f"no stream {body.stream!r}") from None
    except CalibrationError as exc:
        raise HTTPException(status.HTTP_409_CONFLICT, str(exc)) from None
    return _out(console, s)


@router.get("")
def list_sessions(_: CurrentUser, console: ConsoleDep) -> list[dict[str, Any]]:
    """This server's calibrations since it started, newest first."""
    return [_out(console, s) for s in console.calibration.sessions()]


@router.get("/{session_id}", responses=errors(404))
def get_session(session_id: str, _: CurrentUser, console: ConsoleDep) -> dict[str, Any]:
    """The session: each take's state, recording progress and the model's reading of
    it (`warn` when it reads another gesture), training progress and the figures."""
    return _out(console, _session(console, session_id))


@router.post("/{session_id}/takes", status_code=status.HTTP_202_ACCEPTED,
             responses=errors(404, 409))  # fmt: skip
def record_take(
    session_id: str, body: TakeRequest, user: SupervisorUser, console: ConsoleDep, audit: AuditDep
) -> dict[str, Any]:
    """Count down and record a take of a gesture (again, to redo it: the earlier take's
    sample is marked deleted once the new one is recorded)."""
    s = _session(console, session_id)
    try:
        take = console.calibration.record(s, body.gesture, user.username)
    except ValueError as exc:  # CalibrationError, or the recorder's refusal
        raise HTTPException(status.HTTP_409_CONFLICT, str(exc)) from None
    audit(AuditAction.RECORDING_START, actor=user.username, target=s.stream,
          recording=take.recording, frames=s.frames, label=body.gesture,
          calibration=s.id)  # fmt: skip
    return _out(console, s)


@router.post("/{session_id}/train", status_code=status.HTTP_202_ACCEPTED,
             responses=errors(404, 409))  # fmt: skip
def train(
    session_id: str, user: SupervisorUser, console: ConsoleDep, audit: AuditDep
) -> dict[str, Any]:
    """Fine-tune the model the stream runs on the takes' training parts, in the
    background; follow `state`, `epoch` and then `before` / `after`."""
    s = _session(console, session_id)
    try:
        console.calibration.train(s)
    except CalibrationError as exc:
        raise HTTPException(status.HTTP_409_CONFLICT, str(exc)) from None
    audit(AuditAction.CALIBRATION_TRAIN, actor=user.username, target=s.stream,
          calibration=s.id, samples=[t.sample_id for t in s.takes.values()],
          epochs=s.epochs)  # fmt: skip
    return _out(console, s)


@router.post("/{session_id}/promote", responses=errors(404, 409, 503))
def promote(
    session_id: str,
    user: SupervisorUser,
    console: ConsoleDep,
    audit: AuditDep,
    body: PromoteRequest | None = None,
) -> dict[str, Any]:
    """Put the calibrated model into the live engine for this stream only (the others
    keep theirs); 409 when it is worse than before calibration on the held-out parts and
    no `override_reason` is given."""
    s = _session(console, session_id)
    reason = (body.override_reason or "").strip() if body else ""
    name = _name(console, s.candidate) if s.candidate else ""
    previous = console.promoter.active_checkpoint(s.stream) if console.promoter else None
    try:
        result = console.calibration.promote(s, user.username, reason)
    except RuntimeError as exc:
        raise HTTPException(status.HTTP_503_SERVICE_UNAVAILABLE, str(exc)) from None
    except ValueError as exc:
        if name:
            audit(AuditAction.MODEL_PROMOTE_STREAM, actor=user.username, target=name,
                  outcome=AuditOutcome.REFUSED, reason=str(exc), stream=s.stream)  # fmt: skip
        raise HTTPException(status.HTTP_409_CONFLICT, str(exc)) from None
    audit(
        AuditAction.MODEL_PROMOTE_STREAM,
        actor=user.username,
        target=name,
        stream=s.stream,
        calibration=s.id,
        previous=previous,
        previous_name=_name(console, previous),
        path=str(Path(s.candidate)),
        figures={"before": s.before, "after": s.after},
        concerns=console.calibration.concerns(s),
        override_reason=reason,
        pending=result.get("pending"),
    )
    console.bus.publish(
        ModelEvent(
            t=time.time(),
            checkpoint=name,
            previous=_name(console, previous),
            action="promote_stream",
            by=user.username,
        )
    )
    return {"promoted": name, "stream": s.stream, "previous": _name(console, previous),
            "by": user.username, **result}  # fmt: skip
