"""The learning curve of a run as a PNG: the global model's accuracy and loss on the
held-out set per round (thick), and each drone's local validation accuracy and loss
after its local epochs (dashed)."""

from __future__ import annotations

from pathlib import Path
from typing import Any


def plot_curve(
    rounds: list[dict[str, Any]],
    path: str | Path,
    title: str,
    reference: float | None = None,
) -> Path:
    """Write the curve; `reference` draws a horizontal line (e.g. centralised accuracy)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import MaxNLocator

    fig, (ax_acc, ax_loss) = plt.subplots(1, 2, figsize=(11, 4.2))
    xs = [r["round"] for r in rounds]
    for ax, key, label in (
        (ax_acc, "global_accuracy", "accuracy"),
        (ax_loss, "global_loss", "loss"),
    ):
        ax.plot(
            xs, [r.get(key) for r in rounds], "o-", lw=2.5, color="black", label="global (held-out)"
        )
        ax.set_xlabel("round")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    drones = sorted(
        {
            c["drone"]
            for r in rounds
            for c in r.get("clients", [])
            if c.get("phase", "train") == "train"
        }
    )
    for drone in drones:
        pts = [
            (r["round"], c)
            for r in rounds
            for c in r.get("clients", [])
            if c["drone"] == drone
            and c.get("phase", "train") == "train"
            and c.get("status") == "ok"
        ]
        if not pts:
            continue
        rx = [p[0] for p in pts]
        ax_acc.plot(
            rx, [p[1].get("accuracy") for p in pts], "--", marker=".", label=f"{drone} (local val)"
        )
        ax_loss.plot(rx, [p[1].get("loss") for p in pts], "--", marker=".", label=drone)
        failed = [
            r["round"]
            for r in rounds
            for c in r.get("clients", [])
            if c["drone"] == drone and c.get("status") != "ok"
        ]
        if failed:
            ax_acc.plot(failed, [0.02] * len(failed), "x", color="red", ms=9)
    if reference is not None:
        ax_acc.axhline(reference, color="gray", ls=":", label=f"centralised {reference:.3f}")
    ax_acc.set_ylim(0, 1)
    ax_acc.legend(fontsize=8, loc="lower right")
    ax_acc.set_title(title, fontsize=10)
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
