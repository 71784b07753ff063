"""Login throttling: failed logins slow down the user name and the client address they
came from, with an exponential back-off that is bounded, so an attacker can neither try
passwords fast nor lock the real supervisor out.

Two counters: failures of one client address (any user name), and failures of one user
name (any address). Once either has passed `free_failures`, each further failure blocks
for `base_s`, doubling with every failure, never longer than `max_s`:

- an address's failures block that address for every user name;
- a user name's failures set how long the block is, but it applies only to the address
  that failed (the pair user name + address), so a supervisor logging in from another
  machine is never held back by an attacker guessing their password elsewhere, and an
  attacker's attempts never extend the block of someone else's address.

An attempt during a block is refused at once (the password is not even checked) and does
not lengthen it. A successful login resets the user name's counter and its block from
that address. Counters are forgotten `forget_s` after their last failure.

State is in memory, per server process: a restart forgets it (a deliberate way out for
a locked-out operator, and why nothing here is written per attempt). The number of keys
is bounded (`max_keys`): the stalest are dropped first.
"""

from __future__ import annotations

import math
import threading
import time
from collections import OrderedDict
from collections.abc import Callable, Hashable
from dataclasses import dataclass
from typing import TypeVar

K = TypeVar("K", bound=Hashable)


@dataclass(frozen=True)
class ThrottlePolicy:
    free_failures: int = 5  # failures before the first block
    base_s: float = 1.0  # the first block; doubles with every further failure
    max_s: float = 300.0  # no block is longer than this
    forget_s: float = 3600.0  # a counter idle this long starts again from zero

    def block_s(self, failures: int) -> float:
        """How long the `failures`-th failure blocks (0 while still free)."""
        over = failures - self.free_failures
        if over <= 0:
            return 0.0
        return min(self.max_s, self.base_s * 2.0 ** min(over - 1, 60))


@dataclass
class _Counter:
    failures: int = 0
    last_failure: float = 0.0
    blocked_until: float = 0.0
    reported_until: float = 0.0  # the block whose first refused attempt was reported


@dataclass(frozen=True)
class Refusal:
    """A login attempt refused during a block."""

    retry_after_s: int  # whole seconds, for the Retry-After header
    key: str  # "address" or "user"
    first: bool  # the first refused attempt of this block (report it once)


class LoginThrottle:
    """Thread-safe login throttle; `clock` is monotonic seconds."""

    def __init__(
        self,
        policy: ThrottlePolicy | None = None,
        *,
        clock: Callable[[], float] = time.monotonic,
        max_keys: int = 10_000,
    ) -> None:
        self.policy = policy or ThrottlePolicy()
        self.clock = clock
        self.max_keys = max_keys
        self._lock = threading.Lock()
        self._addresses: OrderedDict[str, _Counter] = OrderedDict()
        self._users: OrderedDict[str, _Counter] = OrderedDict()
        self._pairs: OrderedDict[tuple[str, str], _Counter] = OrderedDict()

    def check(self, username: str, address: str) -> Refusal | None:
        """None if this attempt may go ahead, else why and for how long it is refused."""
        now = self.clock()
        with self._lock:
            candidates = [
                ("address", self._get(self._addresses, address, now)),
                ("user", self._get(self._pairs, (username, address), now)),
            ]
            blocking = [
                (key, c) for key, c in candidates if c is not None and c.blocked_until > now
            ]
            if not blocking:
                return None
            key, counter = max(blocking, key=lambda kc: kc[1].blocked_until)
            first = counter.reported_until != counter.blocked_until
            counter.reported_until = counter.blocked_until
            return Refusal(math.ceil(counter.blocked_until - now), key, first)

    def failed(self, username: str, address: str) -> float:
        """Count a failed login; returns how long it now blocks (0: not yet)."""
        now = self.clock()
        with self._lock:
            addr = self._count(self._addresses, address, now)
            addr.blocked_until = now + self.policy.block_s(addr.failures)
            user = self._count(self._users, username, now)
            pair = self._touch(self._pairs, (username, address), now)
            pair.last_failure = now
            pair.blocked_until = now + self.policy.block_s(user.failures)
            return max(addr.blocked_until, pair.blocked_until) - now

    def succeeded(self, username: str, address: str) -> None:
        """A correct login: the user name's counter and its block from `address` end."""
        with self._lock:
            self._users.pop(username, None)
            self._pairs.pop((username, address), None)

    def reset(self) -> None:
        """Forget every counter."""
        with self._lock:
            self._addresses.clear()
            self._users.clear()
            self._pairs.clear()

    # --- bookkeeping ------------------------------------------------------------------------

    def _get(self, table: OrderedDict[K, _Counter], key: K, now: float) -> _Counter | None:
        counter = table.get(key)
        if counter is not None and now - counter.last_failure > self.policy.forget_s:
            del table[key]
            return None
        return counter

    def _touch(self, table: OrderedDict[K, _Counter], key: K, now: float) -> _Counter:
        counter = self._get(table, key, now)
        if counter is None:
            counter = table[key] = _Counter()
            while len(table) > self.max_keys:
                table.popitem(last=False)
        else:
            table.move_to_end(key)
        return counter

    def _count(self, table: OrderedDict[K, _Counter], key: K, now: float) -> _Counter:
        counter = self._touch(table, key, now)
        counter.failures += 1
        counter.last_failure = now
        return counter
