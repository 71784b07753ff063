"""A picture of the closed-loop scene: where everyone stands, each drone's camera frustum,
and what each camera sees (docs/img/sim-scene.png).

    python -m proxima.sim.picture [--out docs/img/sim-scene.png] [--seed 2]

The layout of `proxima scenario sim-handover`: the operator at the origin facing south,
the main drone 5 m in front at 2.5 m, the secondary 5 m away 45 degrees to the
operator's right, both facing the operator, and the scenario's two bystanders. Left: the
scene from above and from the side, the main drone's frustum before and after its 1 m
climb. Right: the images (every detected person's landmarks as the camera reports them,
darker where visibility is higher; the frame's edge drawn), the main camera at 2.5 m and
at 3.5 m (the feet below its lower edge), the secondary's.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from proxima.gesture.skeleton import BONES
from proxima.sim.config import DEFAULT_BYSTANDERS, OperatorConfig, SceneConfig, build_scene
from proxima.sim.mount import CameraMount
from proxima.sim.scene import Scene
from proxima.synth.camera import Camera
from proxima.synth.picture import HAND_BONES
from proxima.viz.cameras import frustum_corners

COLOURS = {"operator": "black", "bystander1": "tab:purple", "bystander2": "tab:brown"}
DRONES = {"main": "tab:blue", "main, climbed": "tab:cyan", "secondary": "tab:red"}


def handover_layout(seed: int = 2) -> tuple[Scene, dict[str, Camera]]:
    """The sim-handover scene and its three cameras (main before and after the climb,
    secondary), from the scenario's defaults."""
    from proxima.scenario.sim_handover import PLAN, SimHandoverConfig, _layout
    from proxima.sim.people import script_text
    from proxima.sim.scene import enu_to_ned

    cfg = SimHandoverConfig(seed=seed)
    scene = build_scene(
        SceneConfig(
            seed=seed,
            operator=OperatorConfig(heading_deg=180.0, script=script_text(PLAN)),
            bystanders=[DEFAULT_BYSTANDERS[1], DEFAULT_BYSTANDERS[3]],
        ),
        "picture",
    )
    specs, yaws = _layout(cfg)
    mounts = {
        "main": CameraMount(pitch_deg=cfg.pitch_deg, hfov_deg=cfg.hfov_deg),
        "secondary": CameraMount(pitch_deg=cfg.secondary_pitch_deg, hfov_deg=cfg.hfov_deg),
    }
    cams: dict[str, Camera] = {}
    for spec in specs:
        n, e, _ = enu_to_ned(spec.home)
        pos = (n, e, -cfg.altitude_m)
        cams[spec.name] = mounts[spec.name].camera(pos, (0.0, 0.0, yaws[spec.name]))
        if spec.name == "main":
            up = (n, e, -cfg.altitude_m - 1.0)
            cams["main, climbed"] = mounts["main"].camera(up, (0.0, 0.0, yaws["main"]))
    return scene, {k: cams[k] for k in DRONES}


def render(out: Path, seed: int = 2) -> Path:
    """Draw the picture and save it as a PNG."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    scene, cams = handover_layout(seed)
    # An instant of the opening hover: the operator's arms out, everyone in place.
    k = next(int(s[2]) for s in scene.operator.segments if s[0] == "hover") + 60
    people = scene.world(k)

    fig = plt.figure(figsize=(17, 9.2))
    grid = fig.add_gridspec(2, 3, width_ratios=[1.0, 1.15, 1.15], hspace=0.28, wspace=0.18)
    top = fig.add_subplot(grid[0, 0])
    side = fig.add_subplot(grid[1, 0])
    for person, world in people:
        c = COLOURS.get(person.name, "grey")
        for a, b in BONES:
            top.plot(world[[a, b], 1], world[[a, b], 0], color=c, lw=1.2)
            side.plot(world[[a, b], 0], -world[[a, b], 2], color=c, lw=1.2)
        label = "operator" if person.operator else f"{person.name} ({person.behaviour})"
        top.annotate(label, (world[0, 1], world[0, 0]), xytext=(5, 5),
                     textcoords="offset points", fontsize=8, color=c)  # fmt: skip
    for name, cam in cams.items():
        c = DRONES[name]
        fr = frustum_corners(cam, 6.0)
        # From above: the lens and the rays of the image's left and right edges.
        for i in (1, 2):
            top.plot(fr[[0, i], 1], fr[[0, i], 0], color=c, lw=1)
        top.plot(cam.position[1], cam.position[0], "o", color=c, label=name)
        if name.startswith("main"):  # from the side: the top and bottom edges
            for i in (1, 4):
                side.plot(fr[[0, i], 0], -fr[[0, i], 2], color=c, lw=1)
            side.plot(cam.position[0], -cam.position[2], "o", color=c, label=f"{name} camera")
    top.set_xlabel("east (m)")
    top.set_ylabel("north (m)")
    top.set_aspect("equal")
    top.set_xlim(-6.5, 6.5)
    top.set_ylim(-6, 5.5)
    top.grid(alpha=0.3)
    top.legend(fontsize=8, loc="lower right")
    top.set_title("from above: people, drones, each camera's horizontal field", fontsize=10)
    side.axhline(0, color="olive", lw=1)
    side.set_xlabel("north (m)")
    side.set_ylabel("up (m)")
    side.set_aspect("equal")
    side.set_xlim(-5.5, 1.5)
    side.set_ylim(-0.3, 4.2)
    side.grid(alpha=0.3)
    side.legend(fontsize=8, loc="upper right")
    side.set_title("from the side: the main camera's vertical field, 2.5 m and 3.5 m up",
                   fontsize=10)  # fmt: skip

    panels = {"main": grid[0, 1], "main, climbed": grid[1, 1], "secondary": grid[0, 2]}
    text = []
    for name, slot in panels.items():
        cam = cams[name]
        ax = fig.add_subplot(slot)
        view = scene.view(cam, k)
        size = np.array([cam.width, cam.height])
        for pv, (person, _world) in zip(view.people, people, strict=True):
            seen = pv.pose
            if seen is None:
                continue
            p = seen.xyz[:, :2] * size
            vis = seen.visibility
            c = COLOURS.get(person.name, "grey")
            for a, b in [*BONES, *HAND_BONES]:
                alpha = float(0.15 + 0.85 * min(vis[a], vis[b]))
                ax.plot(p[[a, b], 0], p[[a, b], 1], color=c, lw=1.3, alpha=alpha)
            ax.scatter(p[:, 0], p[:, 1], s=6, color=c, alpha=0.6)
        ax.add_patch(
            plt.Rectangle((0, 0), cam.width, cam.height, fill=False, lw=2, ec=DRONES[name])
        )
        ax.set_xlim(-80, cam.width + 80)
        ax.set_ylim(cam.height + 260, -60)
        ax.set_aspect("equal")
        height = -cam.position[2]
        sight = view.operator_sight.name.lower()
        ax.set_title(
            f"{name} camera at {height:.1f} m, pitch {cam.pitch_deg:.0f} deg: operator {sight}",
            fontsize=10,
        )
        ax.set_xticks([0, cam.width])
        ax.set_yticks([0, cam.height])
        n_seen = sum(pv.pose is not None for pv in view.people)
        text.append(f"{name}: {n_seen} of {len(view.people)} people detected, operator {sight}")
    note = fig.add_subplot(grid[1, 2])
    note.axis("off")
    note.text(
        0.0,
        0.95,
        "What each camera sees (frame edge drawn; landmarks outside it\n"
        "are what MediaPipe would report there, at low visibility):\n\n"
        + "\n".join(text)
        + "\n\nThe climb moves the main camera's lower edge above the\n"
        "operator's feet: the main stream sees them PARTIAL, the\n"
        "secondary FULL, and the arbiter hands control over.\n\n"
        + f"scene seed {seed}; sim-handover layout (docs/sim.md)",
        va="top",
        fontsize=10,
        family="monospace",
    )
    fig.suptitle(
        "The closed-loop simulator: the synthetic operator and bystanders seen by each "
        "drone's camera",
        fontsize=12,
    )
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=85, bbox_inches="tight")
    plt.close(fig)
    return out


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=Path("docs/img/sim-scene.png"))
    ap.add_argument("--seed", type=int, default=2)
    args = ap.parse_args(argv)
    print(render(args.out, args.seed))


if __name__ == "__main__":
    main()
