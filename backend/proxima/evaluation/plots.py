"""The evaluation's pictures: latency distribution, latency per gesture and view, where
the time goes, the confusion matrix, still stances and temporal-split errors. matplotlib
is imported only when a picture is drawn."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from proxima.evaluation.latency import STAGES, VIEWS
from proxima.gesture.skeleton import BONES
from proxima.types import GESTURES

if TYPE_CHECKING:
    from types import ModuleType

    from proxima.gesture.clip import Clip


def _pyplot() -> ModuleType:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_latency(latencies: Sequence[float], path: Path, title: str) -> None:
    """Histogram of onset -> command latencies with their median, p95 and the 2.5 s target."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6, 3.5))
    ax.hist(latencies, bins=40, color="#4477aa")
    lat = np.asarray(latencies)
    for q, style in ((50, "-"), (95, "--")):
        ax.axvline(
            np.percentile(lat, q),
            color="k",
            linestyle=style,
            label=f"p{q} {np.percentile(lat, q):.2f} s",
        )
    ax.axvline(2.5, color="#cc3311", label="target 2.5 s")
    ax.set_xlabel("gesture onset -> command (s, stream time)")
    ax.set_ylabel("commands")
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def plot_gestures(per_view_gesture: Mapping[str, Mapping[str, dict[str, Any]]], path: Path) -> None:
    """Median onset -> command latency per gesture (rows) and view (columns), each cell
    annotated with its median and the share of its commands later than 2.5 s."""
    plt = _pyplot()
    views = list(per_view_gesture)
    gestures = sorted({g for v in views for g in per_view_gesture[v]})
    med = np.full((len(gestures), len(views)), np.nan)
    fig, ax = plt.subplots(figsize=(4.6, 6))
    for i, g in enumerate(gestures):
        for j, v in enumerate(views):
            cell = per_view_gesture[v].get(g)
            text = "none"
            if cell and cell["median_s"] is not None:
                med[i, j] = cell["median_s"]
                text = f"{cell['median_s']:.1f} s\n{1 - cell['within_2_5_s']:.0%} late"
            ax.text(j, i, text, ha="center", va="center", fontsize=7)
    im = ax.imshow(med, cmap="RdYlGn_r", vmin=1.0, vmax=5.0, aspect="auto")
    ax.set_xticks(range(len(views)), [f"view {v}" for v in views])
    ax.set_yticks(range(len(gestures)), gestures)
    ax.set_title("median onset -> command; share later than 2.5 s", fontsize=9)
    fig.colorbar(im, ax=ax, label="median latency (s)", shrink=0.6)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def plot_stages(rows: Sequence[dict[str, Any]], path: Path) -> None:
    """Per view, the share of the commanded gestures that reached each stage (named,
    passed, commanded) by each time after the onset."""
    plt = _pyplot()
    fig, axes = plt.subplots(1, len(VIEWS), figsize=(10, 3.2), sharey=True)
    for ax, view in zip(axes, VIEWS, strict=True):
        done = [r for r in rows if r["view"] == view and r["commanded_s"] is not None]
        for stage, colour in zip(STAGES, ("#4477aa", "#ccbb44", "#ee6677"), strict=True):
            x = np.sort([r[f"{stage}_s"] for r in done if r[f"{stage}_s"] is not None])
            ax.step(x, np.arange(1, len(x) + 1) / max(len(done), 1), where="post",
                    color=colour, label=stage)  # fmt: skip
        ax.axvline(2.5, color="grey", ls="--", lw=1)
        ax.axhline(0.95, color="grey", ls=":", lw=1)
        ax.set_xlim(0, 6)
        ax.set_title(f"view {view} ({len(done)} commands)", fontsize=9)
        ax.set_xlabel("seconds after the onset")
    axes[0].set_ylabel("share of commanded gestures")
    axes[0].legend(fontsize=8, loc="lower right")
    fig.suptitle("where the time goes: classifier names it, filter passes it, command", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_confusion(confusion: list[list[int]], path: str | Path, title: str) -> Path:
    """Row-normalised confusion matrix as a PNG."""
    plt = _pyplot()
    cm = np.asarray(confusion, float)
    norm = cm / np.maximum(cm.sum(axis=1, keepdims=True), 1)
    fig, ax = plt.subplots(figsize=(8, 7))
    ax.imshow(norm, cmap="Blues", vmin=0, vmax=1)
    ax.set_xticks(range(len(GESTURES)), GESTURES, rotation=60, ha="right", fontsize=8)
    ax.set_yticks(range(len(GESTURES)), GESTURES, fontsize=8)
    ax.set_xlabel("predicted")
    ax.set_ylabel("true")
    ax.set_title(title, fontsize=10)
    for i in range(len(GESTURES)):
        for j in range(len(GESTURES)):
            if cm[i, j]:
                ax.text(j, i, f"{norm[i, j]:.2f}", ha="center", va="center", fontsize=6,
                        color="white" if norm[i, j] > 0.5 else "black")  # fmt: skip
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def plot_stances(result: dict[str, Any], clips: Mapping[str, Clip], path: Path) -> None:
    """Each still stance of `proxima.evaluation.still.still_operator`'s result (its mean
    pose) beside the commands it was read as."""
    plt = _pyplot()
    stances = result["stances"]
    cols = min(len(stances), 7)
    rows = -(-len(stances) // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(1.9 * cols, 3.2 * rows), squeeze=False)
    for ax in axes.flat:
        ax.axis("off")
    for ax, s in zip(axes.flat, stances, strict=False):
        clip = clips[s["clip"]]
        x = clip.xyz[: s["still_frames"]].mean(axis=0)
        px, py = x[:, 0] * clip.aspect, x[:, 1]
        for a, b in BONES:
            ax.plot([px[a], px[b]], [py[a], py[b]], color="#4477aa", lw=1.5)
        ax.set_aspect("equal")
        ax.invert_yaxis()
        said = ", ".join(c["command"] for c in s["commands"]) or "no command"
        ax.set_title(f"from {clip.gesture} ({clip.view})\n-> {said}", fontsize=7)
    fig.suptitle(f"armed operator standing still for {result['still_s']:.0f} s", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_temporal_errors(result: dict[str, Any], path: Path) -> None:
    """One panel per clip that some model gets wrong: a row per model, the nearest
    neighbour last; right windows blank, wrong ones coloured by the label given."""
    plt = _pyplot()
    from matplotlib.colors import ListedColormap

    labels = result["labels"]
    palette = plt.get_cmap("tab20")(np.arange(len(labels)))
    clips = result["clips"]
    rows = len(result["models"]) + 1
    height = (0.25 * rows + 0.45) * len(clips) + 1.2
    fig, axes = plt.subplots(len(clips), 1, figsize=(9, height), squeeze=False)
    seen: set[int] = set()
    for ax, clip in zip(axes[:, 0], clips, strict=True):
        grid = np.array([*clip["predictions"], clip["nearest_neighbour"]], dtype=float)
        seen.update(int(v) for v in np.unique(grid) if v != clip["truth"])
        ax.imshow(
            np.where(grid == clip["truth"], np.nan, grid),  # right: left blank
            aspect="auto",
            cmap=ListedColormap(palette),
            vmin=-0.5,
            vmax=len(labels) - 0.5,
            interpolation="nearest",
        )
        ax.set_facecolor("#e8e8e8")
        names = [f"model {i + 1}" for i in range(rows - 1)] + ["1-NN"]
        ax.set_yticks(range(rows), names, fontsize=6)
        ax.set_xticks([])
        wrong = " / ".join(str(w) for w in clip["wrong"])
        ax.set_title(
            f"{clip['clip']} ({clip['gesture']}): models wrong {wrong}, in every model "
            f"{clip['wrong_in_every_model']}, 1-NN wrong {clip['nearest_neighbour_wrong']} "
            f"of {clip['windows']}",
            fontsize=7,
            loc="left",
        )
    axes[-1, 0].set_xlabel(
        "test windows in time order (grey: right; colour: the label given)", fontsize=8
    )
    handles = [plt.Rectangle((0, 0), 1, 1, color=palette[i]) for i in sorted(seen)]
    fig.legend(handles, [labels[i] for i in sorted(seen)], loc="lower center", fontsize=7,
               ncol=6, frameon=False)  # fmt: skip
    wrong = ", ".join(str(m["wrong"]) for m in result["models"])
    common = result["wrong_in_every_model_and_nearest_neighbour_wrong"]
    fig.suptitle(
        f"Temporal split, {result['test_windows']} test windows: wrong {wrong}; "
        f"wrong in every model {result['wrong_in_every_model']}, of which the nearest "
        f"training window is wrong too for {common}",
        fontsize=8,
    )
    fig.tight_layout(rect=(0, 0.5 / height, 1, 1 - 0.3 / height))  # room: legend, title
    fig.savefig(path, dpi=120)
    plt.close(fig)


def plot_robustness(result: Mapping[str, Any], path: Path, title: str) -> Path:
    """Window accuracy against capture level, one line per condition, each from the
    clean accuracy at level 0; `field` drawn bold."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7, 4.2))
    clean = result["clean"]["accuracy"]
    cmap = plt.get_cmap("tab10")
    for k, (name, levels) in enumerate(result["conditions"].items()):
        xs = [0] + [r["level"] for r in levels if r["accuracy"] is not None]
        ys = [clean] + [r["accuracy"] for r in levels if r["accuracy"] is not None]
        bold = name == "field"
        ax.plot(xs, ys, marker="o", lw=2.8 if bold else 1.4, label=name,
                color="k" if bold else cmap(k % 10))  # fmt: skip
    ax.axhline(clean, color="grey", ls=":", lw=1)
    ax.set_xticks([0, 1, 2, 3], ["clean", "1", "2", "3"])
    ax.set_xlabel("capture level (docs/capture.md)")
    ax.set_ylabel("window accuracy")
    ax.set_title(title, fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, ncol=2, loc="lower left")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path
