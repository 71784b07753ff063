"""The `sim:` stream URI: which scene, which camera.

    sim:SCENE[?KEY=VALUE&...][#DRONE]

SCENE is `operator` (the built-in scene: the operator alone, at the origin facing
south), a scene file (`config/scenes/demo.toml`, see `proxima.sim.config`), or the name
of a scene a program registered (`proxima.sim.registry.register_scene`, as the
scenarios do). `#DRONE` is the camera carried by the drone of that name (its link and
mount registered in this process, as the console and the demo do for their drones);
without it the camera stands still where the keys put it.

Keys of the scene (streams with the same scene and the same scene keys share one scene
object, so one operator and one clock):
- `script=GESTURE:SECONDS,...` the operator's script (`idle` for a still stance);
- `seed=N`, `loop=0|1`, `fps=F`;
- `bystanders=N` adds N of the default bystanders (0..4: arms, walker, standing,
  signalling to someone else).

Keys of the camera (each stream its own):
- `at=NORTH,EAST,HEIGHT` a fixed camera (metres; height above the ground), default 5 m
  in front of the operator at 1.8 m; `look=NORTH,EAST,HEIGHT` what it aims at (default:
  the operator's chest), or `yaw=DEG&pitch=DEG` (clockwise from north; up positive),
  `roll=DEG`; `hfov=DEG` (70), `size=WIDTHxHEIGHT` (1280x720);
- `jitter=X`, `visnoise=X`, `zjitter=X`: the live pose path's noise, times the measured
  (x and y jitter, visibility noise, z's jitter ratio; the scene file's, else 1; 0 =
  none).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from proxima.ingest.base import SourceError

SCENE_KEYS = ("script", "seed", "loop", "fps", "bystanders")
CAMERA_KEYS = (
    "at",
    "look",
    "yaw",
    "pitch",
    "roll",
    "hfov",
    "size",
    "jitter",
    "visnoise",
    "zjitter",
)
MAX_BYSTANDERS = 4


@dataclass(frozen=True)
class SimUri:
    """A parsed `sim:` URI (see the module)."""

    uri: str
    scene: str
    scene_options: tuple[tuple[str, str], ...] = ()
    drone: str | None = None
    at: tuple[float, float, float] | None = None  # north, east, height
    look: tuple[float, float, float] | None = None
    yaw_deg: float | None = None
    pitch_deg: float | None = None
    roll_deg: float = 0.0
    hfov_deg: float = 70.0
    size: tuple[int, int] = (1280, 720)
    jitter: float | None = None
    visibility_noise: float | None = None
    depth_jitter: float | None = None

    def option(self, key: str) -> str | None:
        return dict(self.scene_options).get(key)


def _fail(uri: str, problem: str) -> SourceError:
    return SourceError(f"{uri}: {problem} (sim:SCENE[?KEY=VALUE&...][#DRONE], docs/sim.md)")


def _number(uri: str, key: str, text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise _fail(uri, f"{key}={text!r} is not a number") from None
    if not math.isfinite(v):
        raise _fail(uri, f"{key}={text!r} is not finite")
    return v


def _triple(uri: str, key: str, text: str) -> tuple[float, float, float]:
    parts = text.split(",")
    if len(parts) != 3:
        raise _fail(uri, f"{key}={text!r}: expected NORTH,EAST,HEIGHT")
    n, e, h = (_number(uri, key, p) for p in parts)
    return (n, e, h)


def parse_sim_uri(uri: str) -> SimUri:
    """Parse a `sim:` URI (see the module).

    Raises:
        SourceError: not a sim URI, no scene, an unknown key, or a value that is not
            valid (the message names the key).
    """
    if not uri.startswith("sim:"):
        raise _fail(uri, "not a sim: URI")
    rest = uri[len("sim:") :]
    rest, _, drone = rest.partition("#")
    scene, _, query = rest.partition("?")
    scene = scene.strip()
    if not scene:
        raise _fail(uri, "no scene (e.g. sim:operator)")
    if drone and not all(c.isalnum() or c in "_.-" for c in drone):
        raise _fail(uri, f"drone name {drone!r} may hold letters, digits, _ . - only")
    fields: dict[str, object] = {}
    scene_opts: dict[str, str] = {}
    for item in filter(None, query.split("&")):
        key, sep, value = item.partition("=")
        if not sep or not value:
            raise _fail(uri, f"{item!r}: expected KEY=VALUE")
        if key in scene_opts or key in fields:
            raise _fail(uri, f"{key} given twice")
        if key in SCENE_KEYS:
            scene_opts[key] = _scene_value(uri, key, value)
        elif key in ("at", "look"):
            fields[key] = _triple(uri, key, value)
        elif key in ("yaw", "pitch", "roll"):
            fields[f"{key}_deg"] = _number(uri, key, value)
        elif key == "hfov":
            hfov = _number(uri, key, value)
            if not 10 <= hfov <= 150:
                raise _fail(uri, f"hfov={value}: must lie in 10..150 degrees")
            fields["hfov_deg"] = hfov
        elif key == "size":
            w, _, h = value.lower().partition("x")
            if not (w.isdigit() and h.isdigit() and 16 <= int(w) <= 8192 and 16 <= int(h) <= 8192):
                raise _fail(uri, f"size={value!r}: expected WIDTHxHEIGHT, e.g. 1280x720")
            fields["size"] = (int(w), int(h))
        elif key == "jitter":
            fields["jitter"] = _bounded(uri, key, value, 8.0)
        elif key == "visnoise":
            fields["visibility_noise"] = _bounded(uri, key, value, 4.0)
        elif key == "zjitter":
            fields["depth_jitter"] = _bounded(uri, key, value, 8.0)
        else:
            known = ", ".join(SCENE_KEYS + CAMERA_KEYS)
            raise _fail(uri, f"unknown key {key!r}; known: {known}")
    if drone and any(k in fields for k in ("at", "look", "yaw_deg", "pitch_deg", "roll_deg")):
        raise _fail(
            uri,
            f"#{drone}: the drone's camera goes where the drone goes; drop at/look/yaw/pitch/roll",
        )
    if "look" in fields and ("yaw_deg" in fields or "pitch_deg" in fields):
        raise _fail(uri, "give look= or yaw=/pitch=, not both")
    return SimUri(
        uri,
        scene,
        tuple(sorted(scene_opts.items())),
        drone or None,
        **fields,  # type: ignore[arg-type]
    )


def _bounded(uri: str, key: str, value: str, hi: float) -> float:
    v = _number(uri, key, value)
    if not 0 <= v <= hi:
        raise _fail(uri, f"{key}={value}: must lie in 0..{hi:g} (x the measured)")
    return v


def _scene_value(uri: str, key: str, value: str) -> str:
    """A scene key's value, checked (and normalised so equal scenes share one key)."""
    if key == "seed":
        if not value.lstrip("-").isdigit():
            raise _fail(uri, f"seed={value!r} is not an integer")
        return str(int(value))
    if key == "loop":
        if value not in ("0", "1", "true", "false"):
            raise _fail(uri, f"loop={value!r}: expected 0 or 1")
        return "1" if value in ("1", "true") else "0"
    if key == "fps":
        fps = _number(uri, key, value)
        if not 1 <= fps <= 120:
            raise _fail(uri, f"fps={value}: must lie in 1..120")
        return f"{fps:g}"
    if key == "bystanders":
        if not value.isdigit() or int(value) > MAX_BYSTANDERS:
            raise _fail(uri, f"bystanders={value!r}: expected 0..{MAX_BYSTANDERS}")
        return str(int(value))
    from proxima.sim.people import ScriptError, parse_script, script_text

    try:
        return script_text(parse_script(value))
    except ScriptError as exc:
        raise _fail(uri, f"script: {exc}") from None
