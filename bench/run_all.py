"""Every benchmark in bench/, one after another, at bounded sizes (what `make bench` runs).

    python -m bench.run_all [--out-dir bench/results/latest] [--only NAME,...]
                            [--checkpoint CKPT] [--timeout-s 1800]

Each benchmark runs as its own process (`python -m bench.NAME`) with smaller sizes than
the figures in the README were made with, so the whole round takes minutes rather than
hours; a failing or timed-out benchmark is recorded and the next one still runs. The
latency and error benchmarks need a model that never saw their held-out clips: without
`--checkpoint`, a temporal-split model is trained first (bounded epochs).

Results go to `--out-dir` (default `bench/results/latest/`, ignored by git, so that the
curated figures beside it stay those of the full runs), with `summary.json`: per
benchmark the command, exit status and seconds. Pass `--out-dir bench/results` to
overwrite the curated files. Exits 1 when any benchmark failed.
"""

from __future__ import annotations

import argparse
import json
import platform
import subprocess
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

RESULTS = Path(__file__).resolve().parent / "results"
DEFAULT_OUT = RESULTS / "latest"
TRAIN_EPOCHS = 15  # the temporal model for the held-out benchmarks (the README's: 60)


@dataclass(frozen=True)
class Bench:
    """One benchmark: its module under bench/ and its bounded arguments, in which `{out}`
    stands for the output folder and `{ckpt}` for the temporal-split checkpoint."""

    name: str
    args: str

    @property
    def needs_checkpoint(self) -> bool:
        return "{ckpt}" in self.args

    def command(self, out: Path, ckpt: Path | None) -> list[str]:
        fill = {"out": str(out), "ckpt": str(ckpt)}
        args = [a.format(**fill) for a in self.args.split()]
        return [sys.executable, "-m", f"bench.{self.name}", *args]


BENCHES = (
    Bench("gesture_inference", "--epochs 1 --out {out}/gesture_inference.json"),
    Bench(
        "pose_throughput",
        "--frames 100 --seconds 4 --max-streams 3 --out {out}/pose_throughput.json",
    ),
    Bench("still_operator", "--out {out}/still_operator.json"),
    Bench(
        "drone_latency",
        "--commands 50 --steps 3 --loss-samples 1 --out {out}/drone_latency.json",
    ),
    Bench(
        "command_latency",
        "--checkpoint {ckpt} --streams 6 --segments 20 --out {out}/command_latency.json",
    ),
    Bench("temporal_errors", "--checkpoint {ckpt} --out {out}/temporal_errors.json"),
    Bench(
        "fusion",
        "--checkpoint {ckpt} --seeds 1 --segments 8 --conditions clean --sim-seeds 1 "
        "--sim-segments 4 --depth-noise 0 --out {out}/fusion.json",
    ),
    Bench(
        "federated",
        "--central-checkpoint {ckpt} --rounds 2 --long-rounds 0 --skip-deploy "
        "--out {out}/federated.json",
    ),
    Bench("console_latency", "--streams 2 --duration 20 --out {out}/console_latency.json"),
)


def _run(command: list[str], timeout_s: float) -> tuple[int, float]:
    """Run `command` with its output passed through; (exit status, seconds). A timeout
    is status 124, as timeout(1) reports it."""
    started = time.perf_counter()
    print("$", " ".join(command), flush=True)
    try:
        code = subprocess.run(command, timeout=timeout_s).returncode
    except subprocess.TimeoutExpired:
        code = 124
    return code, round(time.perf_counter() - started, 1)


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out-dir", type=Path, default=DEFAULT_OUT, help="where results go")
    ap.add_argument("--only", default="", help="comma-separated benchmark names")
    ap.add_argument("--checkpoint", type=Path, help="a temporal-split model (default: train)")
    ap.add_argument("--timeout-s", type=float, default=1800.0, help="per benchmark")
    args = ap.parse_args(argv)
    names = [b.name for b in BENCHES]
    chosen = [n.strip() for n in args.only.split(",") if n.strip()] or names
    unknown = sorted(set(chosen) - set(names))
    if unknown:
        ap.error(f"unknown benchmark(s) {', '.join(unknown)}; choose from {', '.join(names)}")
    out: Path = args.out_dir
    out.mkdir(parents=True, exist_ok=True)
    runs: list[dict[str, object]] = []
    summary = {
        "date": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        "python": platform.python_version(),
        "out_dir": str(out),
        "runs": runs,
    }

    def record(name: str, command: list[str], code: int | None, seconds: float) -> None:
        runs.append({"name": name, "command": " ".join(command), "exit": code, "seconds": seconds})
        (out / "summary.json").write_text(json.dumps(summary, indent=1) + "\n")

    ckpt: Path | None = args.checkpoint
    selected = [b for b in BENCHES if b.name in chosen]
    if ckpt is None and any(b.needs_checkpoint for b in selected):
        ckpt = out / "gesture-temporal.pt"
        train = [sys.executable, "-m", "proxima.cli", "train", "--split", "temporal",
                 "--epochs", str(TRAIN_EPOCHS), "--threads", "1", "--out", str(ckpt)]  # fmt: skip
        code, seconds = _run(train, args.timeout_s)
        record("train_temporal", train, code, seconds)
        if code != 0:
            ckpt = None
    for bench in selected:
        command = bench.command(out, ckpt)
        if bench.needs_checkpoint and ckpt is None:
            print(f"{bench.name}: skipped, no temporal-split model", flush=True)
            record(bench.name, command, None, 0.0)
            continue
        code, seconds = _run(command, args.timeout_s)
        record(bench.name, command, code, seconds)
    failed = [str(r["name"]) for r in runs if r["exit"] != 0]
    for r in runs:
        status = "skipped" if r["exit"] is None else f"exit {r['exit']}"
        print(f"{r['name']!s:<18} {status:<8} {r['seconds']:>8.1f} s")
    outcome = f"failed: {', '.join(failed)}" if failed else "all ran"
    print(f"-> {out / 'summary.json'}; {outcome}")
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())
