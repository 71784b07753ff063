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


class TrainingSettings(DeploymentSettings):
    """Federated runs started from the console: on Flower's Deployment Runtime (a local
    SuperLink with one SuperNode per drone, the default, or the drones' own SuperNodes)
    or its Simulation Runtime."""

    enabled: bool = True
    flower_runtime: Literal["deployment", "simulation"] = "deployment"
