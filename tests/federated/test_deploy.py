"""Flower's deployment engine for real: a SuperLink and three SuperNodes as separate
processes on 127.0.0.1, runs submitted with `flwr run`, followed through the database
and the bus as the console sees them."""

from __future__ import annotations

import os
import threading
from pathlib import Path

import pytest
from fl_helpers import fast_config

from proxima.events import EventBus
from proxima.federated.deploy import LocalFederation, default_drones
from proxima.federated.events import TrainingRoundEvent, TrainingRunEvent
from proxima.federated.runner import FederatedRunner
from proxima.gesture.classifier import GestureClassifier

pytestmark = pytest.mark.slow


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    return True


def _runner(tmp_path: Path, samples_db: Path | None = None, **cfg: object) -> FederatedRunner:
    drones = default_drones(3, samples_db=str(samples_db or ""))
    return FederatedRunner(tmp_path / "runs.db", tmp_path / "models", bus=EventBus(),
                           workdir=tmp_path / "fl", drones=drones,
                           defaults=fast_config(**cfg))  # fmt: skip


@pytest.fixture(scope="module")
def deployed(tmp_path_factory, sample_store):
    """One 3-round run on the deployment engine (one run serves every test here: each
    costs a minute or more). The front drone's sample store holds a good and a corrupt
    sample; the left drone's SuperNode is killed once round 1 is scored, so round 2
    waits for it until the round timeout and round 3 runs on the two drones left."""
    tmp = tmp_path_factory.mktemp("deploy")
    db, good, bad = sample_store
    # The round timeout is what round 2 waits for the dead drone: long enough that the
    # live drones finish on a machine busy with other tests (45 s was not, at times).
    runner = _runner(tmp, db, include_samples=True, rounds=3, min_clients=2,
                     round_timeout_s=75.0)  # fmt: skip
    events: list = []
    victim: dict[str, int] = {}
    killed = threading.Event()

    def on_event(ev: object) -> None:
        # Round 1 is scored: round 2's messages are out; the left drone dies now.
        if isinstance(ev, TrainingRoundEvent) and ev.round == 1 and not killed.is_set():
            fed = runner.federation
            assert fed is not None
            victim["pid"] = fed.pid("supernode-left")
            fed.kill("supernode-left")
            killed.set()

    runner.listeners.append(on_event)
    sub = runner.bus.subscribe(types=["training_round", "training_run"])  # type: ignore[union-attr]
    try:
        runner.ensure_federation()
        pids = dict(runner.status()["pids"])
        run_id = runner.start_run({"started_by": "test"})
        run = runner.wait(timeout=480)
        while (ev := sub.get(timeout=0.1)) is not None:
            events.append(ev)
    finally:
        runner.close()
    return {"run": run, "run_id": run_id, "events": events, "pids": pids, "bad": bad,
            "good": good, "killed": killed.is_set(), "victim": victim}  # fmt: skip


def _rounds(deployed) -> dict[int, dict]:  # type: ignore[no-untyped-def]
    run = deployed["run"]
    assert run is not None and run["status"] == "completed", run and run["detail"]
    return {r["round"]: r for r in run["rounds"]}


def test_rounds_on_three_supernodes_beat_round_zero(deployed) -> None:
    run = deployed["run"]
    by_round = _rounds(deployed)
    assert run["engine"] == "deployment" and run["flwr_run_id"]
    assert sorted(by_round) == [0, 1, 2, 3]
    acc = [by_round[r]["global_accuracy"] for r in range(4)]
    assert acc[3] > acc[0] + 0.2, acc
    clients = by_round[1]["clients"]  # before the kill: every drone trained
    assert sorted(c["drone"] for c in clients) == ["front", "left", "right"]
    assert all(c["status"] == "ok" and c["samples"] > 0 for c in clients)
    assert set(deployed["pids"]) == {"superlink", "supernode-front", "supernode-left",
                                     "supernode-right"}  # fmt: skip
    assert not any(_pid_alive(p) for p in deployed["pids"].values())  # all stopped
    clf = GestureClassifier.load(run["checkpoint"])
    assert clf.metadata["test_accuracy"] == pytest.approx(acc[3])
    assert Path(run["model_card"]).is_file()


def test_events_carry_rounds_and_run_states(deployed) -> None:
    events = deployed["events"]
    rounds = [e for e in events if isinstance(e, TrainingRoundEvent)]
    assert [e.round for e in rounds] == [0, 1, 2, 3]
    assert all(e.run_id == deployed["run_id"] and e.rounds_total == 3 for e in rounds)
    assert len(rounds[1].clients) == 3 and rounds[1].to_dict()["type"] == "training_round"
    states = [e.status for e in events if isinstance(e, TrainingRunEvent)]
    assert states[0] == "pending" and states[-1] == "completed" and "running" in states


def test_corrupt_local_sample_is_reported_and_the_run_goes_on(deployed) -> None:
    rounds = _rounds(deployed)
    front = [c for r in (1, 2, 3) for c in rounds[r]["clients"] if c["drone"] == "front"]
    assert len(front) == 3 and all(c["status"] == "ok" for c in front)
    assert all(f"sample {deployed['bad']} skipped" in c["detail"] for c in front)
    assert all("1 console sample(s) used" in c["detail"] for c in front)
    others = [c for r in (1, 2, 3) for c in rounds[r]["clients"]
              if c["drone"] != "front" and c["status"] == "ok"]  # fmt: skip
    assert others and all("skipped" not in c["detail"] for c in others)


def test_killing_a_supernode_mid_run_still_completes_it(deployed) -> None:
    by_round = _rounds(deployed)
    assert deployed["killed"] and not _pid_alive(deployed["victim"]["pid"])
    left2 = [c for c in by_round[2]["clients"] if c["drone"] == "left"]
    assert left2 and left2[0]["status"] == "failed", by_round[2]["clients"]
    assert by_round[2]["clients_ok"] == 2 and by_round[2]["clients_failed"] == 1
    assert sorted(c["drone"] for c in by_round[3]["clients"] if c["status"] == "ok") == [
        "front", "right"]  # fmt: skip
    assert by_round[3]["global_accuracy"] > by_round[0]["global_accuracy"]


def test_local_federation_stops_every_process(tmp_path: Path) -> None:
    fed = LocalFederation(tmp_path / "fl", default_drones(2)).start()
    try:
        pids = {n: p.pid for n, p in fed.procs.items()}
        assert all(fed.alive().values()) and len(pids) == 3
    finally:
        fed.stop()
    assert not any(_pid_alive(p) for p in pids.values())
