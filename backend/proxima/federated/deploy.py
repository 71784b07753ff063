"""Flower's deployment engine: a SuperLink, one SuperNode per local drone (each a
separate process), the Fleet-only gateway when drones dial in from other machines, and
runs submitted with `flwr run`.

Secured by default (`DeploymentSettings`): TLS between SuperLink and SuperNodes and
Flower's SuperNode authentication, so only SuperNodes whose public key was registered
(`flwr supernode register`, at every start) may join; a throwaway CA and keys are made in
the working folder unless a fleet's own are configured (docs/federated.md). The SuperLink
binds 127.0.0.1 (its port also serves the unauthenticated Control API); drones on other
machines reach its Fleet API through `proxima.federated.gateway`.

Every process starts in its own process group, so `stop()` ends each one with what it
spawned, by process id only; a watchdog (`proxima.federated.reaper`) ends them too when
the process that started them dies without stopping them (SIGTERM, SIGHUP, SIGKILL).
"""

from __future__ import annotations

import contextlib
import json
import os
import signal
import socket
import subprocess
import sys
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from proxima.federated.config import APP_DIR, FLConfig, default_drone_name
from proxima.federated.pki import (
    DroneKey,
    ServerCredentials,
    check_public_key,
    check_server_files,
    throwaway_pki,
)
from proxima.federated.reaper import GRACE_S, Reaper, descendants, end_all
from proxima.federated.settings import DeploymentSettings, split_address

BIN = Path(sys.executable).parent
HOST = "127.0.0.1"
CONNECTION = "proxima-local"  # the SuperLink's name in the Flower config of FLWR_HOME


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
    private_key: str = ""  # its SuperNode key ("" = the federation's throwaway key for it)
    root_certificates: str = ""  # CA bundle it trusts ("" = the federation's CA)

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


def _dial(address: str) -> str:
    """The address a local client dials for a server bound to `address`."""
    host, port = split_address(address)
    if host in ("0.0.0.0", "::", ""):
        host = HOST
    return f"[{host}]:{port}" if ":" in host else f"{host}:{port}"


@dataclass
class LocalFederation:
    """The Flower processes of a deployment on this machine, and runs submitted to it."""

    workdir: Path
    drones: list[Drone]
    port: int = 0  # SuperLink port on 127.0.0.1 (0 = pick a free one)
    security: DeploymentSettings = field(default_factory=DeploymentSettings)
    procs: dict[str, subprocess.Popen[bytes]] = field(default_factory=dict)
    logs: dict[str, Path] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.workdir = Path(self.workdir)
        self.home = self.workdir / "flwr-home"
        self.port = self.port or free_port()
        for d in self.drones:
            d.port = d.port or free_port()
        self.server: ServerCredentials | None = None  # TLS files of SuperLink and gateway
        self.keys: dict[str, DroneKey] = {}  # throwaway keys of local drones
        self.node_ids: dict[str, int] = {}  # registered SuperNode keys -> Flower node id
        self.reaper = Reaper()
        self._cli: set[subprocess.Popen[str]] = set()  # `flwr` calls in flight
        self._lock = threading.Lock()
        self._stopped = False

    @property
    def address(self) -> str:
        """The SuperLink (all its APIs) on loopback: what the `flwr` CLI talks to."""
        return f"{HOST}:{self.port}"

    @property
    def fleet_endpoint(self) -> str:
        """What SuperNodes dial: the gateway when there is one, else the SuperLink."""
        return _dial(self.security.fleet_address) if self.security.fleet_address else self.address

    @property
    def tls(self) -> bool:
        return self.security.tls

    def env(self) -> dict[str, str]:
        env = dict(os.environ)
        env["FLWR_HOME"] = str(self.home)
        env["PATH"] = f"{BIN}{os.pathsep}{env.get('PATH', '')}"  # flower-superexec & co
        env["FLWR_DISABLE_RUNTIME_DEPENDENCY_INSTALLATION"] = "1"
        env["FLWR_TELEMETRY_ENABLED"] = "0"  # nothing leaves for Flower's servers
        env["FLWR_DISABLE_UPDATE_CHECK"] = "1"
        for var in ("OMP_NUM_THREADS", "MKL_NUM_THREADS"):
            env.setdefault(var, "1")  # one torch thread per drone process
        env.setdefault("PYTHONUNBUFFERED", "1")
        return env

    def _spawn(self, name: str, args: list[str]) -> subprocess.Popen[bytes]:
        with self._lock:
            if self._stopped:
                raise DeploymentError(f"federation in {self.workdir} was stopped")
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
            self.reaper.watch(proc.pid)
            self.procs[name] = proc
            return proc

    # certificates and keys ---------------------------------------------------------------

    def _prepare_credentials(self) -> None:
        """The SuperLink's TLS files (configured, or a throwaway CA) and the local
        drones' keys; checks every configured file before any process starts.

        Raises:
            PKIError: a configured file that cannot be used (named).
        """
        sec = self.security
        for path in sec.authorized_keys:
            check_public_key(path)
        if not sec.tls:
            return
        need_keys = [d.name for d in self.drones if sec.supernode_auth and not d.private_key]
        if sec.ca_certfile is not None:
            assert sec.server_certfile is not None and sec.server_keyfile is not None
            self.server = ServerCredentials(sec.ca_certfile.resolve(),
                                            sec.server_certfile.resolve(),
                                            sec.server_keyfile.resolve())  # fmt: skip
            check_server_files(self.server)
            if need_keys:
                _, keys = throwaway_pki(self.workdir / "pki", need_keys, server=False)
                self.keys = {k.name: k for k in keys}
        else:
            self.server, keys = throwaway_pki(self.workdir / "pki", need_keys)
            self.keys = {k.name: k for k in keys}

    # processes ----------------------------------------------------------------------------

    def start(self, timeout: float = 60.0) -> LocalFederation:
        """SuperLink first (waits until it listens), the drones' keys registered, the
        gateway, then one SuperNode per local drone.

        Raises:
            PKIError: a configured certificate or key file cannot be used.
            DeploymentError: a process did not start or a key was not registered.
        """
        self._prepare_credentials()
        self.start_superlink(timeout)
        self.register_keys()
        if self.security.fleet_address:
            self.start_gateway(timeout)
        for d in self.drones:
            self.start_supernode(d)
        return self

    def start_superlink(self, timeout: float = 60.0) -> None:
        self.home.mkdir(parents=True, exist_ok=True)
        conn = f'[superlink.{CONNECTION}]\naddress = "{self.address}"\n'
        if self.server is not None:
            conn += f"root-certificates = {json.dumps(str(self.server.ca_cert))}\n"
            tls = ["--ssl-ca-certfile", str(self.server.ca_cert),
                   "--ssl-certfile", str(self.server.cert),
                   "--ssl-keyfile", str(self.server.key)]  # fmt: skip
            if self.security.supernode_auth:
                tls.append("--enable-supernode-auth")
        else:
            conn += "insecure = true\n"
            tls = ["--insecure"]
        (self.home / "config.toml").write_text(f'[superlink]\ndefault = "{CONNECTION}"\n\n{conn}')
        self._spawn(
            "superlink",
            [str(BIN / "flower-superlink"), *tls, "--host", HOST, "--port", str(self.port),
             "--disable-runtime-dependency-installation"],
        )  # fmt: skip
        self._wait_port(HOST, self.port, "superlink", timeout)

    def register_keys(self) -> None:
        """Register every authorised public key (settings' `authorized_keys` and the
        local drones' throwaway keys) with the SuperLink, in parallel.

        Raises:
            DeploymentError: the SuperLink refused a key (the file named).
        """
        if not (self.tls and self.security.supernode_auth):
            return
        pubs = [(p.stem, Path(p)) for p in self.security.authorized_keys]
        pubs += [(k.name, k.public_key) for k in self.keys.values()]
        calls = [(name, path, self._flwr_start("supernode", "register", str(path), CONNECTION,
                                               "--name", name)) for name, path in pubs]  # fmt: skip
        errors = []
        for name, path, proc in calls:
            try:
                out = self._flwr_result("supernode", proc, timeout=60)
                self.node_ids[name] = int(out["node-id"])
            except DeploymentError as exc:
                errors.append(f"{path}: {exc}")
        if errors:
            raise DeploymentError("SuperNode keys not registered: " + "; ".join(errors))

    def start_gateway(self, timeout: float = 60.0) -> None:
        """The Fleet-only gateway on `fleet_address` (the drones' way in)."""
        assert self.server is not None
        self._spawn(
            "gateway",
            [sys.executable, "-m", "proxima.federated.gateway",
             "--listen", self.security.fleet_address, "--upstream", self.address,
             "--ca-certfile", str(self.server.ca_cert), "--certfile", str(self.server.cert),
             "--keyfile", str(self.server.key)],
        )  # fmt: skip
        host, port = split_address(self.fleet_endpoint)
        self._wait_port(host, port, "gateway", timeout)

    def supernode_args(self, drone: Drone) -> list[str]:
        """The `flower-supernode` command line of a drone (TLS and key as configured)."""
        drone.port = drone.port or free_port()
        cfg_file = write_toml(self.workdir / f"node-{drone.name}.toml", drone.node_config())
        args = [str(BIN / "flower-supernode"), "--superlink", self.fleet_endpoint,
                "--host", HOST, "--port", str(drone.port), "--node-config", str(cfg_file),
                "--max-wait-time", "600"]  # fmt: skip
        if not self.tls:
            return [*args, "--insecure"]
        assert self.server is not None
        args += ["--root-certificates", drone.root_certificates or str(self.server.ca_cert)]
        key = drone.private_key or (
            str(self.keys[drone.name].private_key) if drone.name in self.keys else ""
        )
        return [*args, "--auth-supernode-private-key", key] if key else args

    def start_supernode(self, drone: Drone) -> subprocess.Popen[bytes]:
        return self._spawn(f"supernode-{drone.name}", self.supernode_args(drone))

    def restart_dead_supernodes(self) -> list[str]:
        """Start again every local SuperNode whose process has ended; returns their names."""
        dead = [d for d in self.drones if self.procs[f"supernode-{d.name}"].poll() is not None]
        for d in dead:
            proc = self.procs[f"supernode-{d.name}"]
            end_all(set(), descendants({proc.pid}), grace=1.0)  # its SuperExec, if left
            self._release(proc)
            self.start_supernode(d)
        return [d.name for d in dead]

    def _wait_port(self, host: str, port: int, name: str, timeout: float) -> None:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            proc = self.procs[name]
            if proc.poll() is not None:
                raise DeploymentError(
                    f"{name} exited with code {proc.returncode}; log: {self.logs[name]}\n"
                    + self.tail(name)
                )
            with socket.socket(socket.AF_INET6 if ":" in host else socket.AF_INET) as s:
                s.settimeout(0.5)
                if s.connect_ex((host.strip("[]"), port)) == 0:
                    return
            time.sleep(0.2)
        raise DeploymentError(f"{name} did not listen on {host}:{port} within {timeout:.0f} s")

    def pid(self, name: str) -> int:
        return self.procs[name].pid

    def alive(self) -> dict[str, bool]:
        return {n: p.poll() is None for n, p in self.procs.items()}

    def core_alive(self) -> bool:
        """The SuperLink (and the gateway, when there is one) are running."""
        alive = self.alive()
        return alive.get("superlink", False) and alive.get("gateway", True)

    def kill(self, name: str, sig: int = signal.SIGKILL) -> None:
        """Kill one process (not its group): what a crashing drone looks like."""
        proc = self.procs[name]
        if proc.poll() is None:
            os.kill(proc.pid, sig)
            proc.wait(timeout=10)

    def _release(self, proc: subprocess.Popen[Any]) -> None:
        """End what is left of `proc`'s group (only while `proc` is not yet reaped, so
        its PID cannot name another group) and forget it in the watchdog."""
        if proc.poll() is None:
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.killpg(proc.pid, signal.SIGKILL)
        with contextlib.suppress(subprocess.TimeoutExpired):
            proc.wait(timeout=5)
        self.reaper.release(proc.pid)

    def stop(self, grace: float = GRACE_S) -> None:
        """End every process this federation started, with its process group and every
        descendant (the SuperLink's SuperExec and ServerApp run in a session of their
        own), the `flwr` calls in flight included: SIGTERM, SIGKILL after `grace` s.
        Idempotent."""
        with self._lock:
            self._stopped = True
            procs: list[subprocess.Popen[Any]] = [*reversed(self.procs.values()), *self._cli]
        leaders = {p.pid for p in procs if p.poll() is None}  # not reaped: PIDs still ours
        end_all(leaders, descendants({p.pid for p in procs}), grace)
        for proc in procs:
            self._release(proc)
        self.reaper.close()

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

    def _flwr_start(self, *args: str) -> subprocess.Popen[str]:
        """Start a `flwr` CLI call in its own process group, watched like the others."""
        with self._lock:
            if self._stopped:
                raise DeploymentError(f"federation in {self.workdir} was stopped")
            proc = subprocess.Popen(
                [str(BIN / "flwr"), *args, "--format", "json"],
                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=self.env(),
                cwd=self.workdir, start_new_session=True,
            )  # fmt: skip
            self._cli.add(proc)
        self.reaper.watch(proc.pid)
        return proc

    def _flwr_result(
        self, what: str, proc: subprocess.Popen[str], timeout: float
    ) -> dict[str, Any]:
        try:
            stdout, stderr = proc.communicate(timeout=timeout)
        except subprocess.TimeoutExpired:
            self._release(proc)
            raise DeploymentError(f"flwr {what} gave no answer within {timeout:.0f} s") from None
        finally:
            with self._lock:
                self._cli.discard(proc)
            self.reaper.release(proc.pid)
        try:
            out = json.loads(stdout[stdout.find("{") :])
        except ValueError:
            out = {"success": False, "error-message": (stdout + stderr)[-2000:]}
        if proc.returncode != 0 or not out.get("success", False):
            raise DeploymentError(f"flwr {what} failed: {out.get('error-message', out)}")
        return dict(out)

    def _flwr(self, *args: str, timeout: float = 120.0) -> dict[str, Any]:
        return self._flwr_result(args[0], self._flwr_start(*args), timeout)

    def submit(self, cfg: FLConfig) -> str:
        """Submit a run (the FAB in flower-app/ with `cfg` as its run config); returns
        Flower's run id. The ServerApp starts in the SuperLink's SuperExec.

        Raises:
            DeploymentError: the SuperLink refused the run or cannot be reached.
        """
        overrides = write_toml(self.workdir / f"run-{cfg.run_id or 'x'}.toml", cfg.to_run_config())
        out = self._flwr("run", str(APP_DIR), CONNECTION, "--run-config", str(overrides))
        return str(out["run-id"])

    def run_status(self, flwr_run_id: str) -> dict[str, Any]:
        """Flower's view of a run: `status` (e.g. "running", "finished:completed",
        "finished:failed") and `status-details`."""
        runs = self._flwr("ls", CONNECTION, "--run-id", str(flwr_run_id), timeout=60)["runs"]
        return runs[0] if runs else {}

    def stop_run(self, flwr_run_id: str) -> None:
        with contextlib.suppress(DeploymentError):
            self._flwr("stop", str(flwr_run_id), CONNECTION, timeout=60)
