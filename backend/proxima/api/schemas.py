"""Request and response bodies of the console API, and the WebSocket's `hello`.

The browser's types are generated from these (FastAPI's OpenAPI) and from the event
registry: `python -m proxima.api.typegen` writes `frontend/src/types.gen.js`."""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import AfterValidator, BaseModel, ConfigDict, Field

from proxima.api.live import LiveCommand, StreamLive
from proxima.api.recorder import MAX_COUNTDOWN_S, MAX_FRAMES
from proxima.drone.events import DroneAlarmEvent, DroneStateEvent
from proxima.federated.config import (
    BatchSize,
    FractionFit,
    LearningRate,
    LocalEpochs,
    MinClients,
    Partition,
    Rounds,
    Strategy,
)
from proxima.gesture.take_calibration import MAX_EPOCHS, MIN_TAKE_FRAMES
from proxima.settings import MIN_PASSWORD_LENGTH, WELL_KNOWN_PASSWORDS, check_password_strength
from proxima.types import GESTURES

# A calibration take: 10 s at 30 fps, of which the last 90 frames are held out.
DEFAULT_TAKE_FRAMES = 300

# One of the 13 gestures, as an enum in the schema.
GestureName = Literal[GESTURES]  # type: ignore[valid-type]


def _strong(password: str) -> str:
    check_password_strength(password)
    return password


# A new password: long enough and not a well-known one (compared case-insensitively; the
# schema lists the long well-known ones, so a client can check before sending).
NewPassword = Annotated[
    str,
    Field(
        min_length=MIN_PASSWORD_LENGTH,
        max_length=256,
        description=f"at least {MIN_PASSWORD_LENGTH} characters, not a well-known password",
        json_schema_extra={
            "not": {
                "enum": sorted(p for p in WELL_KNOWN_PASSWORDS if len(p) >= MIN_PASSWORD_LENGTH)
            }
        },
    ),
    AfterValidator(_strong),
]


class _In(BaseModel):
    model_config = ConfigDict(extra="forbid")


class LoginRequest(_In):
    username: str = Field(min_length=1, max_length=64)
    password: str = Field(min_length=1, max_length=256)


class UserOut(BaseModel):
    username: str
    role: str
    must_change_password: bool = False
    disabled: bool = False


class LoginResponse(BaseModel):
    token: str
    expires_at: float
    user: UserOut


class PasswordChange(_In):
    old_password: str = Field(max_length=256)
    new_password: NewPassword


class UserCreate(_In):
    username: str = Field(min_length=1, max_length=64, pattern=r"^[A-Za-z0-9_.@-]+$")
    password: NewPassword
    role: Literal["supervisor", "viewer"]


class StreamOut(BaseModel):
    """A camera stream: its configuration (`configured` False for one only seen on the
    bus) and its newest state."""

    name: str
    uri: str
    kind: str
    drone: str
    priority: int
    configured: bool
    driving: bool
    live: StreamLive
    handover_reason: str = ""  # the newest handover's (see StreamLiveMessage)


class DroneOut(BaseModel):
    """A drone: its configuration and its newest telemetry (None before the first)."""

    name: str
    connection: str
    sysid: int
    home: tuple[float, float, float]
    configured: bool
    streams: list[str]
    driving: bool
    state: DroneStateEvent | None


class CommandLogRow(BaseModel):
    """One row of the durable command log (`proxima.store.command_log`): a command's
    whole life cycle, times in ISO 8601 UTC."""

    id: int
    created_at: str | None
    drone: str
    source: str
    command: str
    stream: str
    gesture_t: float | None
    confidence: float | None
    action: str
    status: str  # pending, sent, refused, failed, ignored, done
    reason: str
    ack: str | None
    attempts: int
    ack_latency_ms: float | None
    outcome: str | None
    sent_at: str | None
    acked_at: str | None
    completed_at: str | None


class Hello(BaseModel):
    """The WebSocket's first message: who is connected and the console's live picture
    (what `GET /streams`, `/drones` and `/commands/live` return), before any event."""

    type: Literal["hello"] = "hello"
    ts: float
    user: UserOut
    streams: list[StreamOut]
    drones: list[DroneOut]
    commands: list[LiveCommand]  # newest first
    command_log: list[CommandLogRow]  # the durable log, newest first (emergency stops too)
    alarms: list[DroneAlarmEvent]  # raised and cleared since start, newest first


class RecordingRequest(_In):
    stream: str
    frames: int = Field(60, ge=1, le=MAX_FRAMES)
    countdown_s: float = Field(3.0, ge=0, le=MAX_COUNTDOWN_S)
    label: GestureName | None = None


class SampleOut(BaseModel):
    id: int
    created_at: float
    stream: str
    drone: str
    label: str | None
    status: str
    n_frames: int
    t_start: float
    t_end: float
    created_by: str
    reviewed_by: str | None


class SampleDetail(SampleOut):
    xyz: list[list[list[float]]]
    visibility: list[list[float]]
    times: list[float]


class SampleReview(_In):
    """Keep a sample (with a gesture label, or the label it was recorded with) or delete
    it; keeping one that has no label and gets none answers 409."""

    status: Literal["kept", "deleted"]
    label: GestureName | None = None


class TrainingStart(_In):
    """A federated run's parameters: the fields of the console's form, with the types and
    bounds of `proxima.federated.config.FLConfig` (a test checks they stay equal). A
    field left out keeps the runner's default (the paper's sample-weighted FedAvg, one
    camera view per drone)."""

    rounds: Rounds | None = None
    local_epochs: LocalEpochs | None = None
    batch_size: BatchSize | None = None
    learning_rate: LearningRate | None = None
    fraction_fit: FractionFit | None = None
    min_clients: MinClients | None = None
    strategy: Strategy | None = None
    partition: Partition | None = None
    include_samples: bool | None = None


# The form's fields, in the order the Training page shows them.
TRAINING_FORM: tuple[str, ...] = tuple(TrainingStart.model_fields)


class CalibrationRequest(_In):
    """A calibration of one stream's camera: a take of each gesture (default: all 13),
    `frames` poses each after a `countdown_s`, then `epochs` of fine-tuning."""

    stream: str
    gestures: list[GestureName] | None = Field(None, min_length=1, max_length=len(GESTURES))
    frames: int = Field(DEFAULT_TAKE_FRAMES, ge=MIN_TAKE_FRAMES, le=MAX_FRAMES)
    countdown_s: float = Field(3.0, ge=0, le=MAX_COUNTDOWN_S)
    epochs: int = Field(8, ge=1, le=MAX_EPOCHS)


class TakeRequest(_In):
    gesture: GestureName


class PromoteRequest(_In):
    """A promotion's override: needed (non-empty) when the candidate is below the minimum
    accuracy or the model in use on the held-out set."""

    override_reason: str | None = Field(None, max_length=500)


class EstopConfirm(_In):
    confirmation_id: str = Field(min_length=1, max_length=128)


class RunRef(BaseModel):
    id: str


class AuditEntryOut(BaseModel):
    """One row of the audit log."""

    id: int
    ts: float = Field(description="unix time")
    actor: str = Field(description="the user name (for a failed login: the name tried)")
    action: str = Field(description="area.verb: auth.login, drone.stop, model.promote, ...")
    target: str = Field(description="what it was done to: a drone, model, run, sample, user")
    outcome: Literal["ok", "refused", "failed"]
    client: str = Field(description="the client's address")
    detail: dict[str, Any]


class AuditPage(BaseModel):
    """Audit rows, newest first; pass `next_before_id` as `before_id` for the next page
    (None: this was the last)."""

    entries: list[AuditEntryOut]
    next_before_id: int | None
