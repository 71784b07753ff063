"""Every Flower process the console starts (SuperLink, SuperNodes, their SuperExecs,
the ServerApp and ClientApp processes, `flwr` calls) ends when the console stops:
through `FederatedRunner.close()`, and through the watchdog when the console is ended
by SIGTERM or SIGINT (or killed) without closing anything."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from fl_helpers import fast_config
from fl_procs import descendants, subreaper, wait_gone

from proxima.federated.deploy import default_drones
from proxima.federated.runner import FederatedRunner

pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(sys.platform != "linux", reason="process trees from /proc"),
]
HERE = Path(__file__).resolve().parent
LEFT_WITHIN_S = 8.0  # "a few seconds": SIGTERM, a 5 s grace, then SIGKILL at the latest


def _wait_for(root: int, word: str, timeout: float) -> dict[int, str]:
    """Wait until a descendant of `root` runs a command containing `word`."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        tree = descendants(root)
        if any(word in cmd for cmd in tree.values()):
            return tree
        time.sleep(0.3)
    raise AssertionError(f"no {word!r} process within {timeout:.0f} s: {descendants(root)}")


def test_close_ends_every_flower_process_of_a_running_run(tmp_path: Path) -> None:
    runner = FederatedRunner(tmp_path / "runs.db", tmp_path / "models", workdir=tmp_path / "fl",
                             drones=default_drones(2),
                             defaults=fast_config(rounds=50, min_clients=2))  # fmt: skip
    with subreaper():
        before = set(descendants(os.getpid()))
        try:
            runner.ensure_federation()
            run_id = runner.start_run({})
            tree = _wait_for(os.getpid(), "flwr-clientapp", 120)  # a drone is training
        finally:
            t0 = time.monotonic()
            runner.close()
            closed_in = time.monotonic() - t0
        left = wait_gone(os.getpid(), LEFT_WITHIN_S, ignore=before)
    assert not left, left
    assert closed_in < LEFT_WITHIN_S, closed_in
    names = " ".join(tree.values())
    for proc in ("flower-superlink", "flower-supernode", "flower-superexec", "flwr-serverapp"):
        assert proc in names, names
    run = runner.get_run(run_id)
    assert run is not None and run["status"] == "stopped" and run["detail"] == "the console stopped"
    print(f"{len(tree)} processes, close() took {closed_in:.1f} s")


# The stand-in console has no handler: SIGTERM (and SIGHUP, whose default action is the
# same) end it at once, SIGINT through Python's KeyboardInterrupt and interpreter exit.
@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT], ids=["SIGTERM", "SIGINT"])
def test_a_signal_on_the_console_ends_every_flower_process(tmp_path: Path, sig: int) -> None:
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(HERE), *sys.path]))
    with subreaper():
        # Processes of earlier tests in this session (a browser, a simulator) are not ours.
        before = set(descendants(os.getpid()))
        host = subprocess.Popen([sys.executable, str(HERE / "fl_signal_host.py"), str(tmp_path)],
                                stdout=subprocess.PIPE, text=True, env=env)  # fmt: skip
        try:
            assert host.stdout is not None
            ready = json.loads(host.stdout.readline() or "{}")
            assert ready.get("run") in ("running", "waiting"), ready
            tree = _wait_for(host.pid, "flwr-clientapp", 120)
            t0 = time.monotonic()
            host.send_signal(sig)
            host.wait(timeout=10)
            left = wait_gone(os.getpid(), LEFT_WITHIN_S, ignore=before)
            gone_in = time.monotonic() - t0
        finally:
            if host.poll() is None:
                host.kill()
    assert not left, left
    assert host.returncode != 0
    assert {"superlink", "supernode-front", "supernode-left"} <= set(ready)
    assert len(tree) >= 8, tree  # SuperLink, SuperExecs, ServerApp, SuperNodes, ClientApp
    print(f"{signal.Signals(sig).name}: {len(tree)} processes gone in {gone_in:.1f} s")
