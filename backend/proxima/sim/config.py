"""Scene files: a TOML description of a simulated scene, validated, and the scene built
from it.

    fps = 30                     # frames a second of every stream of the scene
    seed = 0                     # every random draw (bodies, motion, noise)
    loop = true                  # repeat the script (a demo); false: streams end with it

    [operator]
    north = 0.0                  # where they stand (NED metres) and which way they face
    east = 0.0
    heading_deg = 180.0          # clockwise from north: 180 faces south
    script = "hover:4,have_command:4,move_to_left:4"

    [capture]                    # the live pose path's noise (x the measured; 0 = none)
    jitter = 1.0
    visibility_noise = 1.0
    depth_jitter = 1.0           # z's jitter against x and y's (x the measured ratio, 23)

    [[bystanders]]               # people who do not command the drones
    behaviour = "walk"           # stand | arms | walk | gestures
    north = -3.0
    east = -4.0
    heading_deg = 90.0
    to = [-3.0, 4.0]             # walk: the path's other end
    speed_m_s = 1.2
    # script = "wave_off:3"      # gestures: what they signal (to someone else)

Every field has the default shown; a bad file is refused naming the file and the field.
"""

from __future__ import annotations

import tomllib
from pathlib import Path
from typing import Any, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator

from proxima.sim.noise import CaptureNoise
from proxima.sim.people import bystander, operator, parse_script
from proxima.sim.scene import Scene
from proxima.synth.body import Placement

DEFAULT_SCRIPT = (
    "hover:4,have_command:4,move_to_left:4,move_to_right:4,move_upward:4,move_downward:4,wave_off:4"
)


class SceneFileError(ValueError):
    """A scene file that cannot be used; the message names the file and the field."""


class _Model(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid")


class OperatorConfig(_Model):
    north: float = 0.0
    east: float = 0.0
    heading_deg: float = 180.0
    script: str | list[tuple[str, float]] = DEFAULT_SCRIPT

    @field_validator("script")
    @classmethod
    def _script(cls, v: Any) -> Any:
        parse_script(v)  # ScriptError is a ValueError: pydantic reports it on the field
        return v


class CaptureConfig(_Model):
    jitter: float = Field(1.0, ge=0.0, le=8.0)
    visibility_noise: float = Field(1.0, ge=0.0, le=4.0)
    depth_jitter: float = Field(1.0, ge=0.0, le=8.0)


class BystanderConfig(_Model):
    behaviour: Literal["stand", "arms", "walk", "gestures"] = "stand"
    north: float = 0.0
    east: float = 0.0
    heading_deg: float = 180.0
    to: tuple[float, float] | None = None
    speed_m_s: float = Field(1.2, ge=0.3, le=2.5)
    script: str = ""

    @field_validator("script")
    @classmethod
    def _script(cls, v: str) -> str:
        if v:
            parse_script(v)
        return v


class SceneConfig(_Model):
    fps: float = Field(30.0, gt=0.0, le=120.0)
    seed: int = 0
    loop: bool = False
    operator: OperatorConfig = OperatorConfig()
    capture: CaptureConfig = CaptureConfig()
    bystanders: list[BystanderConfig] = []


# Bystanders the `bystanders=N` option adds, in this order, placed around an operator at
# the origin facing south (heading 180): beside them on their left moving their arms,
# walking past behind them, standing on their right, signalling to someone else.
DEFAULT_BYSTANDERS: tuple[BystanderConfig, ...] = (
    BystanderConfig(behaviour="arms", north=1.0, east=2.6, heading_deg=200.0),
    BystanderConfig(behaviour="walk", north=4.0, east=-5.0, heading_deg=90.0, to=(4.0, 5.0)),
    BystanderConfig(behaviour="stand", north=1.5, east=-3.0, heading_deg=150.0),
    BystanderConfig(
        behaviour="gestures",
        north=3.0,
        east=3.5,
        heading_deg=90.0,
        script="wave_off:4,move_ahead:4,land:4,move_to_left:4",
    ),
)


def load_scene_config(path: str | Path) -> SceneConfig:
    """Read and validate a scene file.

    Raises:
        SceneFileError: missing, not TOML, or a field that is not valid (named).
    """
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text())
    except FileNotFoundError:
        raise SceneFileError(f"{path}: no such scene file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise SceneFileError(f"{path}: cannot read: {exc}") from None
    except tomllib.TOMLDecodeError as exc:
        raise SceneFileError(f"{path}: not valid TOML: {exc}") from None
    try:
        return SceneConfig(**data)
    except ValidationError as exc:
        lines = [
            f"{'.'.join(str(p) for p in e['loc']) or 'scene'}: {e['msg']}" for e in exc.errors()
        ]
        raise SceneFileError(f"{path}: invalid scene:\n  " + "\n  ".join(lines)) from None


def build_scene(cfg: SceneConfig, name: str) -> Scene:
    """The scene a configuration describes: the operator's performance sets its length;
    every bystander moves for as many frames."""
    rng = np.random.default_rng([cfg.seed, 0])
    op = cfg.operator
    placement = Placement(op.north, op.east, 0.0, op.heading_deg)
    person = operator(parse_script(op.script), placement, rng, cfg.fps)
    people = [person]
    frames = len(person.world)
    for i, b in enumerate(cfg.bystanders, start=1):
        brng = np.random.default_rng([cfg.seed, i])
        people.append(
            bystander(
                f"bystander{i}",
                b.behaviour,
                Placement(b.north, b.east, 0.0, b.heading_deg),
                frames,
                brng,
                cfg.fps,
                to=b.to,
                speed_m_s=b.speed_m_s,
                steps=parse_script(b.script) if b.script else (),
            )
        )
    noise = CaptureNoise(cfg.capture.jitter, cfg.capture.visibility_noise, cfg.capture.depth_jitter)
    return Scene(name, people, cfg.fps, cfg.loop, noise, cfg.seed)
