"""Score the commands of a run against a stitched stream's ground truth.

Which gestures should cause a command follows the arming rules: `have_command` is always
expected (it arms, and is itself a command); any other gesture is expected only if
control was armed at some time during its segment (from the run's arming events, so a
missed `have_command` counts as one miss, and the motion gestures performed while the
drone correctly ignored the operator are counted as `blocked`, not as misses). Without
arming events, arming is simulated on the script. A command belongs to the segment
performed at its time (a segment lasts from its onset to the next segment's onset, so
the transition after a gesture still belongs to it).

- hit: the first command of a segment that names its expected gesture; latency is
  command time minus the segment's onset.
- late hit: the previous segment's expected command, arriving after the next segment
  began (the previous one had none yet); its latency counts from its own onset.
- repeat: a further command for the same segment and gesture (a spurious command: the
  drone would move twice).
- wrong: any other command (a gesture nobody performed then). Split by what it does to
  the drone, where the command says whether control was armed when it was sent
  (`armed`, as a run records it): a `have_command` while armed only re-arms (`re_arms`,
  nothing moves), one while disarmed arms control nobody asked for (`wrong_arming`), and
  the rest act on the drone (`wrong_acting`: motions, landings, the aborts).
- safety: the hover sent when no stream sees the operator (stream ""), e.g. at the end
  of a replay; counted apart.
- missed: a segment whose expected command never came.
- on time: hits within 2.5 s of the onset, as a fraction of the expected commands.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from proxima.control.arming import ABORT_GESTURE, ARM_GESTURE


@dataclass
class Score:
    """Counts and latencies of one or more runs (`merge` adds runs together)."""

    seconds: float = 0.0
    expected: int = 0
    hits: int = 0
    late: int = 0
    missed: int = 0
    blocked: int = 0
    repeats: int = 0
    wrong: int = 0
    re_arms: int = 0
    wrong_arming: int = 0
    safety: int = 0
    latencies: list[float] = field(default_factory=list)
    latency_by_gesture: dict[str, list[float]] = field(default_factory=dict)
    wrong_examples: list[dict[str, Any]] = field(default_factory=list)
    missed_by_gesture: dict[str, int] = field(default_factory=dict)
    wrong_by_pair: dict[str, int] = field(default_factory=dict)

    @property
    def wrong_acting(self) -> int:
        """Wrong commands that change what the drone does (all but the re-arms and the
        wrong armings, when the commands said their arming)."""
        return self.wrong - self.re_arms - self.wrong_arming

    def add_latency(self, gesture: str, seconds: float) -> None:
        self.latencies.append(seconds)
        self.latency_by_gesture.setdefault(gesture, []).append(seconds)

    def merge(self, other: Score) -> Score:
        self.seconds += other.seconds
        self.expected += other.expected
        self.hits += other.hits
        self.late += other.late
        self.missed += other.missed
        self.blocked += other.blocked
        self.repeats += other.repeats
        self.wrong += other.wrong
        self.re_arms += other.re_arms
        self.wrong_arming += other.wrong_arming
        self.safety += other.safety
        self.latencies.extend(other.latencies)
        for g, lat in other.latency_by_gesture.items():
            self.latency_by_gesture.setdefault(g, []).extend(lat)
        self.wrong_examples.extend(other.wrong_examples)
        for src, dst in (
            (other.missed_by_gesture, self.missed_by_gesture),
            (other.wrong_by_pair, self.wrong_by_pair),
        ):
            for key, n in src.items():
                dst[key] = dst.get(key, 0) + n
        return self

    def summary(self) -> dict[str, Any]:
        """JSON-ready figures: latency median/p95 (s) and errors per hour."""
        hours = self.seconds / 3600.0
        lat = np.asarray(self.latencies, dtype=float)

        def per_hour(n: int) -> float | None:
            return round(n / hours, 3) if hours > 0 else None

        def ratio(n: int) -> float | None:
            return round(n / self.expected, 4) if self.expected else None

        figures = latency_figures(self.latencies)
        return {
            "stream_hours": round(hours, 4),
            "expected_commands": self.expected,
            "hits": self.hits,
            "late_hits": self.late,
            "missed": self.missed,
            "blocked_while_disarmed": self.blocked,
            "hit_rate": ratio(self.hits + self.late),
            "on_time_rate": ratio(int((lat <= 2.5).sum())),
            "latency_median_s": figures["median_s"],
            "latency_p95_s": figures["p95_s"],
            "latency_max_s": round(float(lat.max()), 3) if lat.size else None,
            "within_2_5_s": figures["within_2_5_s"],
            "wrong": self.wrong,
            "repeats": self.repeats,
            "re_arms": self.re_arms,
            "wrong_arming": self.wrong_arming,
            "wrong_acting": self.wrong_acting,
            "wrong_per_hour": per_hour(self.wrong),
            "wrong_acting_per_hour": per_hour(self.wrong_acting),
            "spurious_per_hour": per_hour(self.repeats),
            "wrong_or_spurious_per_hour": per_hour(self.wrong + self.repeats),
            "safety_hovers": self.safety,
            "missed_by_gesture": dict(sorted(self.missed_by_gesture.items())),
            "latency_by_gesture": {
                g: latency_figures(gl) for g, gl in sorted(self.latency_by_gesture.items())
            },
            "wrong_by_pair": dict(sorted(self.wrong_by_pair.items(), key=lambda kv: -kv[1])),
        }


def latency_figures(latencies: Sequence[float]) -> dict[str, Any]:
    """Count, median, p95 and share within 2.5 s of some onset -> command latencies."""
    lat = np.asarray(latencies, dtype=float)
    if not lat.size:
        return {"commands": 0, "median_s": None, "p95_s": None, "within_2_5_s": None}
    return {
        "commands": int(lat.size),
        "median_s": round(float(np.median(lat)), 3),
        "p95_s": round(float(np.percentile(lat, 95)), 3),
        "within_2_5_s": round(float((lat <= 2.5).mean()), 4),
    }


def expected_commands(
    segments: Sequence[dict[str, Any]],
    arming: Sequence[tuple[float, bool]] | None = None,
) -> list[str | None]:
    """The command each performed gesture should cause (None: ignored, as control was
    disarmed). `arming` is the run's (t, armed) changes; None simulates arming on the
    script."""
    if arming is None:
        armed = False
        out: list[str | None] = []
        for s in segments:
            g = s["gesture"]
            if g == ARM_GESTURE:
                armed = True
                out.append(g)
            elif armed:
                out.append(g)
                if g == ABORT_GESTURE:
                    armed = False
            else:
                out.append(None)
        return out
    changes = sorted(arming)
    onsets = [float(s["onset_t"]) for s in segments] + [float("inf")]
    out = []
    for i, s in enumerate(segments):
        start, stop = onsets[i], onsets[i + 1]
        before = [a for t, a in changes if t <= start]
        during = [a for t, a in changes if start < t < stop]
        armed_some_time = (bool(before) and before[-1]) or any(during)
        out.append(s["gesture"] if s["gesture"] == ARM_GESTURE or armed_some_time else None)
    return out


def score_commands(
    segments: Sequence[dict[str, Any]],
    commands: Iterable[dict[str, Any]],
    duration_s: float,
    arming: Sequence[tuple[float, bool]] | None = None,
) -> Score:
    """Score `commands` (dicts with `t`, `command`, `stream`, optionally `armed`: the
    arming they were sent in) against truth `segments`
    (dicts with `gesture`, `onset_t`, as in a stitched stream's truth file), given the
    run's arming changes `arming` ((t, armed) pairs; None: simulated on the script)."""
    onsets = np.array([s["onset_t"] for s in segments], dtype=float)
    expected = expected_commands(segments, arming)
    hit = [False] * len(segments)
    score = Score(seconds=duration_s, expected=sum(e is not None for e in expected))
    score.blocked = len(expected) - score.expected
    for c in sorted(commands, key=lambda c: c["t"]):
        t, name = float(c["t"]), c["command"]
        if not c.get("stream"):
            score.safety += 1
            continue
        i = max(int(np.searchsorted(onsets, t, side="right")) - 1, 0)
        if name == expected[i]:
            if hit[i]:
                score.repeats += 1
            else:
                hit[i] = True
                score.hits += 1
                score.add_latency(name, t - onsets[i])
        elif i > 0 and name == expected[i - 1] and not hit[i - 1]:
            hit[i - 1] = True
            score.late += 1
            score.add_latency(name, t - onsets[i - 1])
        else:
            score.wrong += 1
            if name == ARM_GESTURE and "armed" in c:
                if c["armed"]:
                    score.re_arms += 1
                else:
                    score.wrong_arming += 1
            key = f"{segments[i]['gesture']}->{name}"
            score.wrong_by_pair[key] = score.wrong_by_pair.get(key, 0) + 1
            if len(score.wrong_examples) < 20:
                score.wrong_examples.append(
                    {
                        "t": round(t, 3),
                        "command": name,
                        "performed": segments[i]["gesture"],
                        "since_onset_s": round(t - onsets[i], 3),
                        **({"armed": c["armed"]} if "armed" in c else {}),
                    }
                )
    for i, e in enumerate(expected):
        if e is not None and not hit[i]:
            score.missed += 1
            score.missed_by_gesture[e] = score.missed_by_gesture.get(e, 0) + 1
    return score
