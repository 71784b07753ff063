"""The priority arbiter: which stream's recognition drives the controlled drone.

Each stream reports how well it sees the operator (`Sight`, from
`proxima.pose.operator_sight`): FULL (`operator_visible`, feet included), PARTIAL (enough
landmarks to read gestures, but the feet left the image) or NONE. Streams are ranked
(main first). The rule, applied at every update:

- the highest-ranked stream that sees the operator FULL drives; if none does, the
  highest-ranked one that sees them at least PARTIAL drives; if none, nobody drives ("")
  and the operator is lost;
- the driving stream keeps its level for `hold_s` after it last had it (a blink of the
  pose estimator is no handover), and another stream must have held a level for
  `regain_s` without a break before it can take over at that level.

So, as in the paper, when the main drone's camera loses the operator's feet the secondary
drone (which sees the whole operator) takes over, and the main one takes control back
once it sees the whole operator again; a single camera whose view cuts the feet keeps
driving, because nothing better sees the operator. The drone watchdog uses the same
levels: it hovers only when no stream has seen the operator at PARTIAL or better.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

from proxima.types import Sight


@dataclass(frozen=True)
class Handover:
    """A change of the driving stream at stream time `t` ("" means none)."""

    t: float
    from_stream: str
    to_stream: str
    reason: str


@dataclass
class _Seen:
    sight: Sight = Sight.NONE
    last: dict[Sight, float] = field(default_factory=dict)  # last t at >= level
    since: dict[Sight, float] = field(default_factory=dict)  # start of the stretch >= level


_LEVELS = (Sight.FULL, Sight.PARTIAL)


class PriorityArbiter:
    """Tracks each stream's sight of the operator and decides the driving stream."""

    def __init__(self, streams: Sequence[str], hold_s: float = 1.0, regain_s: float = 1.0) -> None:
        if not streams:
            raise ValueError("the arbiter needs at least one stream")
        if len(set(streams)) != len(streams):
            raise ValueError(f"stream names must be unique: {list(streams)}")
        self.ranking = tuple(streams)
        self.hold_s = hold_s
        self.regain_s = regain_s
        self.active = ""
        self._seen = {s: _Seen() for s in streams}
        self._ended: set[str] = set()

    def _get(self, stream: str) -> _Seen:
        try:
            return self._seen[stream]
        except KeyError:
            raise ValueError(f"unknown stream {stream!r}; ranked: {self.ranking}") from None

    def sight(self, stream: str) -> Sight:
        """The stream's sight of the operator in its latest frame."""
        return self._get(stream).sight

    def observe(self, stream: str, t: float, sight: Sight) -> Handover | None:
        """Record how `stream` sees the operator at `t`, then re-decide.

        Raises:
            ValueError: `stream` is not one of the ranked streams.
        """
        seen = self._get(stream)
        for level in _LEVELS:
            if sight >= level:
                seen.last[level] = t
                seen.since.setdefault(level, t)
            else:
                seen.since.pop(level, None)
        seen.sight = Sight(sight)
        return self.decide(t)

    def end(self, stream: str, t: float) -> Handover | None:
        """The stream ended: it sees nobody from now on and cannot hold control."""
        seen = self._get(stream)
        seen.sight = Sight.NONE
        seen.since.clear()
        self._ended.add(stream)
        return self.decide(t, lost_reason="stream_ended" if stream == self.active else "")

    def _qualified(self, stream: str, level: Sight, t: float) -> bool:
        since = self._seen[stream].since.get(level)
        return since is not None and t - since >= self.regain_s

    def _holds(self, stream: str, level: Sight, t: float) -> bool:
        if stream in self._ended:
            return False
        last = self._seen[stream].last.get(level)
        return last is not None and t - last <= self.hold_s

    def _choose(self, t: float) -> str:
        active = self.active
        for level in _LEVELS:
            for stream in self.ranking:
                if stream == active and self._holds(stream, level, t):
                    return stream
                if self._qualified(stream, level, t):
                    return stream
                if not active and level in self._seen[stream].since:
                    # The first acquisition goes to the highest-ranked stream that sees
                    # the operator; lower ranks wait for it instead of flapping.
                    return ""
        return ""

    def decide(self, t: float, lost_reason: str = "") -> Handover | None:
        """Apply the priority rule at `t`; return the handover it caused, if any.
        `lost_reason` overrides "operator_lost" when the driving stream gives up."""
        active = self.active
        choice = self._choose(t)
        if choice == active:
            return None
        if not active:
            reason = "operator_acquired"
        elif choice and self.ranking.index(choice) < self.ranking.index(active):
            reason = "higher_priority_sees_operator"
        elif choice and self._holds(active, Sight.PARTIAL, t):
            reason = lost_reason or "operator_partly_visible"  # e.g. the feet left its view
        else:
            reason = lost_reason or "operator_lost"
        self.active = choice
        return Handover(t=t, from_stream=active, to_stream=choice, reason=reason)
