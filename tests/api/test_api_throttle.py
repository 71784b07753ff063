"""Login throttling: the back-off policy on its own (with a clock the test moves), then
through the API on real time with short delays: 429 with Retry-After, logged and in the
audit log, a correct password during a block refused unchecked, a successful login
resetting the user name's counter, another address not held back."""

from __future__ import annotations

import logging
import time
from pathlib import Path

import pytest
from api_helpers import ADMIN, make_settings
from fastapi.testclient import TestClient

from proxima.api import create_app
from proxima.api.throttle import LoginThrottle, ThrottlePolicy
from proxima.events import EventBus


class Clock:
    def __init__(self) -> None:
        self.now = 1000.0

    def __call__(self) -> float:
        return self.now


def throttle(**policy: float) -> tuple[LoginThrottle, Clock]:
    clock = Clock()
    return LoginThrottle(ThrottlePolicy(**policy), clock=clock), clock  # type: ignore[arg-type]


def test_back_off_doubles_and_is_bounded() -> None:
    policy = ThrottlePolicy(free_failures=3, base_s=1.0, max_s=8.0)
    assert [policy.block_s(n) for n in range(1, 10)] == [0, 0, 0, 1, 2, 4, 8, 8, 8]
    assert policy.block_s(10_000) == 8.0  # no overflow, still bounded


def test_an_address_is_blocked_after_its_free_failures() -> None:
    t, clock = throttle(free_failures=2, base_s=1.0, max_s=4.0)
    assert t.failed("a", "10.0.0.1") == 0 and t.failed("b", "10.0.0.1") == 0
    assert t.check("c", "10.0.0.1") is None
    assert t.failed("c", "10.0.0.1") == 1.0  # third failure of this address, any name
    refusal = t.check("d", "10.0.0.1")
    assert refusal is not None and refusal.key == "address" and refusal.retry_after_s == 1
    assert refusal.first and not t.check("d", "10.0.0.1").first  # type: ignore[union-attr]
    assert t.check("d", "10.0.0.2") is None  # another address is not
    clock.now += 1.01
    assert t.check("d", "10.0.0.1") is None


def test_refused_attempts_do_not_lengthen_a_block() -> None:
    t, clock = throttle(free_failures=1, base_s=2.0, max_s=60.0)
    t.failed("chief", "10.0.0.9")
    t.failed("chief", "10.0.0.9")
    for _ in range(100):  # hammering during the block changes nothing
        clock.now += 0.01
        assert t.check("chief", "10.0.0.9") is not None
    clock.now += 1.01  # 2 s after the failure, as if nothing had been tried meanwhile
    assert t.check("chief", "10.0.0.9") is None


def test_a_user_names_failures_hold_back_only_the_address_that_failed() -> None:
    t, _ = throttle(free_failures=3, base_s=10.0, max_s=300.0)
    # An attacker guessing chief's password from five addresses, one try each.
    for i in range(5):
        t.failed("chief", f"203.0.113.{i}")
    # The fourth and fifth failures of the name block the addresses they came from ...
    assert t.check("chief", "203.0.113.4") is not None
    assert t.check("chief", "203.0.113.4").key == "user"  # type: ignore[union-attr]
    # ... but chief at the ground station is not held back, and logs in.
    assert t.check("chief", "192.168.1.5") is None
    t.succeeded("chief", "192.168.1.5")
    # The success reset the name's counter: the next failure elsewhere is free again.
    assert t.failed("chief", "203.0.113.9") == 0


def test_a_mistyping_supervisor_waits_at_most_the_bound_then_gets_in() -> None:
    t, clock = throttle(free_failures=2, base_s=1.0, max_s=5.0)
    for _ in range(8):
        t.failed("chief", "192.168.1.5")
        clock.now += 5.0  # each time, wait out the block
    assert t.failed("chief", "192.168.1.5") == 5.0  # never more than max_s
    clock.now += 5.0
    assert t.check("chief", "192.168.1.5") is None
    t.succeeded("chief", "192.168.1.5")
    assert t.check("chief", "192.168.1.5") is None


def test_counters_are_forgotten_and_bounded() -> None:
    t, clock = throttle(free_failures=1, base_s=1.0, max_s=1.0, forget_s=60.0)
    t.failed("x", "10.0.0.1")
    t.failed("x", "10.0.0.1")
    clock.now += 61.0
    assert t.failed("x", "10.0.0.1") == 0  # forgotten: free again
    small = LoginThrottle(ThrottlePolicy(), max_keys=100)
    for i in range(1000):
        small.failed(f"user{i}", f"10.0.{i // 250}.{i % 250}")
    assert max(len(small._addresses), len(small._users), len(small._pairs)) <= 100


@pytest.fixture
def throttled(tmp_path: Path):  # type: ignore[no-untyped-def]
    settings = make_settings(
        tmp_path,
        server={
            "db_path": str(tmp_path / "console.db"),
            "viser_enabled": False,
            "login_free_failures": 2,
            "login_backoff_s": 1.0,
            "login_backoff_max_s": 2.0,
        },
    )
    return create_app(settings, EventBus())


def _login(client: TestClient, password: str):  # type: ignore[no-untyped-def]
    return client.post("/api/auth/login", json={"username": ADMIN[0], "password": password})


def test_the_api_answers_429_with_retry_after_and_records_it(
    throttled, caplog: pytest.LogCaptureFixture
) -> None:
    caplog.set_level(logging.WARNING, logger="proxima.api.routers.auth")
    with TestClient(throttled, client=("198.51.100.7", 40000)) as c:
        assert _login(c, "wrong-one").status_code == 401
        assert _login(c, "wrong-two").status_code == 401
        assert _login(c, "wrong-three").status_code == 401  # this one starts a 1 s block
        blocked = _login(c, ADMIN[1])  # the right password, but not even checked
        assert blocked.status_code == 429
        assert blocked.headers["Retry-After"] == "1"
        assert "too many failed logins" in blocked.json()["detail"]
        assert blocked.json()["errors"] == []
        assert _login(c, ADMIN[1]).status_code == 429
        assert "login throttled: user 'chief' from 198.51.100.7" in caplog.text
        # Another machine is not held back by this one's failures.
        with TestClient(throttled, client=("192.0.2.1", 40000)) as other:
            assert _login(other, ADMIN[1]).status_code == 200
        time.sleep(1.1)
        ok = _login(c, ADMIN[1])
        assert ok.status_code == 200
        token = ok.json()["token"]
        audit = c.get("/api/audit", headers={"Authorization": f"Bearer {token}"}).json()
    rows = [(e["action"], e["outcome"], e["client"]) for e in reversed(audit["entries"])]
    failed = ("auth.login_failed", "refused", "198.51.100.7")
    throttled_row = ("auth.login_throttled", "refused", "198.51.100.7")
    # One throttled row for the block, however many attempts it refused.
    assert rows == [
        failed,
        failed,
        failed,
        throttled_row,
        ("auth.login", "ok", "192.0.2.1"),
        ("auth.login", "ok", "198.51.100.7"),
    ]
    assert audit["entries"][-4]["detail"] == {"blocked": "address", "retry_after_s": 1}


def test_a_bounded_block_never_locks_the_supervisor_out(throttled) -> None:
    with TestClient(throttled, client=("198.51.100.8", 40000)) as c:
        for _ in range(6):  # keep failing: the block grows to its bound and stays there
            r = _login(c, "still-wrong")
            if r.status_code == 429:
                assert int(r.headers["Retry-After"]) <= 2
                time.sleep(int(r.headers["Retry-After"]) + 0.05)
        assert _login(c, "still-wrong").status_code in (401, 429)
        deadline = time.monotonic() + 2.5  # login_backoff_max_s, plus a margin
        while (r := _login(c, ADMIN[1])).status_code == 429:
            assert time.monotonic() < deadline, "blocked longer than the bound"
            time.sleep(0.2)
        assert r.status_code == 200
