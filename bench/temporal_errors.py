"""Where a temporal-split model goes wrong, and whether the data could have told it.

Every LASER clip's held-out part (its last 30%, windows at stride 3, as `proxima
evaluate --split temporal` scores them) is laid out in time twice: the model's decision
for each window, and a model-free check, the label of the nearest training window
(1-nearest neighbour over all LASER clips' training parts, on coarse poses: the body
pipeline's joint positions, hip-centred, torso-scaled and turned to face the camera,
averaged over six 10-frame chunks). Where the model is wrong and the nearest training
window carries the same wrong label, that test stretch looks more like another gesture's
training data than like its own: a better-trained model of the same recordings cannot
be expected to get it right; more recordings can. With several checkpoints (e.g. seeds
of one recipe), the windows every model gets wrong are counted too: if they alone exceed
what a target allows, no choice among these models reaches it.

    python -m bench.temporal_errors --checkpoint A.pt [--checkpoint B.pt ...]

Writes bench/results/temporal_errors.json and temporal_errors.png (one panel per clip
that some model gets wrong: a row per model, the nearest neighbour last).
"""

from __future__ import annotations

import argparse
import json
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from proxima.gesture.windows import Windows

RESULTS = Path(__file__).resolve().parent / "results"
CHUNK = 10  # frames averaged into one coarse pose


def stretches(pred: np.ndarray, truth: np.ndarray, labels: Sequence[str]) -> list[dict]:
    """Runs of consecutive wrong windows with one predicted label, in window order."""
    out: list[dict] = []
    for i, (p, y) in enumerate(zip(pred.tolist(), truth.tolist(), strict=True)):
        if p == y:
            continue
        last = out[-1] if out else None
        if last and last["start"] + last["length"] == i and last["predicted"] == labels[p]:
            last["length"] += 1
        else:
            out.append({"start": i, "length": 1, "predicted": labels[p]})
    return out


def coarse(windows: Windows) -> np.ndarray:
    """Windows -> (N, W // CHUNK * 17 * 2): the shared joints' 2D positions in the body
    pipeline's canonical frame (hip-centred, torso-scaled, facing the camera), averaged
    over each CHUNK frames."""
    from proxima.gesture.features import BodyPipeline
    from proxima.gesture.geometry import to_metric
    from proxima.gesture.skeleton import COMMON

    can = BodyPipeline().canonical(to_metric(windows.xyz, windows.aspect), windows.has_z)
    n, w = can.shape[:2]
    pos = can[:, : w - w % CHUNK, list(COMMON), :2].reshape(n, w // CHUNK, CHUNK, -1)
    return pos.mean(axis=2).reshape(n, -1)


def nearest_labels(train: np.ndarray, train_labels: np.ndarray, test: np.ndarray) -> np.ndarray:
    """The label of each test row's nearest training row (squared Euclidean)."""
    sq = (train**2).sum(axis=1)
    out = np.empty(len(test), dtype=train_labels.dtype)
    for i in range(0, len(test), 256):
        block = test[i : i + 256]
        dist = sq[None, :] - 2 * block @ train.T  # + |block|^2, constant per row
        out[i : i + 256] = train_labels[dist.argmin(axis=1)]
    return out


def analyse(checkpoints: Sequence[Path], data: str | None) -> dict[str, Any]:
    from proxima.gesture.classifier import GestureClassifier
    from proxima.gesture.datasets import load_data
    from proxima.gesture.train import features, predict_proba
    from proxima.gesture.windows import WINDOW, make_windows, split_clips
    from proxima.types import GESTURES

    laser = load_data([data or "laser"])
    parts = split_clips(laser.clips, "temporal", WINDOW, laser.uav_dir)
    names: list[str] = []
    test = make_windows(parts.test, WINDOW, 3, 5, names)
    train = make_windows(parts.train, WINDOW, 2, 5, names)
    nn = nearest_labels(coarse(train), train.labels, coarse(test))
    truth = test.labels  # indices into GESTURES
    labels = list(GESTURES)
    models, preds = [], []
    for path in checkpoints:
        clf = GestureClassifier.load(path)
        if clf.window != WINDOW:
            raise ValueError(f"{path}: window {clf.window}, the temporal split uses {WINDOW}")
        if list(clf.labels) != labels:
            raise ValueError(f"{path}: labels {list(clf.labels)} are not {labels}")
        pred = predict_proba(clf.model, features(clf.pipeline, test)).argmax(axis=1)
        wrong = pred != truth
        preds.append(pred)
        models.append(
            {
                "checkpoint": str(path),
                "accuracy": float((~wrong).mean()),
                "wrong": int(wrong.sum()),
                "wrong_and_nearest_neighbour_wrong": int((wrong & (nn != truth)).sum()),
                # ... and of those, the very label the model gave.
                "wrong_and_nearest_neighbour_agrees": int((wrong & (nn == pred)).sum()),
            }
        )
    every = np.all([p != truth for p in preds], axis=0)
    clips = []
    for c in np.unique(test.clip):
        sel = np.flatnonzero(test.clip == c)
        if not any((p[sel] != truth[sel]).any() for p in preds):
            continue
        clips.append(
            {
                "clip": names[c],
                "gesture": labels[int(truth[sel[0]])],
                "truth": int(truth[sel[0]]),
                "windows": len(sel),
                "wrong": [int((p[sel] != truth[sel]).sum()) for p in preds],
                "wrong_in_every_model": int(every[sel].sum()),
                "nearest_neighbour_wrong": int((nn[sel] != truth[sel]).sum()),
                "model_stretches": [stretches(p[sel], truth[sel], labels) for p in preds],
                "predictions": [p[sel].tolist() for p in preds],
                "nearest_neighbour": nn[sel].tolist(),
            }
        )
    return {
        "labels": labels,
        "test_windows": len(test),
        "train_windows_searched": len(train),
        "nearest_neighbour_accuracy": float((nn == truth).mean()),
        "models": models,
        "wrong_in_every_model": int(every.sum()),
        "wrong_in_every_model_and_nearest_neighbour_wrong": int((every & (nn != truth)).sum()),
        "clips": clips,
    }


def plot(result: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
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


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument(
        "--checkpoint",
        type=Path,
        action="append",
        required=True,
        help="a model trained with --split temporal; repeat to compare several",
    )
    ap.add_argument("--data", default=None, help="LASER folder (default: resolved)")
    ap.add_argument("--out", type=Path, default=RESULTS / "temporal_errors.json")
    args = ap.parse_args(argv)
    result = analyse(args.checkpoint, args.data)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=1))
    if result["clips"]:
        plot(result, args.out.with_suffix(".png"))
    else:
        print("no model gets a window wrong: no picture to draw")
    print(f"nearest neighbour accuracy {result['nearest_neighbour_accuracy']:.3f}")
    for m in result["models"]:
        print(
            f"{m['checkpoint']}: accuracy {m['accuracy']:.3f} ({m['wrong']} of "
            f"{result['test_windows']} wrong; nearest neighbour wrong too: "
            f"{m['wrong_and_nearest_neighbour_wrong']}, with the same label: "
            f"{m['wrong_and_nearest_neighbour_agrees']})"
        )
    print(
        f"wrong in every model: {result['wrong_in_every_model']}, and for the nearest "
        f"neighbour too: {result['wrong_in_every_model_and_nearest_neighbour_wrong']}"
    )
    for clip in result["clips"]:
        print(f"  {clip['clip']}: wrong {clip['wrong']} of {clip['windows']}")
    print(f"-> {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
