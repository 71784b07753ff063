"""Flower's deployment engine on this machine: one SuperLink and one SuperNode per
drone, each a separate process on 127.0.0.1, and runs submitted with `flwr run`.

This is the same engine a fleet uses (docs/federated.md: SuperNodes on the drones'
onboard computers, TLS and node authentication); here everything is on loopback with
`--insecure`. The SuperLink speaks HTTP on one port (Fleet, Control and Runtime APIs);
every SuperNode needs a port of its own for its local Runtime API. All processes start
in their own process group so `stop()` can end each one with what it spawned (Flower's
SuperExec and app processes), by process id only.
"""

from __future__ import annotations

import contextlib
import json
import os
import signal
import socket
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from proxima.federated.config import APP_DIR, FLConfig, default_drone_name

BIN = Path(sys.executable).parent
HOST = "127.0.0.1"


class DeploymentError(RuntimeError):
    """A Flower process did not start, or the SuperLink refused a run."""


def free_port() -> int:
    with socket.socket() as s:
        s.bind((HOST, 0))
        return int(s.getsockname()[1])


def _toml_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return repr(value)
    return json.dumps(str(value))  # a TOML basic string is JSON-compatible


def write_toml(path: Path, values: dict[str, Any]) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("".join(f"{k} = {_toml_value(v)}\n" for k, v in values.items()))
    return path


@dataclass
class Drone:
    """One SuperNode: a drone's name and the facts its ClientApp reads (node config)."""

    name: str
    partition_id: int
    num_partitions: int
    data: str = ""  # the drone's data folder(s), ";"-separated ("" = default)
    samples_db: str = ""  # the console's sample store, for its labelled samples
    port: int = 0  # its Runtime API port (0 = pick a free one)

    def node_config(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "partition-id": self.partition_id,
            "num-partitions": self.num_partitions,
            "drone": self.name,
        }
        if self.data:
            out["data"] = self.data
        if self.samples_db:
            out["samples-db"] = self.samples_db
        return out


def default_drones(n: int, data: str = "", samples_db: str = "") -> list[Drone]:
    return [Drone(default_drone_name(i, n), i, n, data, samples_db) for i in range(n)]


@dataclass
class LocalFederation:
    """The processes of a deployment on loopback, and runs submitted to it."""

    workdir: Path
    drones: list[Drone]
    port: int = 0  # SuperLink port (0 = pick a free one)
    procs: dict[str, subprocess.Popen] = field(default_factory=dict)
    logs: dict[str, Path] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.workdir = Path(self.workdir)
        self.home = self.workdir / "flwr-home"
        self.port = self.port or free_port()
        for d in self.drones:
            d.port = d.port or free_port()

    @property
    def address(self) -> str:
        return f"{HOST}:{self.port}"

    def env(self) -> dict[str, str]:
        env = dict(os.environ)
        env["FLWR_HOME"] = str(self.home)
        env["PATH"] = f"{BIN}{os.pathsep}{env.get('PATH', '')}"  # flower-superexec & co
        env["FLWR_DISABLE_RUNTIME_DEPENDENCY_INSTALLATION"] = "1"
        for var in ("OMP_NUM_THREADS", "MKL_NUM_THREADS"):
            env.setdefault(var, "1")  # one torch thread per drone process
        env.setdefault("PYTHONUNBUFFERED", "1")
        return env

    def _spawn(self, name: str, args: list[str]) -> subprocess.Popen:
        self.workdir.mkdir(parents=True, exist_ok=True)
        log = self.workdir / f"{name}.log"
        self.logs[name] = log
        with log.open("ab") as out:
            proc = subprocess.Popen(
                args,
                stdout=out,
                stderr=subprocess.STDOUT,
                env=self.env(),
                cwd=self.workdir,
                start_new_session=True,  # own process group: stop() takes its children too
            )
        self.procs[name] = proc
        return proc

    # processes ----------------------------------------------------------------------------

    def start(self, timeout: float = 60.0) -> LocalFederation:
        """SuperLink first (waits until it listens), then one SuperNode per drone."""
        self.start_superlink(timeout)
        for d in self.drones:
            self.start_supernode(d)
        return self

    def start_superlink(self, timeout: float = 60.0) -> None:
        self.home.mkdir(parents=True, exist_ok=True)
        (self.home / "config.toml").write_text(
            '[superlink]\ndefault = "proxima-local"\n\n'
            f'[superlink.proxima-local]\naddress = "{self.address}"\ninsecure = true\n'
        )
        self._spawn(
            "superlink",
            [str(BIN / "flower-superlink"), "--insecure", "--host", HOST,
             "--port", str(self.port), "--disable-runtime-dependency-installation"],
        )  # fmt: skip
        self._wait_port(self.port, "superlink", timeout)

    def start_supernode(self, drone: Drone) -> subprocess.Popen:
        cfg_file = write_toml(self.workdir / f"node-{drone.name}.toml", drone.node_config())
        return self._spawn(
            f"supernode-{drone.name}",
            [str(BIN / "flower-supernode"), "--insecure", "--superlink", self.address,
             "--host", HOST, "--port", str(drone.port), "--node-config", str(cfg_file),
             "--max-wait-time", "600"],
        )  # fmt: skip

    def _wait_port(self, port: int, name: str, timeout: float) -> None:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            proc = self.procs[name]
            if proc.poll() is not None:
                raise DeploymentError(
                    f"{name} exited with code {proc.returncode}; log: {self.logs[name]}\n"
                    + self.tail(name)
                )
            with socket.socket() as s:
                s.settimeout(0.5)
                if s.connect_ex((HOST, port)) == 0:
                    return
            time.sleep(0.2)
        raise DeploymentError(f"{name} did not listen on {HOST}:{port} within {timeout:.0f} s")

    def pid(self, name: str) -> int:
        return self.procs[name].pid

    def alive(self) -> dict[str, bool]:
        return {n: p.poll() is None for n, p in self.procs.items()}

    def kill(self, name: str, sig: int = signal.SIGKILL) -> None:
        """Kill one process (not its group): what a crashing drone looks like."""
        proc = self.procs[name]
        if proc.poll() is None:
            os.kill(proc.pid, sig)
            proc.wait(timeout=10)

    def stop(self, grace: float = 5.0) -> None:
        """End every process this federation started, with its process group."""
        for name in reversed(list(self.procs)):
            proc = self.procs[name]
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.killpg(proc.pid, signal.SIGTERM)
        deadline = time.monotonic() + grace
        for proc in self.procs.values():
            with contextlib.suppress(subprocess.TimeoutExpired):
                proc.wait(timeout=max(0.1, deadline - time.monotonic()))
        for proc in self.procs.values():  # the group too: SuperExec and app processes
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.killpg(proc.pid, signal.SIGKILL)
            with contextlib.suppress(subprocess.TimeoutExpired):
                proc.wait(timeout=5)

    def __enter__(self) -> LocalFederation:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def tail(self, name: str, lines: int = 30) -> str:
        log = self.logs.get(name)
        if not log or not log.is_file():
            return ""
        return "\n".join(log.read_text(errors="replace").splitlines()[-lines:])

    # runs ---------------------------------------------------------------------------------

    def _flwr(self, *args: str, timeout: float = 120.0) -> dict[str, Any]:
        proc = subprocess.run(
            [str(BIN / "flwr"), *args, "--format", "json"],
            capture_output=True, text=True, env=self.env(), cwd=self.workdir, timeout=timeout,
        )  # fmt: skip
        try:
            out = json.loads(proc.stdout[proc.stdout.find("{") :])
        except ValueError:
            out = {"success": False, "error-message": (proc.stdout + proc.stderr)[-2000:]}
        if proc.returncode != 0 or not out.get("success", False):
            raise DeploymentError(f"flwr {args[0]} failed: {out.get('error-message', out)}")
        return out

    def submit(self, cfg: FLConfig) -> str:
        """Submit a run (the FAB in flower-app/ with `cfg` as its run config); returns
        Flower's run id. The ServerApp starts in the SuperLink's SuperExec.

        Raises:
            DeploymentError: the SuperLink refused the run or cannot be reached.
        """
        overrides = write_toml(self.workdir / f"run-{cfg.run_id or 'x'}.toml", cfg.to_run_config())
        out = self._flwr("run", str(APP_DIR), "proxima-local", "--run-config", str(overrides))
        return str(out["run-id"])

    def run_status(self, flwr_run_id: str) -> dict[str, Any]:
        """Flower's view of a run: `status` (e.g. "running", "finished:completed",
        "finished:failed") and `status-details`."""
        runs = self._flwr("ls", "proxima-local", "--run-id", str(flwr_run_id), timeout=60)["runs"]
        return runs[0] if runs else {}

    def stop_run(self, flwr_run_id: str) -> None:
        with contextlib.suppress(DeploymentError, subprocess.TimeoutExpired):
            self._flwr("stop", str(flwr_run_id), "proxima-local", timeout=60)
