"""What a drone camera sees of the synthetic operator, and what MediaPipe makes of it
(docs/img/synth-rendered.png).

    python -m proxima.synth.render_picture [--out docs/img/synth-rendered.png]
        [--gesture have_command] [--seed 0]

Three cameras (front, the operator's left side, above and to the right) see one
right-handed operator; each panel is the rendered picture at the same instant with the
exact landmarks (white) and MediaPipe's (red: visibility at least 0.5, yellow: below).
In the side view MediaPipe guesses the hidden far arm; that guess is what training on
rendered clips (`proxima synth --seen-by mediapipe`) teaches the classifier.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import cv2
import numpy as np

from proxima.gesture.skeleton import BONES
from proxima.synth.picture import right_handed_operator
from proxima.synth.projection import project_landmarks
from proxima.synth.render import Renderer, sample_look
from proxima.synth.views import orbit_camera


def render(out: Path, gesture: str = "have_command", seed: int = 0) -> Path:
    """Draw the picture and save it as a PNG."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from proxima.pose.estimator import PoseEstimator

    rng, body, placement, world = right_handed_operator(gesture, seed, idle_s=0.6)
    world = world[:150]
    chest = 0.55 * body.stature
    cams = {
        "front, 5 deg up, 4 m": orbit_camera(placement, chest, 0.0, 5.0, 4.0, hfov_deg=65.0),
        "operator's left, 10 deg up, 4 m": orbit_camera(
            placement, chest, -80.0, 10.0, 4.0, hfov_deg=65.0
        ),
        "right and above, 35 deg up, 5 m": orbit_camera(
            placement, chest, 50.0, 35.0, 5.0, hfov_deg=70.0
        ),
    }
    t = int(np.argmin(world[:, 16, 2]))  # the right wrist highest (NED: least down)
    ground = float(world[:, 27:33, 2].max()) + 0.02
    fig, axes = plt.subplots(1, len(cams), figsize=(12, 5.4))
    for ax, (name, cam) in zip(axes, cams.items(), strict=True):
        renderer = Renderer(cam, sample_look(rng), ground)
        with PoseEstimator(num_poses=1) as est:  # tracking over the clip, as live
            for k in range(t + 1):
                image = renderer.frame(world[k], body, rng)
                poses = est.estimate(cv2.cvtColor(image, cv2.COLOR_RGB2BGR), k / 30)
        ax.imshow(image)
        size = np.array([renderer.width, renderer.height])
        exact = project_landmarks(world[t : t + 1], cam, body).xyz[0, :, :2] * size
        for a, b in BONES:
            ax.plot(exact[[a, b], 0], exact[[a, b], 1], color="white", lw=1.2, alpha=0.8)
        if poses:
            seen = poses[0].xyz[:, :2] * size
            vis = poses[0].visibility
            for a, b in BONES:
                colour = "red" if min(vis[a], vis[b]) >= 0.5 else "yellow"
                ax.plot(seen[[a, b], 0], seen[[a, b], 1], color=colour, lw=1.6)
        lo, hi = exact.min(0), exact.max(0)
        half = 0.62 * (hi[1] - lo[1])  # a crop about the operator, 0.8 as wide as tall
        mid = (lo + hi) / 2
        ax.set_xlim(mid[0] - 0.8 * half, mid[0] + 0.8 * half)
        ax.set_ylim(mid[1] + half, mid[1] - half)
        ax.set_title(name + ("" if poses else " (MediaPipe: nobody)"), fontsize=10)
        ax.set_axis_off()
    fig.suptitle(
        f"The rendered synthetic operator ({gesture}, right-handed)\nexact landmarks white, "
        "MediaPipe's red (visibility >= 0.5) or yellow (< 0.5)",
        fontsize=11,
    )
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=90, bbox_inches="tight")
    plt.close(fig)
    return out


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=Path("docs/img/synth-rendered.png"))
    ap.add_argument("--gesture", default="have_command")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    print(render(args.out, args.gesture, args.seed))


if __name__ == "__main__":
    main()
