"""The simulated scenes and camera-carrying vehicles of this process.

One scene object per scene: every `sim:` stream naming the same scene with the same
scene keys gets the same `Scene` (one operator, one clock), whichever engine or thread
opens it. Vehicles are registered by whoever owns their links (the console's runtime,
the demo, a scenario), with where their local origin sits in the scene and their camera
mount; a `sim:SCENE#DRONE` stream then sees from where that vehicle is.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from proxima.drone.link import Telemetry
from proxima.ingest.base import SourceError
from proxima.shipped import shipped_path
from proxima.sim.config import (
    DEFAULT_BYSTANDERS,
    OperatorConfig,
    SceneConfig,
    SceneFileError,
    build_scene,
    load_scene_config,
)
from proxima.sim.mount import CameraMount
from proxima.sim.scene import Scene, enu_to_ned
from proxima.sim.uri import SimUri
from proxima.synth.camera import Camera

BUILTIN = "operator"


@dataclass(frozen=True)
class MountedVehicle:
    """A vehicle whose camera a `sim:SCENE#NAME` stream looks through: `telemetry()` its
    newest telemetry, `home_ned` its local origin in the scene, `mount` its camera."""

    name: str
    telemetry: Callable[[], Telemetry | None]
    home_ned: tuple[float, float, float]
    mount: CameraMount

    def camera(self) -> Camera | None:
        """The camera where the vehicle is now (None before its first position)."""
        tel = self.telemetry()
        return None if tel is None else self.mount.camera_for(tel, self.home_ned)


_lock = threading.Lock()
_scenes: dict[tuple[str, tuple[tuple[str, str], ...]], Scene] = {}
_named: dict[str, Scene] = {}
_vehicles: dict[str, MountedVehicle] = {}


def register_scene(name: str, scene: Scene) -> None:
    """Make `scene` what `sim:NAME` opens in this process (replacing one of that name)."""
    with _lock:
        _named[name] = scene


def unregister_scene(name: str) -> None:
    with _lock:
        _named.pop(name, None)


def register_vehicle(
    name: str,
    telemetry: Callable[[], Telemetry | None],
    home_ned: Sequence[float],
    mount: CameraMount | None = None,
) -> MountedVehicle:
    """Let `sim:...#NAME` streams see through this vehicle's camera."""
    home = (float(home_ned[0]), float(home_ned[1]), float(home_ned[2]))
    v = MountedVehicle(name, telemetry, home, mount or CameraMount())
    with _lock:
        _vehicles[name] = v
    return v


def register_links(links: Mapping[str, Any], drones: Sequence[Any]) -> list[str]:
    """Register the camera of every configured drone (`proxima.settings.DroneSettings`:
    name, `home` in the console's ENU frame, `camera` mount) that has a link in `links`;
    the names registered."""
    names = []
    for d in drones:
        link = links.get(d.name)
        if link is None:
            continue
        register_vehicle(d.name, link.telemetry, enu_to_ned(d.home), d.camera)
        names.append(d.name)
    return names


def unregister_vehicle(name: str) -> None:
    with _lock:
        _vehicles.pop(name, None)


def vehicle(name: str) -> MountedVehicle | None:
    with _lock:
        return _vehicles.get(name)


def vehicles() -> dict[str, MountedVehicle]:
    with _lock:
        return dict(_vehicles)


def scenes() -> list[Scene]:
    """Every scene opened or registered in this process."""
    with _lock:
        return list({id(s): s for s in [*_named.values(), *_scenes.values()]}.values())


def reset() -> None:
    """Forget every scene and vehicle (tests; a process that starts over)."""
    with _lock:
        _scenes.clear()
        _named.clear()
        _vehicles.clear()


def _config(uri: SimUri) -> tuple[str, SceneConfig]:
    if uri.scene == BUILTIN:
        return BUILTIN, SceneConfig()
    path = Path(uri.scene)
    if path.suffix != ".toml":
        raise SourceError(
            f"{uri.uri}: no scene {uri.scene!r}: use {BUILTIN}, a scene file (.toml) or the "
            "name of a registered scene"
        )
    if not path.is_absolute() and not path.exists():
        # A shipped scene (config/scenes/...), as an installed wheel carries it.
        shipped = shipped_path(uri.scene)
        path = shipped if shipped.is_file() else path
    try:
        return str(path.resolve()), load_scene_config(path)
    except SceneFileError as exc:
        raise SourceError(f"{uri.uri}: {exc}") from None


def scene_for(uri: SimUri) -> Scene:
    """The scene a URI names, made on first use and shared after.

    Raises:
        SourceError: no such scene, a bad scene file, or scene keys on a registered scene.
    """
    with _lock:
        named = _named.get(uri.scene)
    if named is not None:
        if uri.scene_options:
            raise SourceError(
                f"{uri.uri}: scene {uri.scene!r} was registered by this process; its scene "
                f"keys ({', '.join(k for k, _ in uri.scene_options)}) cannot change it"
            )
        return named
    source, cfg = _config(uri)
    key = (source, uri.scene_options)
    with _lock:
        scene = _scenes.get(key)
        if scene is not None:
            return scene
    opts = dict(uri.scene_options)
    update: dict[str, Any] = {}
    if "seed" in opts:
        update["seed"] = int(opts["seed"])
    if "loop" in opts:
        update["loop"] = opts["loop"] == "1"
    if "fps" in opts:
        update["fps"] = float(opts["fps"])
    if "script" in opts:
        update["operator"] = OperatorConfig(
            **{**cfg.operator.model_dump(), "script": opts["script"]}
        )
    if "bystanders" in opts:
        update["bystanders"] = [*cfg.bystanders, *DEFAULT_BYSTANDERS[: int(opts["bystanders"])]]
    cfg = cfg.model_copy(update=update)
    name = (
        uri.scene
        if not uri.scene_options
        else f"{uri.scene}?" + "&".join(f"{k}={v}" for k, v in uri.scene_options)
    )
    built = build_scene(cfg, name)
    with _lock:
        return _scenes.setdefault(key, built)  # a racing opener's scene wins: one per key
