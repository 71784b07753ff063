"""The flight-path picture of a scenario: a top view of every drone's path in the shared
world frame (metres, x east, y north, the operator at the origin) and each drone's
altitude over scenario time, with the commands and handovers marked."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

COLORS = ("#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e")


def world_xy(home: Sequence[float], ned: Sequence[float]) -> tuple[float, float, float]:
    """Local NED of a vehicle whose origin is `home` (world x east, y north, z up) ->
    world (x, y, z)."""
    return (home[0] + ned[1], home[1] + ned[0], home[2] - ned[2])


def plot_flight(
    out: Path,
    title: str,
    paths: Mapping[str, list[list[float]]],
    homes: Mapping[str, Sequence[float]],
    timeline: Sequence[dict[str, Any]],
    facing: Mapping[str, float] | None = None,
    expected: Mapping[str, Sequence[float]] | None = None,
    operator: Sequence[float] = (0.0, 0.0),
) -> Path:
    """Write the PNG; `paths[name]` rows are [t, north, east, down] (local NED),
    `facing[name]` a heading in radians (0 = north) drawn as the camera's direction,
    `expected[name]` a local NED point marked as the expected final position."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig = plt.figure(figsize=(14, 6.2))
    grid = fig.add_gridspec(2, 2, width_ratios=[1.0, 1.35], hspace=0.08)
    top = fig.add_subplot(grid[:, 0])
    east = fig.add_subplot(grid[0, 1])
    alt = fig.add_subplot(grid[1, 1], sharex=east)
    top.plot(*operator, marker="*", markersize=16, color="black", linestyle="none")
    top.annotate("operator", (operator[0], operator[1]), textcoords="offset points", xytext=(6, 6))
    for k, (name, rows) in enumerate(paths.items()):
        color = COLORS[k % len(COLORS)]
        home = homes.get(name, (0.0, 0.0, 0.0))
        if not rows:
            continue
        pts = [world_xy(home, r[1:4]) for r in rows]
        xs, ys = [p[0] for p in pts], [p[1] for p in pts]
        top.plot(xs, ys, color=color, linewidth=2, label=name)
        top.plot(xs[0], ys[0], marker="o", color=color, markersize=7)
        top.plot(xs[-1], ys[-1], marker="s", color=color, markersize=8, fillstyle="none", mew=2)
        if facing and name in facing:
            h = facing[name]
            top.annotate(
                "",
                xy=(xs[0] + 0.8 * math.sin(h), ys[0] + 0.8 * math.cos(h)),
                xytext=(xs[0], ys[0]),
                arrowprops={"arrowstyle": "->", "color": color},
            )
        if expected and name in expected:
            ex = world_xy(home, expected[name])
            top.plot(ex[0], ex[1], marker="x", color=color, markersize=12, mew=2)
        ts = [r[0] for r in rows]
        east.plot(ts, [p[0] for p in pts], color=color, linewidth=2, label=f"{name}")
        north = [p[1] for p in pts]
        if max(north) - min(north) > 0.05:
            east.plot(ts, north, color=color, linewidth=1.5, linestyle="--", label=f"{name} north")
        alt.plot(ts, [p[2] for p in pts], color=color, linewidth=2, label=f"{name}")
    top.set_xlabel("east (m)")
    top.set_ylabel("north (m)")
    top.set_aspect("equal", adjustable="datalim")
    top.grid(alpha=0.3)
    top.legend(loc="best", fontsize=8)
    top.set_title("top view (o start, square end, x expected end, arrow: camera)", fontsize=9)

    _shade_views(timeline, (east, alt))
    for e in timeline:
        if e.get("kind") == "command":
            who = e.get("stream") or "engine"
            for ax in (east, alt):
                ax.axvline(e["t"], color="grey", linestyle=":", linewidth=1)
            alt.annotate(
                f"{e['command']} ({who})",
                (e["t"], 0.03),
                xycoords=("data", "axes fraction"),
                rotation=90,
                fontsize=7,
                va="bottom",
                ha="right",
            )
        elif e.get("kind") == "handover" and e.get("from_stream") and e.get("to_stream"):
            for ax in (east, alt):
                ax.axvline(e["t"], color="orange", linewidth=2)
            east.annotate(
                f"handover {e['from_stream']}->{e['to_stream']}",
                (e["t"], 0.97),
                xycoords=("data", "axes fraction"),
                rotation=90,
                fontsize=7,
                va="top",
                ha="right",
                color="darkorange",
            )
    east.set_ylabel("east (m, world)")
    east.grid(alpha=0.3)
    east.legend(loc="center left", fontsize=8)
    east.tick_params(labelbottom=False)
    alt.set_xlabel("scenario time (s; negative: pre-flight take-off)")
    alt.set_ylabel("altitude (m)")
    alt.grid(alpha=0.3)
    alt.legend(loc="center left", fontsize=8)
    fig.suptitle(title)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return out


def _shade_views(timeline: Sequence[dict[str, Any]], axes: Sequence[Any]) -> None:
    """Shade the stretches in which a camera did not frame the whole operator."""
    lost: dict[str, float] = {}
    end = max((e["t"] for e in timeline if e.get("t") is not None), default=0.0)
    spans: list[tuple[str, float, float]] = []
    for e in timeline:
        if e.get("kind") != "view":
            continue
        if not e["framed"]:
            lost.setdefault(e["stream"], e["t"])
        elif e["stream"] in lost:
            spans.append((e["stream"], lost.pop(e["stream"]), e["t"]))
    spans += [(s, t0, end) for s, t0 in lost.items()]
    for k, (stream, t0, t1) in enumerate(spans):
        for ax in axes:
            label = f"{stream} camera: feet out of view" if ax is axes[0] and k == 0 else None
            ax.axvspan(t0, t1, color="purple", alpha=0.08, label=label)
