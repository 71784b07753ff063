"""Synthetic data sets on disk: LASER-format CSVs plus a manifest, and loading them back.

`generate` makes `clips` clips, spread evenly over the 13 gestures, in scenes of up to
13: one scene is one synthetic person (a body drawn from `anthropometry`) before one
camera (drawn from a view range, the views taken in turn), performing one gesture per
clip, each starting from a short idle stance. Clip k is gesture k mod 13 of scene
k // 13; every random draw comes from a generator seeded with (seed, scene, gesture), so
a clip does not depend on how many others are made.

Files are `DJI_<nnnnn>_<gesture>_<f|l|r>.MP4.csv` in the LASER column format (readable
by `proxima.gesture.laser.load_laser_csv`; f / l / r is the LASER view nearest to the
camera); `manifest.json` holds each scene's body, camera and placement and each clip's
drawn gesture parameters and frame spans. The loader gives the clips source `synth`,
their own subject (one per scene) and the LASER view letter, and the scene
`synth/<subject>/<view>`, which no real clip shares.
"""

from __future__ import annotations

import json
import shutil
import tempfile
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from proxima.gesture.clip import Clip, DataError
from proxima.gesture.laser import load_laser_csv
from proxima.synth.anthropometry import BodyShape, sample_body
from proxima.synth.body import Placement, Stance, world_landmarks
from proxima.synth.camera import Camera
from proxima.synth.motion import IDLE_LABEL, Performance, draw_gesture, perform
from proxima.synth.projection import ImageLandmarks, project_landmarks
from proxima.synth.views import DEFAULT_VIEWS, CameraDraw, ViewRange, sample_camera
from proxima.types import GESTURES

FORMAT = "proxima-synth/1"
MANIFEST = "manifest.json"
SOURCE = "synth"
FPS = 30.0
# Share of a gesture's clips that show its other form, where it has one (GestureSpec.variant).
VARIANT_SHARE = 0.5
CSV_HEADER = ",counter_frame,i,x,y,z,visibility"


class Seer(Protocol):
    """What reports a clip's landmarks from its world poses (T, 33, 3) and camera: the
    geometric projection (the default) or the real pose model on rendered pictures
    (`pose_model.PoseModelSeer`)."""

    def __call__(
        self, world: np.ndarray, camera: Camera, body: BodyShape, rng: np.random.Generator
    ) -> ImageLandmarks: ...

    def describe(self) -> str: ...


class GeometricSeer:
    """The exact landmarks through `projection.project_landmarks`, of each clip's first
    `max_frames` frames (all when None)."""

    def __init__(self, max_frames: int | None = None) -> None:
        if max_frames is not None and max_frames < 1:
            raise ValueError(f"max_frames must be at least 1, got {max_frames}")
        self.max_frames = max_frames

    def __call__(
        self, world: np.ndarray, camera: Camera, body: BodyShape, rng: np.random.Generator
    ) -> ImageLandmarks:
        return project_landmarks(world[: self.max_frames], camera, body)

    def describe(self) -> str:
        return "geometry"


class CaptureModel(Protocol):
    """What a camera and a pose model add to clean landmarks (jitter, dropped frames,
    ...): applied to every clip after projection, before it is written. The project's
    capture model (`proxima.gesture.capture`) plugs in here."""

    def __call__(self, clip: Clip, rng: np.random.Generator) -> Clip: ...


@dataclass(frozen=True)
class Scene:
    """One synthetic person before one camera."""

    index: int
    subject: str
    body: BodyShape
    stance: Stance
    placement: Placement
    camera: CameraDraw

    def to_dict(self) -> dict[str, object]:
        return {
            "scene": self.index,
            "subject": self.subject,
            "body": self.body.to_dict(),
            "stance": {
                "foot_width": round(self.stance.foot_width, 4),
                "toe_out_deg": round(self.stance.toe_out_deg, 2),
            },
            "placement": {
                "north": self.placement.north,
                "east": self.placement.east,
                "down": self.placement.down,
                "heading_deg": round(self.placement.heading_deg, 3),
            },
            **self.camera.to_dict(),
        }


def make_scene(
    seed: int, index: int, view: ViewRange, width: int = 1920, height: int = 1080
) -> Scene:
    """Scene `index` of a data set: its body, stance, placement and camera."""
    rng = np.random.default_rng([seed, index, 0])
    body = sample_body(rng)
    stance = Stance(
        foot_width=float(rng.uniform(0.10, 0.32)), toe_out_deg=float(rng.uniform(3, 15))
    )
    placement = Placement(heading_deg=float(rng.uniform(0, 360)))
    camera = sample_camera(view, rng, body, placement, width, height)
    return Scene(index, f"synth-s{seed}-p{index:04d}", body, stance, placement, camera)


def perform_clip(scene: Scene, gesture: str, seed: int, fps: float = FPS) -> Performance:
    """The performance of one clip: a short idle stance, then the gesture (in its other
    form, where it has one, in `VARIANT_SHARE` of the clips)."""
    g = GESTURES.index(gesture)
    rng = np.random.default_rng([seed, scene.index, 1 + g])
    # Its own draw, so that adding a variant leaves every other gesture's clips as they were.
    variant = bool(np.random.default_rng([seed, scene.index, 300 + g]).random() < VARIANT_SHARE)
    steps = [
        draw_gesture(IDLE_LABEL, rng, duration_s=float(rng.uniform(0.2, 1.0))),
        draw_gesture(gesture, rng, scene.body.handedness, variant=variant),
    ]
    # The operator looks toward the camera, partly turning the head.
    head = float(np.clip(-scene.camera.azimuth_deg * rng.uniform(0.2, 0.7), -60, 60))
    return perform(steps, rng, fps, head_turn_deg=head)


def image_clip(name: str, gesture: str, scene: Scene, seen: ImageLandmarks) -> Clip:
    """The detected frames of a projection as a Clip (frame numbers from 1, with gaps)."""
    keep = np.flatnonzero(seen.detected)
    return Clip(
        name=name,
        gesture=gesture,
        view=scene.camera.laser_view,
        subject=scene.subject,
        source=SOURCE,
        frames=keep + 1,
        xyz=seen.xyz[keep],
        visibility=seen.visibility[keep],
        aspect=seen.aspect,
    )


def write_csv(path: Path, clip: Clip) -> None:
    """One clip in the LASER column format (`,counter_frame,i,x,y,z,visibility`)."""
    n = len(clip)
    rows = np.empty((n * 33, 7))
    rows[:, 0] = np.arange(n * 33)
    rows[:, 1] = np.repeat(clip.frames, 33)
    rows[:, 2] = np.tile(np.arange(33), n)
    rows[:, 3:6] = clip.xyz.reshape(-1, 3)
    rows[:, 6] = clip.visibility.reshape(-1)
    with path.open("w", newline="") as f:
        f.write(CSV_HEADER + "\n")
        np.savetxt(f, rows, fmt="%d,%d,%d,%.6f,%.6f,%.6f,%.6f")


def file_name(number: int, gesture: str, view: str) -> str:
    return f"DJI_{number:05d}_{gesture}_{view}.MP4.csv"


def generate(
    out: str | Path,
    clips: int,
    seed: int = 0,
    views: Sequence[ViewRange] = DEFAULT_VIEWS,
    fps: float = FPS,
    resolution: tuple[int, int] = (1920, 1080),
    capture: CaptureModel | None = None,
    seer: Seer | None = None,
    overwrite: bool = False,
    on_clip: Callable[[int, str], None] | None = None,
    command: str = "",
) -> dict[str, Any]:
    """Write a synthetic data set to `out` and return its manifest.

    `seer` reports the landmarks (default: the geometric projection); the manifest names
    it. Files are written to a temporary folder beside `out` and moved into place at the
    end, so a failed run leaves nothing half-written.

    Raises:
        ValueError: `clips` under 1, no views, or `out` is a non-empty folder that is not
            a synthetic data set (or is one and `overwrite` is off).
    """
    out = Path(out)
    seer = seer or GeometricSeer()
    if clips < 1:
        raise ValueError(f"--clips must be at least 1, got {clips}")
    if not views:
        raise ValueError("at least one view is needed")
    if out.exists() and (not out.is_dir() or any(out.iterdir())):
        if not is_synth_dir(out):
            raise ValueError(f"{out}: exists and is not an empty folder or a synthetic data set")
        if not overwrite:
            raise ValueError(f"{out}: holds a synthetic data set already (use --overwrite)")
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}-", dir=out.parent))
    t0 = time.perf_counter()
    scenes: list[Scene] = []
    entries: list[dict[str, Any]] = []
    try:
        for k in range(clips):
            index, gesture = divmod(k, len(GESTURES))
            gesture_name = GESTURES[gesture]
            if index == len(scenes):
                view = views[index % len(views)]
                scenes.append(make_scene(seed, index, view, *resolution))
            scene = scenes[index]
            perf = perform_clip(scene, gesture_name, seed, fps)
            world = world_landmarks(scene.body, perf.posture, scene.placement, scene.stance)
            seen = seer(
                world,
                scene.camera.camera,
                scene.body,
                np.random.default_rng([seed, index, 200 + gesture]),
            )
            name = f"synth-s{seed}-{k + 1:05d}_{gesture_name}_{scene.camera.laser_view}"
            clip = image_clip(name, gesture_name, scene, seen)
            if capture is not None:
                clip = capture(clip, np.random.default_rng([seed, index, 100 + gesture]))
            fname = file_name(k + 1, gesture_name, scene.camera.laser_view)
            if len(clip):
                write_csv(tmp / fname, clip)
            entries.append(
                {
                    "file": fname if len(clip) else None,
                    "name": name,
                    "gesture": gesture_name,
                    "scene": index,
                    "subject": scene.subject,
                    "view": scene.camera.laser_view,
                    "view_name": scene.camera.view,
                    "frames": len(seen.detected),
                    "detected": len(clip),
                    "aspect": round(seen.aspect, 6),
                    "segments": [
                        {"label": s[0], "start": s[1], "onset": s[2], "end": s[3]}
                        for s in perf.segments
                    ],
                    "steps": [d.to_dict() for d in perf.draws],
                }
            )
            if on_clip:
                on_clip(k, gesture_name)
        manifest: dict[str, Any] = {
            "format": FORMAT,
            "command": command,
            "seed": seed,
            "clips": clips,
            "fps": fps,
            "resolution": list(resolution),
            "views": [v.spec() for v in views],
            "capture": None if capture is None else type(capture).__name__,
            "seen_by": seer.describe(),
            "seconds": round(time.perf_counter() - t0, 2),
            "scenes": [s.to_dict() for s in scenes],
            "clip_list": entries,
        }
        (tmp / MANIFEST).write_text(json.dumps(manifest, indent=1))
        if out.exists():
            shutil.rmtree(out)
        tmp.rename(out)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)
    return manifest


def is_synth_dir(path: str | Path) -> bool:
    """Whether a folder holds a synthetic data set (its manifest names the format)."""
    m = Path(path) / MANIFEST
    if not m.is_file():
        return False
    try:
        return json.loads(m.read_text()).get("format") == FORMAT
    except (OSError, ValueError, AttributeError):
        return False


def read_manifest(path: str | Path) -> dict[str, Any]:
    """The manifest of a synthetic data set.

    Raises:
        DataError: missing, unreadable, or not a synthetic data set's manifest.
    """
    m = Path(path) / MANIFEST
    try:
        manifest = json.loads(m.read_text())
    except FileNotFoundError:
        raise DataError(f"{m}: no manifest (make the data set with `proxima synth`)") from None
    except (OSError, ValueError) as exc:
        raise DataError(f"{m}: unreadable manifest ({exc})") from exc
    if not isinstance(manifest, dict) or manifest.get("format") != FORMAT:
        raise DataError(f"{m}: not a synthetic data set manifest (format {FORMAT})")
    return manifest


def load_synth_dir(path: str | Path) -> list[Clip]:
    """Every clip of a synthetic data set, through the LASER loader, with its own source,
    subject, view and image aspect from the manifest.

    Raises:
        DataError: no or bad manifest, a listed file missing or bad, or a file whose
            gesture differs from the manifest's.
    """
    path = Path(path)
    manifest = read_manifest(path)
    clips: list[Clip] = []
    for i, entry in enumerate(manifest.get("clip_list", [])):
        try:
            fname, gesture = entry["file"], entry["gesture"]
            meta = {k: entry[k] for k in ("name", "subject", "view", "aspect")}
        except (KeyError, TypeError):
            raise DataError(f"{path / MANIFEST}: clip entry {i} lacks a field") from None
        if fname is None:
            continue  # the camera never saw the person: nothing was written
        if not (path / fname).is_file():
            raise DataError(f"{path / fname}: listed in the manifest but missing")
        clip = load_laser_csv(path / fname)
        if clip.gesture != gesture:
            raise DataError(
                f"{path / fname}: gesture {clip.gesture!r} but the manifest says {gesture!r}"
            )
        clips.append(
            replace(
                clip,
                source=SOURCE,
                name=str(meta["name"]),
                subject=str(meta["subject"]),
                view=str(meta["view"]),
                aspect=float(meta["aspect"]),
            )
        )
    if not clips:
        raise DataError(f"{path}: the synthetic data set holds no clips")
    return clips
