"""All of Proxima's settings in one pydantic-settings class, nested per subsystem.

Sources, strongest first: keyword arguments, environment variables `PROXIMA_...` (nested
fields with a double underscore: `PROXIMA_SERVER__PORT=8100`, lists as JSON:
`PROXIMA_STREAMS='[{"name": "front", ...}]'`), a TOML file (`--config PATH`, else
`PROXIMA_CONFIG`, else `./proxima.toml` when present), then the defaults below.

Each section is the subsystem's own model, not a copy: `[[streams]]` are
`proxima.engine.StreamSpec`, `[engine]` is `proxima.engine.EngineSettings`, `[recognition]`
is `proxima.control.ControlSettings`, `[safety]` is `proxima.drone.safety.SafetyConfig`,
`[training]` is `proxima.federated.settings.TrainingSettings`.
Keys that were renamed still work for now: `DEPRECATED_KEYS` moves them to their new place
with a `DeprecationWarning` and a log line naming both.

Secrets have no default: the first supervisor comes from `PROXIMA_ADMIN_USER` /
`PROXIMA_ADMIN_PASSWORD` or gets a one-time password printed at first start, and a
well-known or short password is refused.
"""

from __future__ import annotations

import logging
import os
import tomllib
import warnings
from contextvars import ContextVar
from pathlib import Path
from typing import Any

from pydantic import BaseModel, ConfigDict, Field, SecretStr, ValidationError, model_validator
from pydantic_settings import (
    BaseSettings,
    PydanticBaseSettingsSource,
    SettingsConfigDict,
)

from proxima.control.config import ControlSettings
from proxima.drone.heading import HeadingMode
from proxima.drone.safety import SafetyConfig
from proxima.engine.config import EngineSettings, StreamSpec
from proxima.federated.settings import TrainingSettings
from proxima.shipped import STATIC_DIR, shipped_path
from proxima.sim.mount import CameraMount

log = logging.getLogger(__name__)

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


class DroneSettings(_Section):
    """One vehicle: its MAVLink connection string, where its home is in the shared world
    frame (metres, x east, y north, z up), so the 3D view can place several, which way
    it points while it flies a move (`proxima.drone.heading`) and its camera (where a
    `sim:SCENE#NAME` stream sees from, the 3D view's frustum)."""

    name: str = Field(min_length=1, pattern=r"^[A-Za-z0-9_.-]+$")
    connection: str = Field(description="udpin:127.0.0.1:14550, tcp:HOST:PORT, /dev/ttyUSB0")
    sysid: int = Field(1, ge=1, le=255)
    home: tuple[float, float, float] = (0.0, 0.0, 0.0)
    heading: HeadingMode = Field(
        "free", description="free (no yaw sent), keep, or face_operator (view.operator_position)"
    )
    camera: CameraMount = CameraMount()


class ServerSettings(_Section):
    """The console's HTTP server, its database and the 3D view.

    `tls_certfile` and `tls_keyfile` (PEM files, both or neither) switch the console to
    HTTPS. The 3D view (viser) listens on `viser_host`:`viser_port` (0: a free port picked
    at start) and is reached only through the console's `/viser/` with a login. Failed
    logins are slowed down: after `login_free_failures` failures of one user name or one
    client address, each further one blocks that key `login_backoff_s`, doubling, at most
    `login_backoff_max_s`.

    Promoting a model is refused, unless overridden with a reason, when its accuracy on
    the console's held-out set is under `promotion_min_accuracy` or more than
    `promotion_tolerance` below the model in use (overall or on wave_off, the abort).
    A drone's battery raises a warning alarm at `battery_warn_pct` and a critical one at
    `battery_critical_pct`.
    """

    host: str = "127.0.0.1"
    port: int = Field(8000, ge=0, le=65535)
    db_path: Path = Path("runs/proxima.db")
    static_dir: Path | None = None  # default: the shipped console (proxima.shipped)
    models_dir: Path = Path("models")
    session_ttl_s: float = Field(12 * 3600, gt=0)
    tls_certfile: Path | None = None
    tls_keyfile: Path | None = None
    viser_enabled: bool = True
    viser_host: str = "127.0.0.1"
    viser_port: int = Field(0, ge=0, le=65535)
    thumbnail_hz: float = Field(2.0, gt=0, description="JPEG thumbnails of camera streams")
    thumbnail_width: int = Field(320, ge=32)
    login_free_failures: int = Field(5, ge=1, le=100)
    login_backoff_s: float = Field(1.0, gt=0, le=60)
    login_backoff_max_s: float = Field(300.0, gt=0, le=3600)
    promotion_min_accuracy: float = Field(0.8, ge=0, le=1)
    promotion_tolerance: float = Field(0.02, ge=0, le=1)
    battery_warn_pct: float = Field(20.0, ge=0, le=100)
    battery_critical_pct: float = Field(10.0, ge=0, le=100)

    @model_validator(mode="after")
    def _check_tls(self) -> ServerSettings:
        if (self.tls_certfile is None) != (self.tls_keyfile is None):
            raise ValueError("set both tls_certfile and tls_keyfile, or neither")
        for name in ("tls_certfile", "tls_keyfile"):
            path = getattr(self, name)
            if path is not None and not path.is_file():
                raise ValueError(f"{name}: no such file: {path}")
        if self.login_backoff_max_s < self.login_backoff_s:
            raise ValueError("login_backoff_max_s must be at least login_backoff_s")
        if self.battery_critical_pct > self.battery_warn_pct:
            raise ValueError("battery_critical_pct must be at most battery_warn_pct")
        return self

    @property
    def tls(self) -> bool:
        """Whether the console serves HTTPS."""
        return self.tls_certfile is not None


class ViewSettings(_Section):
    """The 3D view: where the operator stands in the world frame (metres, x east, y
    north), how long drone trails are, and how often the scene is redrawn."""

    operator_position: tuple[float, float] = (0.0, 0.0)
    operator_height_m: float = Field(1.75, gt=0)
    trail_points: int = Field(300, ge=2)
    update_hz: float = Field(10.0, gt=0)


# Documented keys that were renamed, old path -> new path (section, [table,] key). Each
# still works, with a warning naming both; setting the old and the new key is an error.
DEPRECATED_KEYS: dict[tuple[str, ...], tuple[str, ...]] = {
    ("recognition", "checkpoint"): ("engine", "checkpoint"),
    ("recognition", "stride"): ("engine", "stride"),
    ("recognition", "filter_window"): ("recognition", "filter_size"),
    ("recognition", "arming_timeout_s"): ("recognition", "idle_disarm_s"),
    ("recognition", "handover_hold_s"): ("recognition", "hold_s"),
    ("recognition", "operator_lost_hover_s"): ("safety", "operator_lost_s"),
    ("safety", "min_command_interval_s"): ("safety", "min_interval_s"),
    ("safety", "geofence", "radius_m"): ("safety", "geofence_radius_m"),
    ("safety", "geofence", "min_alt_m"): ("safety", "min_altitude_m"),
    ("safety", "geofence", "max_alt_m"): ("safety", "max_altitude_m"),
    ("training", "engine"): ("training", "flower_runtime"),
}


def _key_name(path: tuple[str, ...], style: str) -> str:
    if style == "toml":
        return f"[{'.'.join(path[:-1])}] {path[-1]}"
    if style == "env":
        return "PROXIMA_" + "__".join(path).upper()
    return ".".join(path)


def _table(data: dict[str, Any], path: tuple[str, ...], create: bool = False) -> Any:
    """The nested dict at `path` (None where a level is missing or not a table)."""
    node: Any = data
    for part in path:
        if not isinstance(node, dict):
            return None
        if part not in node and create:
            node[part] = {}
        node = node.get(part)
    return node if isinstance(node, dict) else None


def _copy_tables(data: dict[str, Any]) -> dict[str, Any]:
    return {k: _copy_tables(v) if isinstance(v, dict) else v for k, v in data.items()}


def rename_deprecated_keys(data: dict[str, Any], where: str, style: str = "toml") -> dict[str, Any]:
    """A copy of `data` (one source's raw settings) with each key of `DEPRECATED_KEYS`
    moved to its new name, warning once per key (`DeprecationWarning` and a log line).
    `style` says how the message writes keys: "toml", "env" (`PROXIMA_...`) or "python".

    Raises:
        SettingsError: a deprecated key and its new name are both set (both named).
    """
    data = _copy_tables(data)
    for old, new in DEPRECATED_KEYS.items():
        parent = _table(data, old[:-1])
        if parent is None or old[-1] not in parent:
            continue
        value = parent.pop(old[-1])
        if len(old) > 2 and not parent:  # an old table ([safety.geofence]) left empty
            del _table(data, old[:-2])[old[-2]]
        old_name, new_name = _key_name(old, style), _key_name(new, style)
        target = _table(data, new[:-1], create=True)
        if target is None:
            raise SettingsError(f"{where}: {old_name} is deprecated, and {new_name} has no table")
        if new[-1] in target:
            raise SettingsError(
                f"{where}: both {old_name} (deprecated) and {new_name} are set; keep {new_name}"
            )
        target[new[-1]] = value
        message = f"{where}: {old_name} is deprecated; use {new_name}"
        warnings.warn(message, DeprecationWarning, stacklevel=2)
        log.warning(message)
    return data


_toml_path: ContextVar[Path | None] = ContextVar("proxima_toml_path", default=None)


class _RenamedKeys(PydanticBaseSettingsSource):
    """Another source's values with deprecated keys moved to their new names."""

    def __init__(self, inner: PydanticBaseSettingsSource, where: str | None, style: str) -> None:
        super().__init__(inner.settings_cls)
        self.inner, self.where, self.style = inner, where, style

    def get_field_value(self, field: Any, field_name: str) -> tuple[Any, str, bool]:
        return None, field_name, False

    def __call__(self) -> dict[str, Any]:
        where = self.where or str(_toml_path.get())
        return rename_deprecated_keys(self.inner(), where, self.style)


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

    streams: list[StreamSpec] = []
    drones: list[DroneSettings] = []
    engine: EngineSettings = EngineSettings()
    recognition: ControlSettings = ControlSettings()
    safety: SafetyConfig = SafetyConfig()
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
        return (
            _RenamedKeys(init_settings, "arguments", "python"),
            _RenamedKeys(env_settings, "environment", "env"),
            _RenamedKeys(_TomlSource(settings_cls), None, "toml"),
        )

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

    def stream(self, name: str) -> StreamSpec:
        """The stream called `name`.

        Raises:
            KeyError: no such stream.
        """
        for s in self.streams:
            if s.name == name:
                return s
        raise KeyError(name)

    def static_dir(self) -> Path:
        """Where the built frontend lies: `[server] static_dir`, else the one shipped
        with Proxima (static/ in a checkout, inside the package in a wheel)."""
        if self.server.static_dir is not None:
            return self.server.static_dir
        return shipped_path(STATIC_DIR)
