"""Federated training against centralised training on the LASER temporal split, with one
camera view per drone (3 drones), on Flower's simulation and deployment engines.

    .venv/bin/python -m bench.federated [--central-checkpoint PATH] [--long-rounds 20]
        [--init CKPT] [--local-epochs N] [--keep-central PATH] [--skip-deploy] [--out JSON]
        [--strategy NAME]

Measures:
- centralised: `proxima train`'s code and defaults on the temporal split (or a given
  checkpoint; with `--init` both it and the federated runs start from that checkpoint),
  scored on the held-out test windows the federated runs use;
- simulation, 5 rounds x 3 drones: wall time (target <= 60 s), global accuracy per
  round, peak memory of the driver and of all its processes (Ray workers included);
- deployment engine, 5 rounds x 3 drones: SuperLink + 3 SuperNodes on loopback, wall
  time from `flwr run` to the last round;
- a longer simulation: how many rounds the global model needs to come within 2 points
  of centralised (target), and its curve (bench/results/federated_curve.png).

Writes bench/results/federated.json. This machine is shared: the load average at each
step is recorded beside every time.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import platform
import resource
import tempfile
import threading
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

OUT = Path(__file__).parent / "results" / "federated.json"


class PeakMemory:
    """Peak resident memory of this process and of it plus all its descendants."""

    def __init__(self) -> None:
        self.tree_mb = 0.0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._poll, daemon=True)

    def _poll(self) -> None:
        try:
            import psutil
        except ImportError:
            return
        me = psutil.Process()
        while not self._stop.wait(0.5):
            total = 0
            for p in [me, *me.children(recursive=True)]:
                with contextlib.suppress(psutil.Error):
                    total += p.memory_info().rss
            self.tree_mb = max(self.tree_mb, total / 2**20)

    def __enter__(self) -> PeakMemory:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join()


def load() -> float:
    return round(os.getloadavg()[0], 2)


def centralised(
    checkpoint: Path | None,
    test_stride: int,
    mirror: bool,
    init: str = "",
    keep: Path | None = None,
    seed: int = 0,
    window: int = 60,
) -> dict[str, Any]:
    from proxima.evaluation.metrics import evaluate_checkpoint
    from proxima.gesture.train import TrainConfig
    from proxima.gesture.workflow import train_model

    out: dict[str, Any] = {"load_average_at_start": load()}
    if checkpoint is None:
        tmp = keep or Path(tempfile.mkdtemp()) / "central.pt"
        cfg = TrainConfig(threads=1, mirror=mirror, seed=seed, window=window)  # as the drones
        t0 = time.perf_counter()
        res = train_model(None, "tcn", "temporal", tmp, cfg, command="bench.federated",
                          init=init or None)  # fmt: skip
        out.update(train_seconds=round(time.perf_counter() - t0, 1), epochs=len(res.history),
                   train_config=cfg.to_dict(), init=init)  # fmt: skip
        checkpoint = tmp
    m = evaluate_checkpoint(checkpoint, None, "temporal", stride=test_stride)
    out.update(checkpoint=str(checkpoint), accuracy=m["accuracy"], macro_f1=m["macro_f1"],
               test_windows=m["windows"])  # fmt: skip
    return out


def simulation(cfg: Any, label: str) -> tuple[dict[str, Any], Any]:
    from proxima.federated.simulate import simulate

    start_load = load()
    with PeakMemory() as mem:
        res = simulate(cfg)
    doc = res.to_json()
    return {
        "label": label,
        "engine": "simulation",
        "wall_s": doc["wall_s"],
        "status": doc["status"],
        "final_accuracy": doc["final_accuracy"],
        "accuracy_per_round": [r["global_accuracy"] for r in doc["rounds"]],
        "round_seconds": [r["duration_s"] for r in doc["rounds"]],
        "driver_peak_rss_mb": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024),
        "all_processes_peak_rss_mb": round(mem.tree_mb),
        "load_average": [start_load, load()],
        "config": doc["config"],
        "rounds": doc["rounds"],
    }, res


def deployment(cfg: Any) -> dict[str, Any]:
    from proxima.federated.runner import FederatedRunner

    tmp = Path(tempfile.mkdtemp())
    runner = FederatedRunner(tmp / "runs.db", tmp / "models", workdir=tmp / "fl", defaults=cfg)
    start_load = load()
    try:
        t0 = time.perf_counter()
        runner.ensure_federation()
        startup = time.perf_counter() - t0
        t1 = time.perf_counter()
        runner.start_run({})
        run = runner.wait()
        wall = time.perf_counter() - t1
    finally:
        runner.close()
    assert run is not None
    return {
        "engine": "deployment (SuperLink + 3 SuperNodes on 127.0.0.1)",
        "process_startup_s": round(startup, 1),
        "wall_s": round(wall, 1),
        "status": run["status"],
        "final_accuracy": run["final_accuracy"],
        "accuracy_per_round": [r["global_accuracy"] for r in run["rounds"]],
        "round_seconds": [r["duration_s"] for r in run["rounds"]],
        "load_average": [start_load, load()],
    }


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--central-checkpoint", type=Path, help="score this instead of training")
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--long-rounds", type=int, default=20, help="0 to skip")
    ap.add_argument("--skip-deploy", action="store_true")
    ap.add_argument("--mirror", action=argparse.BooleanOptionalAction, default=None,
                    help="mirroring augmentation on the drones and the centralised run "
                    "(default: FLConfig's)")  # fmt: skip
    ap.add_argument("--init", default="", help="checkpoint both runs start from (e.g. the "
                    "synthetic operator's model, docs/synth.md)")  # fmt: skip
    ap.add_argument("--local-epochs", type=int, default=None, help="default: FLConfig's")
    ap.add_argument("--strategy", default=None, help="default: FLConfig's")
    ap.add_argument("--seed", type=int, default=0, help="seed of both runs (FLConfig, TrainConfig)")
    ap.add_argument("--window", type=int, default=None, help="frames per window of both runs "
                    "(default: FLConfig's)")  # fmt: skip
    ap.add_argument("--keep-central", type=Path, help="save the centralised checkpoint here")
    ap.add_argument("--central-only", action="store_true",
                    help="only the centralised reference (more seeds of it)")  # fmt: skip
    ap.add_argument("--out", type=Path, default=OUT, help="results JSON; the curve beside it")
    args = ap.parse_args()

    import torch

    from proxima.federated.config import FLConfig

    torch.set_num_threads(1)
    base = FLConfig(rounds=args.rounds, include_samples=False, init=args.init, seed=args.seed)
    if args.local_epochs is not None:
        base = replace(base, local_epochs=args.local_epochs)
    if args.mirror is not None:
        base = replace(base, mirror=args.mirror)
    if args.strategy is not None:
        base = replace(base, strategy=args.strategy)
    if args.window is not None:
        base = replace(base, window=args.window)
    results: dict[str, Any] = {
        "machine": {"cpus": os.cpu_count(), "python": platform.python_version(),
                    "torch": torch.__version__, "flwr": _flwr_version()},
        "partition": "view: one LASER camera view per drone (f, l, r)",
        "mirror": base.mirror,
        "init": args.init,
        "local_epochs": base.local_epochs,
        "augment": base.augment,
        "strategy": base.strategy,
        "seed": base.seed,
        "window": base.window,
    }  # fmt: skip
    central = centralised(args.central_checkpoint, base.test_stride, base.mirror, args.init,
                          args.keep_central, args.seed, base.window)  # fmt: skip
    results["centralised"] = central
    print("centralised", central["accuracy"], flush=True)
    if args.central_only:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(json.dumps(results, indent=1))
        print(f"-> {args.out}")
        return
    sim, _ = simulation(base, f"{args.rounds} rounds x 3 drones")
    results["simulation_5_rounds"] = sim
    print("simulation", sim["wall_s"], sim["final_accuracy"], flush=True)
    if not args.skip_deploy:
        results["deployment_5_rounds"] = dep = deployment(replace(base))
        print("deployment", dep["wall_s"], dep["final_accuracy"], flush=True)
    target = central["accuracy"] - 0.02
    if args.long_rounds:
        long_cfg = replace(base, rounds=args.long_rounds, run_id="")
        long, res = simulation(long_cfg, f"{args.long_rounds} rounds x 3 drones")
        reached = [r["round"] for r in res.rounds if r["global_accuracy"] >= target]
        long["first_round_within_2_points"] = reached[0] if reached else None
        long["best_accuracy"] = max(long["accuracy_per_round"])
        results["simulation_long"] = long
        from proxima.federated.curve import plot_curve

        curve = args.out.with_name(args.out.stem + "_curve.png")
        plot_curve(res.rounds, curve, f"FedAvg, one view per drone, {args.long_rounds} rounds",
                   reference=central["accuracy"])  # fmt: skip
        print("long", long["wall_s"], long["best_accuracy"], reached[:1], flush=True)
    results["targets"] = {
        "accuracy_within_2_points_of_centralised": {
            "threshold": round(target, 4),
            "after_5_rounds": sim["final_accuracy"],
            "met_after_5_rounds": sim["final_accuracy"] >= target,
            "first_round_met": results.get("simulation_long", {}).get(
                "first_round_within_2_points"
            ),
        },
        "five_rounds_three_drones_wall_s_le_60": {
            "wall_s": sim["wall_s"],
            "met": sim["wall_s"] <= 60,
            "load_average": sim["load_average"],
        },
    }
    for k in ("simulation_5_rounds", "simulation_long"):
        if k in results:
            results[k].pop("rounds", None)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(results, indent=1))
    print(f"-> {args.out}")


def _flwr_version() -> str:
    from importlib.metadata import version

    return version("flwr")


if __name__ == "__main__":
    main()
