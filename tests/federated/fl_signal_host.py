"""A stand-in console for the signal tests: starts a run's Flower processes through
`FederatedRunner`, prints their PIDs as one JSON line, then sleeps until a signal ends
it. It handles no signal itself: whatever ends it, the watchdog must end the rest."""

from __future__ import annotations

import json
import signal
import sys
import time
from pathlib import Path

from fl_helpers import fast_config

from proxima.federated.deploy import default_drones
from proxima.federated.runner import FederatedRunner


def main(work: Path) -> None:
    # Default dispositions, whatever this was started under: a shell's background job
    # inherits SIGINT ignored and nohup SIGHUP ignored, and neither would end it.
    signal.signal(signal.SIGINT, signal.default_int_handler)
    signal.signal(signal.SIGHUP, signal.SIG_DFL)
    runner = FederatedRunner(work / "runs.db", work / "models", workdir=work / "fl",
                             drones=default_drones(2),
                             defaults=fast_config(rounds=50, min_clients=2))  # fmt: skip
    runner.ensure_federation()
    run_id = runner.start_run({})
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        run = runner.get_run(run_id) or {}
        if run.get("status") not in (None, "pending"):
            break
        time.sleep(0.3)
    print(json.dumps({"run": runner.get_run(run_id)["status"], **runner.status()["pids"]}),
          flush=True)  # fmt: skip
    time.sleep(3600)


if __name__ == "__main__":
    main(Path(sys.argv[1]))
