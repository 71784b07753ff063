"""The `[training]` settings section: which Flower runtime the console uses, and how its
deployment is secured and exposed.

Secure by default and cheap: the SuperLink always speaks TLS and accepts only SuperNodes
whose public keys it registered (Flower's SuperNode authentication). With no certificate
paths set, every start makes a throwaway CA, a loopback server certificate and one key
pair per local SuperNode in the runs folder (milliseconds; nothing else trusts them).
A real fleet sets the certificate paths, the drones' public keys, a `fleet_address` the
drones dial and `local_supernodes = false` (docs/federated.md: "A real fleet").

The SuperLink itself always binds 127.0.0.1: in flwr 1.41 and 1.42 its one port also serves the
Control API (submit runs, register SuperNodes) with no account authentication in the
open-source edition, so the drones reach it through the Fleet-only gateway
(`proxima.federated.gateway`) on `fleet_address`.
"""

from __future__ import annotations

import ipaddress
from pathlib import Path
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, model_validator

from proxima.federated.config import ConfigError, FLConfig
from proxima.shipped import FEDERATED_START, shipped_path


def split_address(address: str) -> tuple[str, int]:
    """`HOST:PORT` or `[IPv6]:PORT` -> (host, port).

    Raises:
        ValueError: no port, or a port outside 1-65535.
    """
    host, sep, port = address.rpartition(":")
    if not sep or not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise ValueError(f"expected HOST:PORT with a port in 1-65535, got {address!r}")
    return host.strip("[]"), int(port)


def is_loopback(host: str) -> bool:
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


class DeploymentSettings(BaseModel):
    """How the Deployment Runtime is secured and where drones reach it."""

    model_config = ConfigDict(extra="forbid")

    tls: bool = Field(default=True, description="TLS between SuperLink and SuperNodes")
    supernode_auth: bool = Field(
        default=True, description="only registered SuperNode keys may join"
    )
    ca_certfile: Path | None = Field(default=None, description="CA certificate (PEM) drones trust")
    server_certfile: Path | None = Field(default=None, description="SuperLink certificate (PEM)")
    server_keyfile: Path | None = Field(default=None, description="SuperLink private key (PEM)")
    authorized_keys: list[Path] = Field(
        default_factory=list,
        description="drones' SuperNode public keys (OpenSSH), registered at every start",
    )
    fleet_address: str = Field(
        default="",
        description="HOST:PORT drones dial (the Fleet-only gateway); empty: this machine",
    )
    local_supernodes: bool = Field(
        default=True,
        description="start one SuperNode per drone here (false: the drones run theirs)",
    )

    @model_validator(mode="after")
    def _check(self) -> DeploymentSettings:
        paths = (self.ca_certfile, self.server_certfile, self.server_keyfile)
        if any(p is not None for p in paths) and not all(p is not None for p in paths):
            raise ValueError(
                "set ca_certfile, server_certfile and server_keyfile together, or none "
                "(none: a throwaway CA for this machine only)"
            )
        if self.supernode_auth and not self.tls:
            raise ValueError("supernode_auth needs tls = true (Flower refuses it otherwise)")
        if self.fleet_address:
            host, _ = split_address(self.fleet_address)
            if not self.tls:
                raise ValueError(
                    "fleet_address needs tls = true: never plain HTTP off this machine"
                )
            if self.ca_certfile is None and not is_loopback(host):
                raise ValueError(
                    f"fleet_address {self.fleet_address!r} is reachable from other machines: "
                    "set ca_certfile, server_certfile and server_keyfile (proxima fl pki)"
                )
        if not self.local_supernodes:
            if not self.fleet_address:
                raise ValueError("local_supernodes = false needs a fleet_address the drones dial")
            if self.supernode_auth and not self.authorized_keys:
                raise ValueError(
                    "local_supernodes = false with supernode_auth: list the drones' public "
                    "keys in authorized_keys, or no drone can join"
                )
        return self


# What a console run trains with unless the supervisor's form says otherwise: the best
# recipe measured for the shipped 30-frame model (docs/federated.md, "The console's
# runs"): from the synthetic start, 0.874 / 0.876 after 5 rounds (seeds 0 / 1) against
# 0.682 / 0.661 for FLConfig's own defaults (one local epoch of FedAvg, a fresh model).
RUN_DEFAULTS: dict[str, bool | int | float | str] = {
    "strategy": "scaffold",
    "local-epochs": 20,
    "mirror": True,
    "keep-round": "best",
    "fraction-evaluate": 1.0,
}


class TrainingSettings(DeploymentSettings):
    """Federated runs started from the console: on Flower's Deployment Runtime (a local
    SuperLink with one SuperNode per drone, the default, or the drones' own SuperNodes)
    or its Simulation Runtime; from the synthetic operator's model with the measured
    recipe unless these settings say otherwise."""

    enabled: bool = True
    flower_runtime: Literal["deployment", "simulation"] = "deployment"
    start: str = Field(
        default="synthetic",
        description="the model console runs start from: 'synthetic' (the shipped "
        "models/synth-only-1560.pt), 'none' (a seeded fresh model) or a checkpoint path",
    )
    run_defaults: dict[str, bool | int | float | str] = Field(
        default_factory=lambda: dict(RUN_DEFAULTS),
        description="run config keys (as `proxima fl simulate --set`) every console run "
        "starts from; the form's fields override them",
    )

    @model_validator(mode="after")
    def _check_runs(self) -> TrainingSettings:
        if "init" in {k.replace("_", "-") for k in self.run_defaults}:
            raise ValueError("run_defaults: set the start model with `start`, not 'init'")
        if self.start not in ("synthetic", "none") and not Path(self.start).is_file():
            raise ValueError(f"start: no checkpoint at {self.start!r}")
        try:  # a bad key or value fails here, named, not at the first run
            FLConfig.from_run_config(self.run_defaults)
        except ConfigError as exc:
            raise ValueError(f"run_defaults: {exc}") from None
        return self

    def start_path(self) -> Path | None:
        """The checkpoint console runs start from, or None for a seeded fresh model.

        Raises:
            ValueError: `start` is 'synthetic' and the shipped file is missing.
        """
        if self.start == "none":
            return None
        if self.start != "synthetic":
            return Path(self.start).resolve()
        path = shipped_path(FEDERATED_START)
        if not path.is_file():
            raise ValueError(f"start: the shipped synthetic start is missing ({path})")
        return path.resolve()

    def run_config(self, **overrides: bool | int | float | str) -> FLConfig:
        """The FLConfig console runs start from: `run_defaults`, the start model as
        `init`, then `overrides` (e.g. the live model's `window`).

        Raises:
            ValueError: a missing start; ConfigError (a ValueError): a bad override, named
                (`run_defaults` were checked when the settings loaded).
        """
        start = self.start_path()
        values = {**self.run_defaults, "init": str(start) if start else "", **overrides}
        return FLConfig.from_run_config(values)
