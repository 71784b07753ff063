"""Request and response bodies of the console API."""

from __future__ import annotations

from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field

from proxima.api.recorder import MAX_COUNTDOWN_S, MAX_FRAMES


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
    old_password: str
    new_password: str = Field(min_length=1, max_length=256)


class UserCreate(_In):
    username: str = Field(min_length=1, max_length=64, pattern=r"^[A-Za-z0-9_.@-]+$")
    password: str = Field(min_length=1, max_length=256)
    role: Literal["supervisor", "viewer"]


class StreamOut(BaseModel):
    name: str
    uri: str
    kind: str
    drone: str
    priority: int
    configured: bool
    driving: bool
    live: dict[str, Any]


class DroneOut(BaseModel):
    name: str
    connection: str
    sysid: int
    home: tuple[float, float, float]
    configured: bool
    streams: list[str]
    driving: bool
    state: dict[str, Any]


class RecordingRequest(_In):
    stream: str
    frames: int = Field(60, ge=1, le=MAX_FRAMES)
    countdown_s: float = Field(3.0, ge=0, le=MAX_COUNTDOWN_S)
    label: str | None = None


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
    status: Literal["kept", "deleted"]
    label: str | None = None


class TrainingStart(_In):
    """A federated run's parameters; a field left out keeps the runner's default (the
    paper's sample-weighted FedAvg, one camera view per drone)."""

    rounds: int | None = Field(None, ge=1, le=500)
    local_epochs: int | None = Field(None, ge=1, le=100)
    batch_size: int | None = Field(None, ge=1, le=4096)
    learning_rate: float | None = Field(None, gt=0, le=1)
    fraction_fit: float | None = Field(None, gt=0, le=1)
    min_clients: int | None = Field(None, ge=1, le=100)
    strategy: Literal["fedavg", "fedprox", "fedadam", "fedavgm"] | None = None
    partition: Literal["view", "iid", "dirichlet"] | None = None
    include_samples: bool | None = None


class EstopConfirm(_In):
    confirmation_id: str = Field(min_length=1, max_length=128)
