"""All of Proxima's settings in one pydantic-settings class, nested per subsystem.

Sources, strongest first: keyword arguments, environment variables `PROXIMA_...` (nested
fields with a double underscore: `PROXIMA_SERVER__PORT=8100`, lists as JSON:
`PROXIMA_STREAMS='[{"name": "front", ...}]'`), a TOML file (`--config PATH`, else
`PROXIMA_CONFIG`, else `./proxima.toml` when present), then the defaults below.

Secrets have no default: the first supervisor comes from `PROXIMA_ADMIN_USER` /
`PROXIMA_ADMIN_PASSWORD` or gets a one-time password printed at first start, and a
well-known or short password is refused.
"""

from __future__ import annotations

import os
import tomllib
from contextvars import ContextVar
from pathlib import Path
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, SecretStr, ValidationError, model_validator
from pydantic_settings import (
    BaseSettings,
    PydanticBaseSettingsSource,
    SettingsConfigDict,
)

from proxima.control.config import ConfirmByCommand, ThresholdByCommand, ThumbHand

URI_SCHEMES = ("webcam:", "file:", "rtsp://", "rtsps://", "replay:")

# Passwords anyone would try first; refused even when long enough.
WELL_KNOWN_PASSWORDS = frozenset(
    {
        "admin",
        "administrator",
        "password",
        "password1",
        "changeme",
        "change-me",
        "secret",
        "proxima",
        "supervisor",
        "12345678",
        "123456789",
        "qwertyuiop",
        "letmein",
        "default",
    }
)
MIN_PASSWORD_LENGTH = 10


class SettingsError(ValueError):
    """Settings that cannot be used; the message names the file and the field."""


def check_password_strength(password: str) -> None:
    """Raise ValueError for a password that is too short or well known.

    Raises:
        ValueError: naming the problem (never echoing the password).
    """
    if len(password) < MIN_PASSWORD_LENGTH:
        raise ValueError(f"password too short: at least {MIN_PASSWORD_LENGTH} characters")
    if password.lower() in WELL_KNOWN_PASSWORDS:
        raise ValueError("password is a well-known default; choose another")


class _Section(BaseModel):
    model_config = ConfigDict(extra="forbid")


class StreamSettings(_Section):
    """One camera stream: where frames come from and which drone's camera it is."""

    name: str = Field(min_length=1, pattern=r"^[A-Za-z0-9_.-]+$")
    uri: str = Field(description="webcam:N, file:PATH, rtsp://..., replay:PATH[@FPS]")
    drone: str = Field(min_length=1)
    priority: int = Field(0, ge=0, description="0 = main drone, 1 = secondary, ...")

    @model_validator(mode="after")
    def _check_uri(self) -> StreamSettings:
        if not self.uri.startswith(URI_SCHEMES):
            raise ValueError(
                f"stream {self.name!r}: uri {self.uri!r} must start with one of "
                + ", ".join(URI_SCHEMES)
            )
        return self

    @property
    def kind(self) -> str:
        """`replay` for landmark replays (no pixels), `camera` for everything else."""
        return "replay" if self.uri.startswith("replay:") else "camera"


class GeofenceSettings(_Section):
    """A vertical cylinder around the home point that no target may leave."""

    radius_m: float = Field(30.0, gt=0)
    min_alt_m: float = Field(1.0, ge=0)
    max_alt_m: float = Field(20.0, gt=0)

    @model_validator(mode="after")
    def _check_alt(self) -> GeofenceSettings:
        if self.max_alt_m <= self.min_alt_m:
            raise ValueError("geofence.max_alt_m must be above geofence.min_alt_m")
        return self


class DroneSettings(_Section):
    """One vehicle: its MAVLink connection string and where its home is in the shared
    world frame (metres, x east, y north, z up), so the 3D view can place several."""

    name: str = Field(min_length=1, pattern=r"^[A-Za-z0-9_.-]+$")
    connection: str = Field(description="udpin:127.0.0.1:14550, tcp:HOST:PORT, /dev/ttyUSB0")
    sysid: int = Field(1, ge=1, le=255)
    home: tuple[float, float, float] = (0.0, 0.0, 0.0)


class RecognitionSettings(_Section):
    """The decision stage: filter, threshold, debounce, arming, handover. A field left
    unset (None) keeps the live engine's tuned default (see docs/recognition.md)."""

    checkpoint: Path | None = None
    stride: int | None = Field(None, ge=1, description="classify every N frames")
    filter_window: int | None = Field(None, ge=1, description="moving average over N")
    threshold: float | None = Field(None, ge=0, le=1)
    debounce_s: float | None = Field(None, ge=0)
    arming_timeout_s: float | None = Field(None, gt=0, description="idle time to disarm")
    handover_hold_s: float | None = Field(None, ge=0)
    confirm: int | None = Field(None, ge=1, description="decisions in a row before a command")
    confirm_by_command: ConfirmByCommand | None = Field(
        None, description="decisions a command needs in a row, e.g. {land = 9}: safer landings"
    )
    threshold_by_command: ThresholdByCommand | None = Field(
        None, description="threshold per command, e.g. {wave_off = 0.7}: an easier abort"
    )
    thumb_hand: ThumbHand | None = Field(
        None, description="the hand all_clear / not_clear need in view ('off': no check)"
    )
    operator_lost_hover_s: float = Field(5.0, gt=0, description="hover after this long")


class SafetySettings(_Section):
    """Checks before any command reaches a vehicle."""

    geofence: GeofenceSettings = GeofenceSettings()
    max_step_m: float = Field(3.0, gt=0)
    min_command_interval_s: float = Field(1.0, ge=0)


class ServerSettings(_Section):
    """The console's HTTP server, its database and the 3D view."""

    host: str = "127.0.0.1"
    port: int = Field(8000, ge=0, le=65535)
    db_path: Path = Path("runs/proxima.db")
    static_dir: Path | None = None  # default: <repo>/static
    models_dir: Path = Path("models")
    session_ttl_s: float = Field(12 * 3600, gt=0)
    viser_enabled: bool = True
    viser_host: str = "127.0.0.1"
    viser_port: int = Field(8081, ge=0, le=65535)
    thumbnail_hz: float = Field(2.0, gt=0, description="JPEG thumbnails of camera streams")
    thumbnail_width: int = Field(320, ge=32)


class ViewSettings(_Section):
    """The 3D view: where the operator stands in the world frame (metres, x east, y
    north), how long drone trails are, and how often the scene is redrawn."""

    operator_position: tuple[float, float] = (0.0, 0.0)
    operator_height_m: float = Field(1.75, gt=0)
    trail_points: int = Field(300, ge=2)
    update_hz: float = Field(10.0, gt=0)


class TrainingSettings(_Section):
    """Federated runs started from the console: on Flower's deployment engine (a local
    SuperLink and one SuperNode per drone, the default) or its simulation engine."""

    enabled: bool = True
    engine: Literal["deployment", "simulation"] = "deployment"


_toml_path: ContextVar[Path | None] = ContextVar("proxima_toml_path", default=None)


class _TomlSource(PydanticBaseSettingsSource):
    """Reads the TOML file chosen by `Settings.load`; errors name the file and line."""

    def get_field_value(self, field: Any, field_name: str) -> tuple[Any, str, bool]:
        return None, field_name, False

    def __call__(self) -> dict[str, Any]:
        path = _toml_path.get()
        if path is None:
            return {}
        try:
            with open(path, "rb") as fh:
                return tomllib.load(fh)
        except FileNotFoundError as exc:
            raise SettingsError(f"{path}: settings file not found") from exc
        except tomllib.TOMLDecodeError as exc:
            raise SettingsError(f"{path}: not valid TOML: {exc}") from exc


class Settings(BaseSettings):
    """Every setting of a running Proxima (console, engine, drone links, 3D view)."""

    model_config = SettingsConfigDict(
        env_prefix="PROXIMA_",
        env_nested_delimiter="__",
        extra="forbid",
    )

    streams: list[StreamSettings] = []
    drones: list[DroneSettings] = []
    recognition: RecognitionSettings = RecognitionSettings()
    safety: SafetySettings = SafetySettings()
    server: ServerSettings = ServerSettings()
    view: ViewSettings = ViewSettings()
    training: TrainingSettings = TrainingSettings()
    admin_user: str | None = None
    admin_password: SecretStr | None = None

    @classmethod
    def settings_customise_sources(
        cls,
        settings_cls: type[BaseSettings],
        init_settings: PydanticBaseSettingsSource,
        env_settings: PydanticBaseSettingsSource,
        dotenv_settings: PydanticBaseSettingsSource,
        file_secret_settings: PydanticBaseSettingsSource,
    ) -> tuple[PydanticBaseSettingsSource, ...]:
        return (init_settings, env_settings, _TomlSource(settings_cls))

    @model_validator(mode="after")
    def _check(self) -> Settings:
        names = [s.name for s in self.streams]
        if len(set(names)) != len(names):
            raise ValueError(f"stream names must be unique, got {names}")
        drones = [d.name for d in self.drones]
        if len(set(drones)) != len(drones):
            raise ValueError(f"drone names must be unique, got {drones}")
        if self.drones:
            for s in self.streams:
                if s.drone not in drones:
                    raise ValueError(
                        f"stream {s.name!r} names drone {s.drone!r}, not one of {drones}"
                    )
        if (self.admin_user is None) != (self.admin_password is None):
            raise ValueError("set both PROXIMA_ADMIN_USER and PROXIMA_ADMIN_PASSWORD, or neither")
        if self.admin_password is not None:
            try:
                check_password_strength(self.admin_password.get_secret_value())
            except ValueError as exc:
                raise ValueError(f"admin_password refused: {exc}") from None
        return self

    @classmethod
    def load(cls, config: Path | str | None = None, **overrides: Any) -> Settings:
        """Settings from `config` (or `PROXIMA_CONFIG`, or ./proxima.toml), the environment
        and `overrides`.

        Raises:
            SettingsError: a missing or malformed file, or an invalid field (named).
        """
        path: Path | None
        if config is not None:
            path = Path(config)
        elif os.environ.get("PROXIMA_CONFIG"):
            path = Path(os.environ["PROXIMA_CONFIG"])
        else:
            path = Path("proxima.toml") if Path("proxima.toml").is_file() else None
        token = _toml_path.set(path)
        try:
            return cls(**overrides)
        except ValidationError as exc:
            where = str(path) if path else "environment"
            lines = []
            for err in exc.errors():
                loc = ".".join(str(p) for p in err["loc"]) or "settings"
                lines.append(f"{loc}: {err['msg']}")
            raise SettingsError(f"{where}: invalid settings:\n  " + "\n  ".join(lines)) from None
        finally:
            _toml_path.reset(token)

    def stream(self, name: str) -> StreamSettings:
        """The stream called `name`.

        Raises:
            KeyError: no such stream.
        """
        for s in self.streams:
            if s.name == name:
                return s
        raise KeyError(name)

    def static_dir(self) -> Path:
        """Where the built frontend lies (static/ at the repository root by default)."""
        if self.server.static_dir is not None:
            return self.server.static_dir
        return Path(__file__).resolve().parents[2] / "static"
