"""Model cards: a Markdown page beside a checkpoint saying what it is, how it was made
and how well it does, from the checkpoint's own metadata and protocol results."""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from proxima.evaluation.protocols import results_table
from proxima.gesture.classifier import GestureClassifier
from proxima.gesture.ensemble import EnsembleClassifier, load_checkpoint, members_of


def render_model_card(
    checkpoint: str | Path, results: Sequence[dict[str, Any]] = (), notes: str = ""
) -> str:
    """The card's Markdown for a checkpoint (one model or an ensemble file) and
    (optionally) its protocol results."""
    checkpoint = Path(checkpoint)
    clf = load_checkpoint(checkpoint)
    members = members_of(clf)
    first = members[0]
    params = sum(p.numel() for p in first.model.parameters())
    size = f"{checkpoint.stat().st_size / 1024:.0f} KiB (weights stored as float16)"
    meta = first.metadata
    if isinstance(clf, EnsembleClassifier):
        lines = [
            f"# Model card: `{checkpoint.name}`",
            "",
            f"- An ensemble of {len(members)} `{first.model_name}` models ({params:,} parameters "
            f"each), feature pipeline `{first.pipeline.name}`, window {clf.window} frames, "
            f"{len(clf.labels)} gestures: the mean of the members' calibrated probabilities.",
            f"- File size: {size}.",
            f"- Created: {clf.metadata.get('created', '?')}",
            f"- Command: `{clf.metadata.get('command', '?')}`",
            "",
            "| member | seed | split | training windows | epochs | temperature | created |",
            "|---|---|---|---|---|---|---|",
            *(member_row(i, m) for i, m in enumerate(members)),
            "",
            f"- Each member's command: `{meta.get('command', '?')}` (its own `--seed`).",
        ]
    else:
        lines = [
            f"# Model card: `{checkpoint.name}`",
            "",
            f"- Model: `{clf.model_name}` ({params:,} parameters), feature pipeline "
            f"`{first.pipeline.name}`, window {clf.window} frames, {len(clf.labels)} gestures.",
            f"- File size: {size}.",
            f"- Created: {meta.get('created', '?')}",
            f"- Command: `{meta.get('command', '?')}`",
            f"- Split it was trained on: `{meta.get('split', '?')}`; "
            f"{meta.get('train_windows', '?')} training windows, "
            f"{meta.get('epochs_run', '?')} epochs.",
        ]
    config = json.dumps(meta.get("train_config", {}), sort_keys=True)
    lines += [
        f"- Data: {', '.join(Path(d).name for d in meta.get('data', []))}; "
        f"SHA-256 of the data files' SHA-256 list: `{meta.get('data_sha256', '?')}`",
        f"- Training config{' (member 0)' if len(members) > 1 else ''}: `{config}`",
        "",
    ]
    lines += [
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


def member_row(index: int, member: GestureClassifier) -> str:
    """One ensemble member's row of the card's members table."""
    meta = member.metadata
    cfg = meta.get("train_config", {})
    return (
        f"| {index} | {cfg.get('seed', '?')} | `{meta.get('split', '?')}` | "
        f"{meta.get('train_windows', '?')} | {meta.get('epochs_run', '?')} | "
        f"{member.temperature:.3f} | {meta.get('created', '?')} |"
    )
