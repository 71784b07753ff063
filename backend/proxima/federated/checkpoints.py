"""Each run's global model as a versioned checkpoint with a Markdown model card beside
it, and promotion into the live engine, which is only ever an explicit action.

Checkpoints go to `<models_dir>/federated/gesture-fl-<run id>.pt` (the run id starts
with its UTC time, so names sort by version) in the format `GestureClassifier.load`
reads; the card `gesture-fl-<run id>.md` says how it was trained and how it scored per
round. The console's Models page lists both and has the promote button.
"""

from __future__ import annotations

import datetime as dt
import json
from pathlib import Path
from typing import Any

import numpy as np

from proxima.federated.config import FLConfig
from proxima.federated.recorder import kept_round_row
from proxima.federated.task import new_model, set_weights
from proxima.gesture.classifier import save_checkpoint


def checkpoint_path(models_dir: str | Path, run_id: str) -> Path:
    return Path(models_dir) / "federated" / f"gesture-fl-{run_id}.pt"


def save_run_model(
    cfg: FLConfig,
    weights: dict[str, np.ndarray],
    rounds: list[dict[str, Any]],
    extra: dict[str, Any] | None = None,
    kept: int | None = None,
) -> tuple[Path, Path]:
    """Write the global model (round `kept`'s, default the last) and its card; returns
    (checkpoint, card)."""
    model, pipeline = new_model(cfg)
    set_weights(model, weights)
    final = kept_round_row(rounds, kept)
    meta = {
        "command": "federated run",
        "split": "temporal",
        "federated": {
            "run_id": cfg.run_id,
            "run_config": cfg.to_run_config(),
            "kept_round": final.get("round"),
            "rounds": [
                {
                    k: r.get(k)
                    for k in (
                        "round",
                        "global_accuracy",
                        "global_loss",
                        "val_loss",
                        "clients_ok",
                        "clients_failed",
                    )
                }
                for r in rounds
            ],
            **(extra or {}),
        },
        "test_accuracy": final.get("global_accuracy"),
    }
    path = save_checkpoint(
        checkpoint_path(cfg.models_dir, cfg.run_id), model, cfg.model, pipeline, cfg.window, meta
    )
    card = path.with_suffix(".md")
    card.write_text(model_card(cfg, rounds, path, extra or {}, final))
    return path, card


def _fmt(x: Any) -> str:
    return f"{x:.3f}" if isinstance(x, float) else ("-" if x is None else str(x))


def model_card(
    cfg: FLConfig,
    rounds: list[dict[str, Any]],
    path: Path,
    extra: dict[str, Any],
    final: dict[str, Any] | None = None,
) -> str:
    """The Markdown card: what, how trained, how it scored (the model is round `final`'s,
    default the last), and how to use it."""
    final = final if final is not None else kept_round_row(rounds, None)
    kept_why = (
        "lowest loss on the drones' validation windows"
        if cfg.keep_round == "best"
        else "the last round's"
    )
    drones = sorted({c["drone"] for r in rounds for c in r.get("clients", [])})
    lines = [
        f"# Federated gesture model `{path.name}`",
        "",
        f"- Run: `{cfg.run_id}`, saved {dt.datetime.now(dt.UTC).isoformat(timespec='seconds')}",
        f"- Model: `{cfg.model}` on the scale-free `{cfg.pipeline}` features (no fitted "
        "statistics, so no drone scaled with statistics only it had)",
        f"- Strategy: `{cfg.strategy}`, {cfg.rounds} rounds, {cfg.local_epochs} local epoch(s) "
        f"a round, batch {cfg.batch_size}, learning rate {cfg.learning_rate:g}, "
        f"fraction fit {cfg.fraction_fit:g}, at least {cfg.min_clients} drones",
        f"- Data: partition `{cfg.partition}` over {cfg.num_drones} drones "
        f"({', '.join(drones) or 'none answered'}); console samples "
        f"{'included' if cfg.include_samples else 'not included'}; training windows every "
        f"{cfg.stride} frames",
        f"- Held-out test: the temporal split's test part (last 30% of every clip), windows "
        f"every {cfg.test_stride} frames; no drone trained on it",
        f"- **Global accuracy after round {final.get('round', '-')}: "
        f"{_fmt(final.get('global_accuracy'))}** (loss {_fmt(final.get('global_loss'))})",
        f"- Kept: round {final.get('round', '-')}'s global model ({kept_why})",
    ]
    for k, v in extra.items():
        lines.append(f"- {k.replace('_', ' ')}: {_fmt(v)}")
    lines += [
        "",
        "| round | global accuracy | global loss | validation loss | drones ok "
        "| drones failed | seconds |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in rounds:
        lines.append(
            f"| {r['round']} | {_fmt(r.get('global_accuracy'))} | {_fmt(r.get('global_loss'))} "
            f"| {_fmt(r.get('val_loss'))} "
            f"| {r.get('clients_ok', '-')} | {r.get('clients_failed', '-')} "
            f"| {_fmt(r.get('duration_s'))} |"
        )
    failures = [
        (r["round"], c)
        for r in rounds
        for c in r.get("clients", [])
        if c.get("status") != "ok" or c.get("detail")
    ]
    if failures:
        lines += ["", "## Drone reports", ""]
        lines += [
            f"- round {rnd}, {c['drone']} ({c.get('phase')}): {c.get('status')}"
            f"{': ' + c['detail'] if c.get('detail') else ''}"
            for rnd, c in failures
        ]
    lines += [
        "",
        "## Use",
        "",
        "Not active until promoted: `proxima fl promote "
        f"{cfg.run_id}` (or the Models page of the console). Run config:",
        "",
        "```json",
        json.dumps(cfg.to_run_config(), indent=1, sort_keys=True),
        "```",
        "",
    ]
    return "\n".join(lines)
