"""The time-ordered merge: streams in their own threads at different speeds decide
exactly as if their updates were processed in stream-time order."""

import random
import threading
import time

from proxima.control import CommandController, ControlSettings, Sight, StreamUpdate
from proxima.engine import TimeOrderedMerge

SETTINGS = ControlSettings(debounce_s=1.0, confirm=1, hold_s=0.5, regain_s=0.3)


def script() -> dict[str, list[StreamUpdate]]:
    """Main sees the operator, arms, commands, loses the feet at 6 s; side sees all."""

    def seq(stream, spans):
        out = []
        for start, stop, sight, action in spans:
            for i in range(round((stop - start) * 30)):
                t = round(start + i / 30, 6)
                out.append(StreamUpdate(stream, t, sight, action if i % 5 == 0 else None))
        return out

    F, P = Sight.FULL, Sight.PARTIAL
    main = seq("main", [(0, 3, F, "have_command"), (3, 6, F, "move_to_left"), (6, 12, P, "land")])
    side = seq("side", [(0, 7, F, "hover"), (7, 9, F, "have_command"), (9, 12, F, "move_ahead")])
    for us in (main, side):
        us.append(StreamUpdate(us[-1].stream, us[-1].t, Sight.NONE, ended=True))
    return {"main": main, "side": side}


def reference(updates: dict[str, list[StreamUpdate]]) -> list[dict]:
    ctl = CommandController(["main", "side"], "x500", SETTINGS)
    merged = sorted(
        (u for us in updates.values() for u in us),
        key=lambda u: (u.t, ["main", "side"].index(u.stream)),
    )
    return [e.to_dict() for u in merged for e in ctl.process(u)]


def test_threads_at_different_speeds_decide_like_the_reference() -> None:
    updates = script()
    expected = reference(updates)
    handovers = [e["to_stream"] for e in expected if e["type"] == "handover"]
    assert handovers == ["main", "side", ""]  # "": both streams ended
    for trial in range(3):
        ctl = CommandController(["main", "side"], "x500", SETTINGS)
        got: list[dict] = []
        lock = threading.Lock()

        def publish(e, got=got, lock=lock):
            with lock:
                got.append(e.to_dict())

        merge = TimeOrderedMerge(ctl, publish, ["main", "side"])
        rng = random.Random(trial)

        def run(stream: str, pause: float, rng=rng, merge=merge, updates=updates) -> None:
            for u in updates[stream]:
                merge.submit(u)
                if rng.random() < 0.05:
                    time.sleep(pause)

        threads = [
            threading.Thread(target=run, args=("main", 0.002)),
            threading.Thread(target=run, args=("side", 0.0)),
        ]
        for th in threads:
            th.start()
        for th in threads:
            th.join()
        merge.flush()
        assert got == expected, f"trial {trial}"


def test_a_silent_live_stream_stops_holding_the_others_back() -> None:
    now = [0.0]
    ctl = CommandController(["main", "cam"], "x500", SETTINGS)
    got: list = []
    merge = TimeOrderedMerge(
        ctl, got.append, ["main", "cam"], stale_after_s=1.0, clock=lambda: now[0]
    )
    merge.set_live("cam")
    merge.submit(StreamUpdate("main", 0.0, Sight.FULL))
    merge.submit(StreamUpdate("main", 0.5, Sight.FULL))
    assert merge.decided == 0  # waits for the camera stream, which said nothing yet
    now[0] = 1.5  # the camera has been silent for 1.5 s of wall clock
    merge.submit(StreamUpdate("main", 1.0, Sight.FULL))
    assert merge.decided == 3
    assert ctl.active == "main"
