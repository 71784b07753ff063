"""Training with the synthetic operator (issue 22 part 2), scored on real clips only.

Recipes, each run through `proxima train`'s code (`train_model`) and scored with
`proxima evaluate`'s (`evaluate_checkpoint`):

- `real`: LASER + UAV-Gesture, the shipped model's data (the reference);
- `synth-only`: one model trained on the synthetic clips alone (`--split all`), scored on
  every split's real test part (the target is the real front view, cross-view:f);
- `pretrain`: that synthetic model fine-tuned on each split's real training part
  (`--init`);
- `mixed`: real + synthetic clips together (`--data synth:DIR`); the synthetic clips
  train in every split and never test (`split_clips`).

Temporal and cross-view splits are scored on LASER, `uav-gesture:N` on that split's
held-out people, as `proxima protocols --eval-data laser` does. One JSON per (recipe,
split) goes to `--rows` (so an interrupted run resumes where it stopped), and all rows
found there to `--json`.

    python -m bench.synth_training --synth runs/synth-390 --split cross-view:f ...
"""

from __future__ import annotations

import argparse
import json
import shlex
from dataclasses import replace
from pathlib import Path
from typing import Any

import torch

from proxima.evaluation.metrics import evaluate_checkpoint
from proxima.evaluation.protocols import LASER_PROTOCOLS, UAV_PROTOCOLS
from proxima.gesture.data_source import SYNTH_PREFIX
from proxima.gesture.train import TrainConfig
from proxima.gesture.workflow import train_model

RECIPES = ("real", "synth-only", "pretrain", "mixed")
REAL = ("laser", "uav-gesture")
SPLITS = (*LASER_PROTOCOLS[1:], *UAV_PROTOCOLS)  # cross-view first, then UAV-Gesture
OUT = Path("bench/results/synth-training.json")


def train_data(recipe: str, synth: str | Path) -> list[str]:
    """The `--data` specs a recipe trains a split's model on (`pretrain`: the fine-tuning
    data; its pretraining data is `train_data("synth-only", synth)`)."""
    if recipe not in RECIPES:
        raise ValueError(f"unknown recipe {recipe!r}; choose from {RECIPES}")
    synth_spec = f"{SYNTH_PREFIX}{synth}"
    if recipe == "synth-only":
        return [synth_spec]
    if recipe == "mixed":
        return [*REAL, synth_spec]
    return list(REAL)


def eval_data(split: str) -> list[str]:
    """What a split is scored on: LASER, or UAV-Gesture's held-out people (the split
    needs both folders loaded, as in training)."""
    return list(REAL) if split.startswith("uav-gesture") else ["laser"]


def _cli(args: list[str]) -> str:
    return "proxima " + shlex.join(args)


def train_args(cfg: TrainConfig) -> list[str]:
    values = {"epochs": cfg.epochs, "patience": cfg.patience, "stride": cfg.stride,
              "seed": cfg.seed, "threads": cfg.threads}  # fmt: skip
    return [a for k, v in values.items() for a in (f"--{k}", str(v))]


def _data_args(specs: list[str]) -> list[str]:
    return [a for s in specs for a in ("--data", s)]


def run_row(
    recipe: str, split: str, synth: Path, cfg: TrainConfig, ckpt_dir: Path, pretrained: Path
) -> dict[str, Any]:
    """Train (unless synth-only, whose one model is `pretrained`) and score one split."""
    ckpt = ckpt_dir / f"{recipe}-{split.replace(':', '-')}.pt"
    data = train_data(recipe, synth)
    init = pretrained if recipe == "pretrain" else None
    train_cmd = ["train", *_data_args(data), "--split", split, *train_args(cfg)]
    if init is not None:
        train_cmd += ["--init", str(init)]
    row: dict[str, Any] = {"recipe": recipe, "split": split}
    if recipe == "synth-only":
        ckpt = pretrained
        row["train_command"] = _cli(_pretrain_cmd(synth, cfg, pretrained))
    else:
        tr = train_model(data, "tcn", split, ckpt, replace(cfg), command=_cli(train_cmd),
                         init=init)  # fmt: skip
        row.update(epochs=len(tr.history), train_seconds=round(tr.seconds, 1),
                   train_windows=tr.train_windows)  # fmt: skip
        row["train_command"] = _cli([*train_cmd, "--out", str(ckpt)])
    ev = eval_data(split)
    m = evaluate_checkpoint(ckpt, ev, split)
    row["eval_command"] = _cli(["evaluate", "--checkpoint", str(ckpt), *_data_args(ev),
                                "--split", split, "--json", "E.json"])  # fmt: skip
    row.update({k: m[k] for k in ("accuracy", "macro_f1", "clip_accuracy", "windows")})
    row["per_view"] = {v: r["accuracy"] for v, r in m["per_view"].items()}
    return row


def _pretrain_cmd(synth: Path, cfg: TrainConfig, out: Path) -> list[str]:
    data = _data_args(train_data("synth-only", synth))
    return ["train", *data, "--split", "all", *train_args(cfg), "--out", str(out)]


def pretrain(synth: Path, cfg: TrainConfig, out: Path) -> Path:
    """The synthetic-only model (recipe `synth-only`, and `pretrain`'s starting point)."""
    if not out.is_file():
        cmd = _pretrain_cmd(synth, cfg, out)
        train_model(train_data("synth-only", synth), "tcn", "all", out, replace(cfg),
                    command=_cli(cmd))  # fmt: skip
    return out


def collect(rows_dir: Path, out: Path) -> list[dict[str, Any]]:
    rows = [json.loads(f.read_text()) for f in sorted(rows_dir.glob("*.json"))]
    order = {r: i for i, r in enumerate(RECIPES)}
    splits = {s: i for i, s in enumerate(SPLITS)}
    rows.sort(key=lambda r: (order[r["recipe"]], splits.get(r["split"], 99)))
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(rows, indent=1))
    return rows


def table(rows: list[dict[str, Any]]) -> str:
    """Markdown: one line per recipe, window accuracy per split (clip accuracy after /)."""
    splits = [s for s in SPLITS if any(r["split"] == s for r in rows)]
    lines = ["| recipe | " + " | ".join(splits) + " |", "|---" * (len(splits) + 1) + "|"]
    for recipe in RECIPES:
        got = {r["split"]: r for r in rows if r["recipe"] == recipe}
        if got:
            cells = [f"{got[s]['accuracy']:.3f} / {got[s]['clip_accuracy']:.2f}"
                     if s in got else "" for s in splits]  # fmt: skip
            lines.append(f"| {recipe} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--synth", type=Path, required=True, help="folder from `proxima synth`")
    ap.add_argument("--collect", action="store_true", help="only gather --rows into --json")
    ap.add_argument("--recipe", action="append", choices=RECIPES, help="default: all")
    ap.add_argument("--split", action="append", help="default: cross-view f/l/r, uav 1-3")
    ap.add_argument("--epochs", type=int, default=15)
    ap.add_argument("--patience", type=int, default=5)
    ap.add_argument("--stride", type=int, default=8)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--rows", type=Path, default=Path("runs/synth-training"))
    ap.add_argument("--json", type=Path, default=OUT)
    a = ap.parse_args(argv)
    torch.set_num_threads(a.threads)  # scoring too: the machine is shared
    cfg = TrainConfig(epochs=a.epochs, patience=a.patience, stride=a.stride, seed=a.seed,
                      threads=a.threads)  # fmt: skip
    a.rows.mkdir(parents=True, exist_ok=True)
    if a.collect:
        print(table(collect(a.rows, a.json)))
        return
    pretrained = a.rows / "synth-only.pt"
    for recipe in a.recipe or RECIPES:
        if recipe in ("synth-only", "pretrain"):
            pretrain(a.synth, cfg, pretrained)
        for split in a.split or SPLITS:
            row_file = a.rows / f"{recipe}-{split.replace(':', '-')}.json"
            if row_file.is_file():
                continue  # done in an earlier run
            row = run_row(recipe, split, a.synth, cfg, a.rows, pretrained)
            row_file.write_text(json.dumps(row, indent=1))
            print(f"{recipe} {split}: {row['accuracy']:.3f} (clip {row['clip_accuracy']:.3f})",
                  flush=True)  # fmt: skip
    print(table(collect(a.rows, a.json)))


if __name__ == "__main__":
    main()
