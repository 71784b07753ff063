"""The deployment engine secured, for real on loopback: TLS between SuperLink and
SuperNodes and Flower's SuperNode authentication, with a CA and keys made in the test.
An authorised drone joins and trains, an unknown key is refused while the run goes on
with the others, a SuperNode that does not trust the SuperLink's CA cannot connect, and
the Fleet-only gateway carries drones but not the Control API."""

from __future__ import annotations

import ssl
import time
from pathlib import Path

import certifi
import httpx
import pytest
from fl_helpers import fast_config

from proxima.events import EventBus
from proxima.federated.deploy import BIN, Drone, LocalFederation, default_drones, free_port
from proxima.federated.pki import make_ca, make_drone_key, make_server_cert
from proxima.federated.runner import FederatedRunner
from proxima.federated.settings import DeploymentSettings

pytestmark = pytest.mark.slow


def _wait(predicate, timeout: float) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(0.3)
    return predicate()


def test_authorised_drones_train_and_an_unknown_key_is_refused(tmp_path: Path) -> None:
    """Two drones with registered keys train one round; a third SuperNode with a key of
    its own that nobody registered is refused at activation, and the run completes."""
    stranger = make_drone_key(tmp_path / "stranger", "intruder")
    drones = [*default_drones(2), Drone("intruder", 2, 3, private_key=str(stranger.private_key))]
    runner = FederatedRunner(tmp_path / "runs.db", tmp_path / "models", bus=EventBus(),
                             workdir=tmp_path / "fl", drones=drones,
                             defaults=fast_config(rounds=1, min_clients=2))  # fmt: skip
    t0 = time.monotonic()
    try:
        fed = runner.ensure_federation()
        started = time.monotonic() - t0
        st = runner.status()
        assert st["tls"] and st["supernode_auth"]
        assert sorted(st["registered_nodes"]) == ["front", "left"]
        runner.start_run({"started_by": "test"})
        run = runner.wait(timeout=240)
        intruder = fed.procs["supernode-intruder"]
        assert _wait(lambda: intruder.poll() is not None, 30), "the unknown SuperNode still runs"
        intruder_log = fed.tail("supernode-intruder", 200)
        superlink_log = fed.tail("superlink", 2000)
    finally:
        runner.close()
    wall = time.monotonic() - t0
    assert run is not None and run["status"] == "completed", run and run["detail"]
    assert [r["round"] for r in run["rounds"]] == [0, 1]
    clients = run["rounds"][1]["clients"]
    assert sorted(c["drone"] for c in clients) == ["front", "left"]
    assert all(c["status"] == "ok" and c["samples"] > 0 for c in clients)
    assert run["rounds"][1]["global_accuracy"] > run["rounds"][0]["global_accuracy"]
    assert intruder.returncode != 0
    assert "Failed to activate SuperNode" in intruder_log, intruder_log
    assert "No SuperNode found with the given public key" in superlink_log
    print(f"federation up in {started:.1f} s; one TLS round and close in {wall:.1f} s")


@pytest.fixture()
def fleet_pki(tmp_path: Path) -> dict[str, Path]:
    """A fleet's own CA and ground-station certificate (not the throwaway ones), one
    authorised drone key, and a second CA nobody uses."""
    ca_cert, ca_key = make_ca(tmp_path / "ca")
    creds = make_server_cert(tmp_path / "ground", ca_cert, ca_key, ["127.0.0.1"])
    front = make_drone_key(tmp_path / "drones" / "front", "front")
    other_ca, _ = make_ca(tmp_path / "other-ca", name="someone else's CA")
    return {"ca": creds.ca_cert, "cert": creds.cert, "key": creds.key,
            "front_key": front.private_key, "front_pub": front.public_key,
            "other_ca": other_ca}  # fmt: skip


def test_supernode_without_the_ca_cannot_connect(tmp_path: Path, fleet_pki) -> None:
    """With the fleet's certificates from settings: the drone holding the CA and its
    registered key joins; one trusting only the public CAs and one trusting another CA
    fail the TLS handshake and exit, and one speaking plain HTTP never gets an answer."""
    key = str(fleet_pki["front_key"])
    security = DeploymentSettings(ca_certfile=fleet_pki["ca"], server_certfile=fleet_pki["cert"],
                                  server_keyfile=fleet_pki["key"],
                                  authorized_keys=[fleet_pki["front_pub"]])  # fmt: skip
    fed = LocalFederation(tmp_path / "fl", [Drone("front", 0, 3, private_key=key)],
                          security=security)  # fmt: skip
    bad = {
        "public-cas": Drone("public-cas", 1, 3, private_key=key, root_certificates=certifi.where()),
        "other-ca": Drone(
            "other-ca", 2, 3, private_key=key, root_certificates=str(fleet_pki["other_ca"])
        ),
    }
    try:
        fed.start()
        assert sorted(fed.node_ids) == ["front"]
        procs = {name: fed.start_supernode(d) for name, d in bad.items()}
        procs["plain-http"] = fed._spawn("supernode-plain-http", [
            str(BIN / "flower-supernode"), "--insecure", "--superlink", fed.address,
            "--port", str(free_port()), "--max-retries", "3"])  # fmt: skip
        assert _wait(lambda: all(p.poll() is not None for p in procs.values()), 60), {
            n: p.poll() for n, p in procs.items()}  # fmt: skip
        nodes = fed._flwr("supernode", "ls", "proxima-local")["nodes"]
        logs = {name: fed.tail(f"supernode-{name}", 200) for name in procs}
        assert fed.alive()["supernode-front"]
    finally:
        fed.stop()
    assert [n["node-id"] for n in nodes if n["status"] == "online"] == [
        str(fed.node_ids["front"])]  # fmt: skip
    assert all(p.returncode != 0 for p in procs.values())
    for name in ("public-cas", "other-ca"):
        assert "CERTIFICATE_VERIFY_FAILED" in logs[name], logs[name]
    assert "Connection attempt failed" in logs["plain-http"], logs["plain-http"]


def test_drones_train_through_the_fleet_gateway_which_refuses_the_control_api(
    tmp_path: Path, fleet_pki
) -> None:
    """SuperNodes that dial the fleet address (the gateway) train a round; the Control
    API is not reachable there, only on the SuperLink's loopback port."""
    gateway = f"127.0.0.1:{free_port()}"
    security = DeploymentSettings(ca_certfile=fleet_pki["ca"], server_certfile=fleet_pki["cert"],
                                  server_keyfile=fleet_pki["key"],
                                  fleet_address=gateway)  # fmt: skip
    runner = FederatedRunner(tmp_path / "runs.db", tmp_path / "models", workdir=tmp_path / "fl",
                             drones=default_drones(2), security=security,
                             defaults=fast_config(rounds=1, min_clients=2))  # fmt: skip
    ctx = ssl.create_default_context(cafile=str(fleet_pki["ca"]))
    try:
        fed = runner.ensure_federation()
        assert fed.fleet_endpoint == gateway and fed.supernode_args(fed.drones[0])[2] == gateway
        with httpx.Client(verify=ctx, timeout=10) as http:
            control = http.post(f"https://{gateway}/v1/control/list-runs", content=b"")
            register = http.post(f"https://{gateway}/v1/control/register-node", content=b"")
        runner.start_run({})
        run = runner.wait(timeout=240)
    finally:
        runner.close()
    assert control.status_code == 404 and register.status_code == 404
    assert run is not None and run["status"] == "completed", run and run["detail"]
    assert sorted(c["drone"] for c in run["rounds"][1]["clients"]) == ["front", "left"]
