"""Model cards: a Markdown page beside a checkpoint saying what it is, how it was made
and how well it does, from the checkpoint's own metadata and protocol results."""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from proxima.evaluation.protocols import results_table
from proxima.gesture.classifier import GestureClassifier


def render_model_card(
    checkpoint: str | Path, results: Sequence[dict[str, Any]] = (), notes: str = ""
) -> str:
    """The card's Markdown for a checkpoint and (optionally) its protocol results."""
    checkpoint = Path(checkpoint)
    clf = GestureClassifier.load(checkpoint)
    meta = clf.metadata
    params = sum(p.numel() for p in clf.model.parameters())
    lines = [
        f"# Model card: `{checkpoint.name}`",
        "",
        f"- Model: `{clf.model_name}` ({params:,} parameters), feature pipeline "
        f"`{clf.pipeline.name}`, window {clf.window} frames, {len(clf.labels)} gestures.",
        f"- File size: {checkpoint.stat().st_size / 1024:.0f} KiB (weights stored as float16).",
        f"- Created: {meta.get('created', '?')}",
        f"- Command: `{meta.get('command', '?')}`",
        f"- Split it was trained on: `{meta.get('split', '?')}`; "
        f"{meta.get('train_windows', '?')} training windows, {meta.get('epochs_run', '?')} epochs.",
        f"- Data: {', '.join(Path(d).name for d in meta.get('data', []))}; "
        f"SHA-256 of the data files' SHA-256 list: `{meta.get('data_sha256', '?')}`",
        f"- Training config: `{json.dumps(meta.get('train_config', {}), sort_keys=True)}`",
        "",
        "## Labels",
        "",
        ", ".join(clf.labels),
        "",
    ]
    if results:
        lines += [
            "## Evaluation protocols",
            "",
            "Each row trains the same model with the same command on the split's training "
            "part and scores its test part (`proxima protocols`); the shipped model itself "
            "is trained on everything (`--split all`).",
            "",
            results_table(results),
            "",
        ]
    if notes:
        lines += [notes.strip(), ""]
    return "\n".join(lines)
