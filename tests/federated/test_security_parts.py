"""The parts of the secured deployment that need no Flower process: certificates and
keys (checked with Flower's own loaders and a real TLS handshake), the `[training]`
settings, `proxima fl pki`, the Fleet-only gateway's routing, the command lines the
SuperLink and SuperNodes get, and the watchdog surviving its parent's SIGKILL."""

from __future__ import annotations

import json
import os
import socket
import ssl
import stat
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from cryptography import x509
from cryptography.hazmat.primitives import serialization
from cryptography.hazmat.primitives.asymmetric import ec, rsa
from starlette.testclient import TestClient
from typer.testing import CliRunner

from proxima.federated.deploy import Drone, LocalFederation, free_port
from proxima.federated.gateway import create_app
from proxima.federated.pki import (
    PKIError,
    check_public_key,
    check_server_files,
    make_ca,
    make_drone_key,
    make_server_cert,
)
from proxima.federated.settings import DeploymentSettings, TrainingSettings
from proxima.settings import Settings, SettingsError


@pytest.fixture()
def fleet(tmp_path: Path):
    ca_cert, ca_key = make_ca(tmp_path / "ca")
    creds = make_server_cert(tmp_path / "ground", ca_cert, ca_key, ["10.0.0.5", "ground.local"])
    return ca_cert, ca_key, creds


def test_server_certificate_is_signed_by_the_ca_for_the_fleet_and_loopback(fleet) -> None:
    ca_cert, ca_key, creds = fleet
    ca = x509.load_pem_x509_certificate(ca_cert.read_bytes())
    cert = x509.load_pem_x509_certificate(creds.cert.read_bytes())
    cert.verify_directly_issued_by(ca)
    san = cert.extensions.get_extension_for_class(x509.SubjectAlternativeName).value
    ips = {str(ip) for ip in san.get_values_for_type(x509.IPAddress)}
    assert ips == {"10.0.0.5", "127.0.0.1"}
    assert set(san.get_values_for_type(x509.DNSName)) == {"ground.local", "localhost"}
    for key in (ca_key, creds.key):
        assert stat.S_IMODE(key.stat().st_mode) == 0o600
    check_server_files(creds)


def _tls_server(creds) -> tuple[int, threading.Thread]:
    ctx = ssl.create_default_context(ssl.Purpose.CLIENT_AUTH)
    ctx.load_cert_chain(creds.cert, creds.key)
    sock = socket.socket()
    sock.bind(("127.0.0.1", 0))
    sock.listen(2)

    def serve() -> None:
        for _ in range(2):
            conn, _ = sock.accept()
            try:
                with ctx.wrap_socket(conn, server_side=True) as tls:
                    tls.sendall(b"ok")
            except (ssl.SSLError, OSError):
                pass
        sock.close()

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    return sock.getsockname()[1], thread


def test_a_real_tls_handshake_trusts_our_ca_and_no_other(fleet, tmp_path: Path) -> None:
    ca_cert, _, creds = fleet
    port, thread = _tls_server(creds)
    good = ssl.create_default_context(cafile=str(ca_cert))
    with (
        socket.create_connection(("127.0.0.1", port)) as raw,
        good.wrap_socket(raw, server_hostname="127.0.0.1") as tls,
    ):
        assert tls.recv(2) == b"ok"
    other, _ = make_ca(tmp_path / "other")
    bad = ssl.create_default_context(cafile=str(other))
    with (
        socket.create_connection(("127.0.0.1", port)) as raw,
        pytest.raises(ssl.SSLCertVerificationError),
    ):
        bad.wrap_socket(raw, server_hostname="127.0.0.1")
    thread.join(5)


def test_drone_keys_load_with_flowers_own_loaders(tmp_path: Path) -> None:
    from flwr.cli.supernode.register import try_load_public_key

    key = make_drone_key(tmp_path, "front")
    private = serialization.load_ssh_private_key(key.private_key.read_bytes(), None)
    assert isinstance(private, ec.EllipticCurvePrivateKey) and private.curve.name == "secp384r1"
    assert stat.S_IMODE(key.private_key.stat().st_mode) == 0o600
    assert key.public_key.read_text().startswith("ecdsa-sha2-nistp384 ")
    assert try_load_public_key(key.public_key)  # what `flwr supernode register` reads
    check_public_key(key.public_key)
    with pytest.raises(PKIError, match="letters, digits"):
        make_drone_key(tmp_path, "../evil")


def test_unusable_key_and_certificate_files_are_refused_by_name(tmp_path: Path, fleet) -> None:
    rsa_pub = tmp_path / "rsa.pub"
    rsa_pub.write_bytes(rsa.generate_private_key(65537, 2048).public_key().public_bytes(
        serialization.Encoding.OpenSSH, serialization.PublicFormat.OpenSSH))  # fmt: skip
    garbage = tmp_path / "garbage.pub"
    garbage.write_text("not a key\n")
    with pytest.raises(PKIError, match=r"rsa\.pub: expected an EC key"):
        check_public_key(rsa_pub)
    with pytest.raises(PKIError, match=r"garbage\.pub: not an OpenSSH public key"):
        check_public_key(garbage)
    with pytest.raises(PKIError, match=r"missing\.pub: cannot read"):
        check_public_key(tmp_path / "missing.pub")
    _, _, creds = fleet
    broken = creds.__class__(creds.ca_cert, garbage, creds.key)
    with pytest.raises(PKIError, match=r"garbage\.pub: not a readable PEM certificate"):
        check_server_files(broken)


@pytest.mark.parametrize(
    ("fields", "message"),
    [
        ({"ca_certfile": "ca.crt"}, "set ca_certfile, server_certfile and server_keyfile"),
        ({"tls": False}, "supernode_auth needs tls"),
        ({"tls": False, "supernode_auth": False, "fleet_address": "127.0.0.1:9092"},
         "fleet_address needs tls"),
        ({"fleet_address": "0.0.0.0:9092"}, "reachable from other machines"),
        ({"fleet_address": "ground"}, "expected HOST:PORT"),
        ({"local_supernodes": False}, "needs a fleet_address"),
        ({"local_supernodes": False, "fleet_address": "127.0.0.1:9092"}, "authorized_keys"),
    ],
)  # fmt: skip
def test_deployment_settings_refuse_what_cannot_be_secured(fields: dict, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        DeploymentSettings(**fields)


def test_training_section_in_a_settings_file(tmp_path: Path) -> None:
    toml = tmp_path / "proxima.toml"
    toml.write_text(
        '[training]\nfleet_address = "0.0.0.0:9092"\nlocal_supernodes = false\n'
        'ca_certfile = "g/ca.crt"\nserver_certfile = "g/server.pem"\n'
        'server_keyfile = "g/server.key"\nauthorized_keys = ["g/front.pub"]\n'
    )
    training = Settings.load(toml).training
    assert isinstance(training, TrainingSettings) and training.flower_runtime == "deployment"
    assert training.authorized_keys == [Path("g/front.pub")] and not training.local_supernodes
    assert TrainingSettings().tls and TrainingSettings().supernode_auth  # secure by default
    toml.write_text("[training]\ntls = false\n")
    with pytest.raises(
        SettingsError, match=r"(?s)proxima\.toml.*training.*supernode_auth needs tls"
    ):
        Settings.load(toml)


def test_pki_command_writes_what_goes_where_and_keeps_existing_keys(tmp_path: Path) -> None:
    from proxima.cli import app

    out = tmp_path / "fleet"
    args = ["fl", "pki", str(out), "--host", "10.0.0.5", "--drone", "front", "--drone", "left"]
    res = CliRunner().invoke(app, args)
    assert res.exit_code == 0, res.output
    expected = ["ca/ca.crt", "ca/ca.key", "ground/ca.crt", "ground/server.pem",
                "ground/server.key", "ground/authorized/front.pub",
                "ground/authorized/left.pub", "drones/front/ca.crt", "drones/front/front.key",
                "drones/left/left.key"]  # fmt: skip
    for rel in expected:
        assert (out / rel).is_file(), rel
    assert (out / "drones/front/ca.crt").read_bytes() == (out / "ca/ca.crt").read_bytes()
    key = (out / "drones/front/front.key").read_bytes()
    res = CliRunner().invoke(app, ["fl", "pki", str(out), "--drone", "front", "--drone", "right"])
    assert res.exit_code == 0 and "drone front: key kept" in res.output, res.output
    assert (out / "drones/front/front.key").read_bytes() == key
    assert (out / "ground/authorized/right.pub").is_file()
    security = DeploymentSettings(
        ca_certfile=out / "ground/ca.crt", server_certfile=out / "ground/server.pem",
        server_keyfile=out / "ground/server.key", fleet_address="0.0.0.0:9092",
        local_supernodes=False, authorized_keys=sorted((out / "ground/authorized").glob("*.pub")),
    )  # fmt: skip
    assert len(security.authorized_keys) == 3


def test_gateway_serves_the_fleet_api_only(tmp_path: Path, fleet) -> None:
    ca_cert, _, _ = fleet
    app = create_app(f"127.0.0.1:{free_port()}", ca_cert, timeout_s=2)  # nothing listens
    with TestClient(app) as client:
        for path in ("/v1/control/start-run", "/v1/control/register-node",
                     "/v1/runtime/pull-task-input", "/"):  # fmt: skip
            res = client.post(path, content=b"\x00")
            assert res.status_code == 404 and "only the Fleet API" in res.text
        assert client.get("/v1/fleet/pull-messages").status_code == 404  # POST only
        res = client.post("/v1/fleet/pull-messages", content=b"\x00",
                          headers={"content-type": "application/protobuf"})  # fmt: skip
        assert res.status_code == 502 and "SuperLink unreachable" in res.text


def test_command_lines_carry_tls_and_the_drones_keys(tmp_path: Path) -> None:
    fed = LocalFederation(tmp_path / "fl", [Drone("front", 0, 2), Drone("left", 1, 2)])
    fed._prepare_credentials()
    assert fed.server is not None and sorted(fed.keys) == ["front", "left"]
    args = fed.supernode_args(fed.drones[0])
    assert "--insecure" not in args
    assert args[args.index("--root-certificates") + 1] == str(fed.server.ca_cert)
    assert args[args.index("--auth-supernode-private-key") + 1] == str(
        fed.keys["front"].private_key
    )
    assert args[args.index("--superlink") + 1] == fed.address
    insecure = DeploymentSettings(tls=False, supernode_auth=False)
    plain = LocalFederation(tmp_path / "plain", [Drone("front", 0, 1)], security=insecure)
    plain._prepare_credentials()
    assert plain.server is None and "--insecure" in plain.supernode_args(plain.drones[0])


HOST = """
import json, subprocess, sys, time
sys.path.insert(0, sys.argv[1])
from proxima.federated.reaper import Reaper
r = Reaper()
# a group leader, and a grandchild that leaves for a session of its own (as Flower's
# SuperExec does)
p = subprocess.Popen(["sh", "-c", "setsid sleep 300 & echo $!; exec sleep 300"],
                     stdout=subprocess.PIPE, text=True, start_new_session=True)
r.watch(p.pid)
grandchild = int(p.stdout.readline())
time.sleep(1.5)  # the watchdog notes the tree every second
print(json.dumps([p.pid, grandchild, r.pid]), flush=True)
time.sleep(300)
"""


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


@pytest.mark.skipif(sys.platform != "linux", reason="process trees from /proc")
def test_watchdog_ends_the_tree_when_its_parent_is_killed(tmp_path: Path) -> None:
    backend = str(Path(__import__("proxima").__file__).resolve().parents[1])
    host = subprocess.Popen([sys.executable, "-c", HOST, backend], stdout=subprocess.PIPE,
                            text=True)  # fmt: skip
    try:
        assert host.stdout is not None
        leader, grandchild, watchdog = json.loads(host.stdout.readline())
        assert _alive(leader) and _alive(grandchild) and _alive(watchdog)
        os.kill(host.pid, 9)  # no clean-up code of the parent runs
        host.wait(5)
        deadline = time.monotonic() + 8
        while time.monotonic() < deadline and any(map(_alive, (leader, grandchild, watchdog))):
            time.sleep(0.1)
        assert not any(map(_alive, (leader, grandchild, watchdog)))
    finally:
        if host.poll() is None:
            host.kill()
