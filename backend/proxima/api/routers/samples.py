"""Labelled samples: record from a stream, review, keep or delete (recorded in the audit
log), list."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, HTTPException, Query, status

from proxima.api.deps import AuditDep, ConsoleDep, CurrentUser, DbDep, SupervisorUser
from proxima.api.errors import errors
from proxima.api.schemas import RecordingRequest, SampleDetail, SampleOut, SampleReview
from proxima.store.audit import AuditAction
from proxima.store.samples import Sample, SampleStatus, list_samples, review_sample

router = APIRouter(prefix="/samples", tags=["samples"])


def _out(s: Sample) -> SampleOut:
    return SampleOut(
        id=s.id,
        created_at=s.created_at,
        stream=s.stream,
        drone=s.drone,
        label=s.label,
        status=s.status,
        n_frames=s.n_frames,
        t_start=s.t_start,
        t_end=s.t_end,
        created_by=s.created_by,
        reviewed_by=s.reviewed_by,
    )


@router.get("")
def get_samples(
    _: CurrentUser,
    db: DbDep,
    drone: str | None = None,
    stream: str | None = None,
    status_: Annotated[SampleStatus | None, Query(alias="status")] = None,
    limit: Annotated[int, Query(ge=1, le=1000)] = 200,
) -> list[SampleOut]:
    return [
        _out(s) for s in list_samples(db, drone=drone, stream=stream, status=status_, limit=limit)
    ]


@router.post("/recordings", status_code=status.HTTP_202_ACCEPTED, responses=errors(404, 409))
def start_recording(
    body: RecordingRequest, user: SupervisorUser, console: ConsoleDep, audit: AuditDep
) -> dict:
    """Count down, then record `frames` poses of the stream as a pending sample; progress
    arrives on the WebSocket as `recording` events and at GET /recordings/{id}. 409 while
    a recording runs on that stream."""
    try:
        stream = console.settings.stream(body.stream)
    except KeyError:
        raise HTTPException(status.HTTP_404_NOT_FOUND, f"no stream {body.stream!r}") from None
    try:
        rec = console.recorder.start(
            stream=stream.name,
            drone=stream.drone,
            frames=body.frames,
            countdown_s=body.countdown_s,
            user=user.username,
            label=body.label,
        )
    except ValueError as exc:
        raise HTTPException(status.HTTP_409_CONFLICT, str(exc)) from None
    audit(
        AuditAction.RECORDING_START,
        actor=user.username,
        target=stream.name,
        recording=rec.id,
        frames=body.frames,
        label=body.label,
    )
    return rec.to_dict()


@router.get("/recordings/{recording_id}", responses=errors(404))
def get_recording(recording_id: str, _: CurrentUser, console: ConsoleDep) -> dict:
    rec = console.recorder.get(recording_id)
    if rec is None:
        raise HTTPException(status.HTTP_404_NOT_FOUND, f"no recording {recording_id!r}")
    return rec.to_dict()


def _sample(db: DbDep, sample_id: int) -> Sample:
    s = db.get(Sample, sample_id)
    if s is None:
        raise HTTPException(status.HTTP_404_NOT_FOUND, f"no sample {sample_id}")
    return s


@router.get("/{sample_id:int}", responses=errors(404))
def get_sample(sample_id: int, _: CurrentUser, db: DbDep) -> SampleDetail:
    """A sample with its landmarks, for the skeleton playback."""
    s = _sample(db, sample_id)
    arr = s.arrays()
    return SampleDetail(
        **_out(s).model_dump(),
        xyz=arr.xyz.round(4).tolist(),
        visibility=arr.visibility.round(3).tolist(),
        times=arr.times.tolist(),
    )


@router.patch("/{sample_id:int}", responses=errors(404, 409))
def review(
    sample_id: int, body: SampleReview, user: SupervisorUser, db: DbDep, audit: AuditDep
) -> SampleOut:
    """Keep (with a gesture label) or delete a sample; 409 to keep one without a label."""
    s = _sample(db, sample_id)
    try:
        review_sample(db, s, status=body.status, label=body.label, by=user.username)
    except ValueError as exc:
        raise HTTPException(status.HTTP_409_CONFLICT, str(exc)) from None
    action = AuditAction.SAMPLE_KEEP if body.status == "kept" else AuditAction.SAMPLE_DELETE
    audit(action, actor=user.username, target=str(s.id), label=s.label, drone=s.drone)
    return _out(s)


@router.get("/{sample_id:int}/reading", responses=errors(404))
def reading(sample_id: int, _: CurrentUser, db: DbDep, console: ConsoleDep) -> dict[str, Any]:
    """What the model in use (else the shipped one) reads in the sample: the mean of its
    probabilities over the sample's windows (a sample shorter than the model's window is
    padded with its first frame), the top gesture and each gesture's probability, so the
    console can warn when it disagrees with the label chosen."""
    from proxima.api.reading import model_in_use, model_reading
    from proxima.api.routers.models import _name

    s = _sample(db, sample_id)
    clf, path = model_in_use(console)
    return {"sample": sample_id, "model": _name(console, path),
            **model_reading(clf, s.arrays().xyz)}  # fmt: skip
