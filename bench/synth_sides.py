"""How often does MediaPipe read the rendered operator as facing away (left and right
swapped), and does `proxima.synth.pose_model.match_sides` undo it?

Synthetic clips are rendered and passed through MediaPipe (`proxima synth --seen-by
mediapipe --sides mediapipe`, the same code); each clip's landmarks are compared with the
exact projection of the same frames. A frame counts as swapped when the mirrored
labelling lies clearly closer to the truth (`match_sides`'s rule). Beside it, for the
front views, the share of frames whose shoulders are in the wrong order (the operator's
left shoulder on the image's left), the same measure as on LASER's real front view.

    python -m bench.synth_sides [--clips 39] [--seed 20] [--max-frames 180]

Writes bench/results/synth_sides.json. About 40 ms a frame.
"""

from __future__ import annotations

import argparse
import json
import shlex
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from proxima.gesture.data_source import resolve_laser_dir
from proxima.gesture.laser import load_laser_dir
from proxima.synth.anthropometry import BodyShape
from proxima.synth.camera import Camera
from proxima.synth.dataset import generate
from proxima.synth.pose_model import PoseModelSeer, match_sides
from proxima.synth.projection import ImageLandmarks, project_landmarks

RESULTS = Path(__file__).resolve().parent / "results"
REVERSED = ("shoulders_reversed", "shoulders_reversed_after", "shoulders_reversed_exact")


def shoulders_reversed(xyz: np.ndarray) -> np.ndarray:
    """(T,) whether the operator's left shoulder (11) lies left of the right one (12) in
    the image: a person facing the camera has it on the right."""
    return xyz[:, 11, 0] < xyz[:, 12, 0]


class ProbedSeer:
    """MediaPipe's landmarks as they come, with each clip's swap figures recorded."""

    def __init__(self, seer: PoseModelSeer) -> None:
        self.seer = seer
        self.clips: list[dict[str, float]] = []

    def describe(self) -> str:
        return self.seer.describe()

    def __call__(
        self, world: np.ndarray, camera: Camera, body: BodyShape, rng: np.random.Generator
    ) -> ImageLandmarks:
        seen = self.seer(world, camera, body, rng)
        exact = project_landmarks(world[: len(seen.xyz)], camera, body)
        fixed, swapped = match_sides(seen, exact)
        found = seen.detected

        def error(xyz: np.ndarray) -> float:
            gap = np.linalg.norm(xyz[found, :, :2] - exact.xyz[found, :, :2], axis=-1)
            return float(np.median(gap)) if found.any() else float("nan")

        self.clips.append(
            {
                "frames": int(found.sum()),
                "swapped": int(swapped.sum()),
                "shoulders_reversed": int(shoulders_reversed(seen.xyz)[found].sum()),
                "shoulders_reversed_after": int(shoulders_reversed(fixed.xyz)[found].sum()),
                "shoulders_reversed_exact": int(shoulders_reversed(exact.xyz)[found].sum()),
                "median_error": error(seen.xyz),
                "median_error_after": error(fixed.xyz),
            }
        )
        return seen


def real_shoulders() -> dict[str, dict[str, float]]:
    """LASER's real clips, per view: the share of frames with the shoulders reversed."""
    clips = load_laser_dir(resolve_laser_dir())
    out: dict[str, dict[str, float]] = {}
    for view in ("f", "l", "r"):
        rows = [shoulders_reversed(c.xyz) for c in clips if c.view == view]
        flat = np.concatenate(rows)
        out[view] = {"frames": len(flat), "shoulders_reversed": round(float(flat.mean()), 4)}
    return out


def summarise(clips: list[dict[str, Any]]) -> dict[str, Any]:
    frames = sum(c["frames"] for c in clips)

    def share(key: str) -> float:
        return round(sum(c[key] for c in clips) / max(frames, 1), 4)

    def median(key: str) -> float:
        return round(float(np.nanmedian([c[key] for c in clips])), 4)

    return {
        "clips": len(clips),
        "frames": frames,
        "swapped": share("swapped"),
        "clips_over_10_percent": sum(c["swapped"] > 0.1 * max(c["frames"], 1) for c in clips),
        **{k: share(k) for k in REVERSED},
        "median_error": median("median_error"),
        "median_error_after": median("median_error_after"),
    }


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--clips", type=int, default=39, help="clips in all (13 per default view)")
    ap.add_argument("--seed", type=int, default=20)
    ap.add_argument("--max-frames", type=int, default=180)
    ap.add_argument("--out", type=Path, default=RESULTS / "synth_sides.json")
    args = ap.parse_args(argv)
    from rich.progress import Progress

    probe = ProbedSeer(PoseModelSeer(max_frames=args.max_frames, sides="mediapipe"))
    start = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp, Progress() as progress:
        task = progress.add_task("rendering and seeing", total=args.clips)
        manifest = generate(
            Path(tmp) / "set",
            args.clips,
            args.seed,
            seer=probe,
            on_clip=lambda k, _g: progress.update(task, completed=k + 1),
        )
    seconds = time.perf_counter() - start
    views: dict[str, list[dict[str, Any]]] = {}
    for entry, figures in zip(manifest["clip_list"], probe.clips, strict=True):
        views.setdefault(entry["view_name"], []).append({"gesture": entry["gesture"], **figures})
    result = {
        "benchmark": "MediaPipe's left/right swaps on the rendered operator (issue 22)",
        "command": "python -m bench.synth_sides " + shlex.join(sys.argv[1:]),
        "date": time.strftime("%Y-%m-%d"),
        "seed": args.seed,
        "max_frames": args.max_frames,
        "views": manifest["views"],
        "seen_by": probe.describe(),
        "rendered": {view: summarise(clips) for view, clips in views.items()},
        "laser_real": real_shoulders(),
        "seconds": round(seconds, 1),
        "per_clip": views,
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=1))
    for view, row in result["rendered"].items():
        print(
            f"{view:6s} swapped {row['swapped']:.3f} of {row['frames']} frames; shoulders "
            f"reversed {row['shoulders_reversed']:.3f} -> {row['shoulders_reversed_after']:.3f}"
            f" (exact {row['shoulders_reversed_exact']:.3f}); median error "
            f"{row['median_error']:.4f} -> {row['median_error_after']:.4f}"
        )
    print("LASER real, shoulders reversed:", result["laser_real"])
    print(f"wrote {args.out} ({seconds:.0f} s)")


if __name__ == "__main__":
    main()
