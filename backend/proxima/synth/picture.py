"""A picture of the synthetic operator through two virtual cameras (docs/img/synth-operator.png).

    python -m proxima.synth.picture [--out docs/img/synth-operator.png] [--gesture move_to_left]
        [--seed 0]

Left: the scene from above the operator's shoulder, with the operator's skeleton and the
two cameras' frusta. Middle and right: each camera's image, the landmarks as MediaPipe
would report them (the skeleton at one instant, darker where visibility is lower) and
the wrists' paths over the whole clip.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from proxima.gesture.skeleton import BONES
from proxima.synth.anthropometry import BodyShape, sample_body
from proxima.synth.body import Placement, Stance, world_landmarks
from proxima.synth.camera import Camera
from proxima.synth.motion import IDLE_LABEL, draw_gesture, perform
from proxima.synth.projection import project_landmarks
from proxima.synth.views import orbit_camera

HAND_BONES = [
    (15, 17),
    (15, 19),
    (15, 21),
    (16, 18),
    (16, 20),
    (16, 22),
    (27, 29),
    (29, 31),
    (27, 31),
    (28, 30),
    (30, 32),
    (28, 32),
    (23, 25),
    (24, 26),
]


def _frustum(cam: Camera, depth: float) -> np.ndarray:
    """(5, 3) world points: the camera centre and the four image corners `depth` ahead."""
    rot = cam.world_to_camera().T  # optical -> world
    f = cam.focal_px
    corners = [
        (-cam.width / 2, -cam.height / 2),
        (cam.width / 2, -cam.height / 2),
        (cam.width / 2, cam.height / 2),
        (-cam.width / 2, cam.height / 2),
    ]
    pts = [np.asarray(cam.position)]
    for u, v in corners:
        pts.append(np.asarray(cam.position) + rot @ (np.array([u / f, v / f, 1.0]) * depth))
    return np.array(pts)


def right_handed_operator(
    gesture: str, seed: int, idle_s: float = 0.5
) -> tuple[np.random.Generator, BodyShape, Placement, np.ndarray]:
    """The pictures' operator: a right-handed man facing north, `idle_s` of idle stance
    then `gesture`; returns the generator (for further draws), body, placement and world
    landmarks (T, 33, 3)."""
    rng = np.random.default_rng(seed)
    body = sample_body(rng, sex="male", handedness="right")
    placement = Placement(heading_deg=0.0)
    steps = [draw_gesture(IDLE_LABEL, rng, duration_s=idle_s), draw_gesture(gesture, rng)]
    perf = perform(steps, rng, head_turn_deg=0.0)
    return rng, body, placement, world_landmarks(body, perf.posture, placement, Stance())


def render(out: Path, gesture: str = "move_to_left", seed: int = 0) -> Path:
    """Draw the picture and save it as a PNG."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    _, body, placement, world = right_handed_operator(gesture, seed)
    chest = 0.55 * body.stature
    cams = {
        "front camera\nazimuth 0, elevation 5, 4 m": orbit_camera(
            placement, chest, 0.0, 5.0, 4.0, hfov_deg=65.0
        ),
        "drone camera, right and above\nazimuth 75, elevation 30, 4.5 m": orbit_camera(
            placement, chest, 75.0, 30.0, 4.5, hfov_deg=70.0
        ),
    }
    # The instant shown: the swinging wrist highest (the clearest frame of the gesture).
    t = int(np.argmin(world[:, 16, 2])) if gesture != "hover" else len(world) // 2

    fig = plt.figure(figsize=(16, 5.6))
    ax3 = fig.add_subplot(1, 3, 1, projection="3d")

    def enu(p: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return p[..., 1], p[..., 0], -p[..., 2]  # east, north, up for drawing

    pose = world[t]
    for a, b in [*BONES, *HAND_BONES]:
        ax3.plot(*enu(pose[[a, b]]), color="k", lw=1.5)
    for colour, (name, cam) in zip(("tab:blue", "tab:orange"), cams.items(), strict=True):
        fr = _frustum(cam, 1.2)
        for i in range(1, 5):
            ax3.plot(*enu(fr[[0, i]]), color=colour, lw=1)
            ax3.plot(*enu(fr[[i, i % 4 + 1]]), color=colour, lw=1)
        ax3.scatter(*enu(fr[0]), color=colour, s=30, label=name.split("\n")[0])
    ax3.set_xlabel("east (m)")
    ax3.set_ylabel("north (m)")
    ax3.set_zlabel("up (m)")
    ax3.set_xlim(-1, 4.5)
    ax3.set_ylim(-1, 4.5)
    ax3.set_zlim(0, 3.5)
    ax3.view_init(elev=22, azim=-115)
    ax3.set_title(f"scene: {gesture}, {body.stature:.2f} m, NED world", fontsize=10)
    ax3.legend(loc="upper left", fontsize=8)

    for k, (name, cam) in enumerate(cams.items()):
        seen = project_landmarks(world, cam, body)
        ax = fig.add_subplot(1, 3, k + 2)
        xy = seen.xyz[..., :2] * [cam.width, cam.height]
        for j, colour in ((15, "tab:red"), (16, "tab:blue")):
            ax.plot(xy[:, j, 0], xy[:, j, 1], color=colour, lw=0.8, alpha=0.6)
        p, vis = xy[t], seen.visibility[t]
        for a, b in [*BONES, *HAND_BONES]:
            ax.plot(
                p[[a, b], 0],
                p[[a, b], 1],
                color="k",
                lw=1.4,
                alpha=float(0.25 + 0.75 * min(vis[a], vis[b])),
            )
        sc = ax.scatter(p[:, 0], p[:, 1], c=vis, cmap="viridis", vmin=0, vmax=1, s=14, zorder=3)
        ax.set_xlim(0, cam.width)
        ax.set_ylim(cam.height, 0)
        ax.set_aspect("equal")
        ax.set_title(f"{name}, hfov {cam.hfov_deg:.0f} deg, {cam.width}x{cam.height}", fontsize=10)
        ax.set_xticks([0, cam.width // 2, cam.width])
        ax.set_yticks([0, cam.height // 2, cam.height])
    fig.colorbar(sc, ax=fig.axes[1:], fraction=0.02, label="visibility")
    fig.suptitle(
        "The synthetic operator through two virtual cameras (wrist paths over the clip: "
        "red left, blue right)",
        fontsize=11,
    )
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=90, bbox_inches="tight")
    plt.close(fig)
    return out


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=Path("docs/img/synth-operator.png"))
    ap.add_argument("--gesture", default="move_to_left")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    print(render(args.out, args.gesture, args.seed))


if __name__ == "__main__":
    main()
