"""`proxima demo`: the whole system on its embedded default, in one process tree.

    simulated drones    one `proxima sim-drone` process per configured drone whose
                        connection is udpin:127.0.0.1:PORT (taken off to hover)
    camera streams      the configured streams; replayed ones play the demo script in a
                        loop (a fresh engine starts when every replay has ended); sim
                        ones see the simulated operator from their drone (`--sim`)
    console             the web app and WebSocket hub (uvicorn on a thread), the live
                        engine, drone links and controller, the 3D view (viser)

SIGINT (Ctrl-C), SIGTERM and SIGHUP stop everything in order: the engine, the console, the
links, then each simulator by its PID (SIGTERM, SIGKILL after a timeout). Simulators
run in their own session, so a Ctrl-C in the terminal reaches only the demo, which
stops them itself; on Linux the kernel also sends them SIGTERM if the demo dies.
"""

from __future__ import annotations

import re
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from proxima.scenario.fleet import SimProcess, start_sim, stop_all, take_off, turn_to
from proxima.settings import Settings

LOCAL_UDP = re.compile(r"^udpin:(127\.0\.0\.1|localhost):(?P<port>\d+)$")
HOVER_ALTITUDE_M = 2.5

Say = Callable[[str], None]


def simulated_drones(settings: Settings) -> list[tuple[str, int, int]]:
    """(name, port, sysid) of the configured drones the demo simulates: those whose
    connection listens on 127.0.0.1 over UDP. Other connections (SITL over TCP, a
    serial radio, a network address) are real vehicles the demo only connects to."""
    out = []
    for d in settings.drones:
        m = LOCAL_UDP.match(d.connection)
        if m:
            out.append((d.name, int(m["port"]), d.sysid))
    return out


@dataclass
class Demo:
    """One running demo; `start()` then `wait()` and `stop()` (idempotent)."""

    settings: Settings
    log_dir: Path
    say: Say = print
    sims: list[SimProcess] = field(default_factory=list)
    runtime: Any = None  # proxima.api.runtime.ConsoleRuntime
    server: Any = None  # proxima.api.server.BackgroundServer
    loops: int = 0
    stop_requested: threading.Event = field(default_factory=threading.Event)
    _loop_thread: threading.Thread | None = field(default=None, init=False)
    _stopped: bool = field(default=False, init=False)

    # --- start ----------------------------------------------------------------------------
    def start(self) -> Demo:
        """Start simulators, take them off, then the console with the engine and the
        3D view; returns once the console answers.

        Raises:
            RuntimeError: a simulator did not start or take off, or the console did not
                come up (everything started so far is stopped again by `stop()`).
        """
        self._start_sims()
        if self.stop_requested.is_set():
            return self
        self._take_off()
        if self.stop_requested.is_set():
            return self
        from proxima.api.runtime import build_runtime
        from proxima.api.server import BackgroundServer
        from proxima.events import EventBus

        self.say("starting the console, the live engine and the 3D view ...")
        self.runtime = build_runtime(self.settings, bus=EventBus(), realtime=True)
        s = self.settings.server
        self.server = BackgroundServer(self.runtime.app, host=s.host, port=s.port, server=s).start()
        self._loop_thread = threading.Thread(target=self._loop, name="demo-loop", daemon=True)
        self._loop_thread.start()
        return self

    def _start_sims(self) -> None:
        for name, port, sysid in simulated_drones(self.settings):
            sim = start_sim(
                name, port, sysid, log_path=self.log_dir / f"sim-{name}.log", new_session=True
            )
            self.sims.append(sim)
            self.say(f"sim-drone {name}: sysid {sysid}, udpin:127.0.0.1:{port}, pid {sim.pid}")

    def _take_off(self) -> None:
        """Pre-flight for the simulators the demo started (never for a real vehicle): a
        link of its own connects, takes off to hover and lets go of the port."""
        from proxima.drone.mavlink import MavlinkLink

        errors: list[str] = []

        facing = {d.name for d in self.settings.drones if d.heading == "face_operator"}

        def one(sim: SimProcess) -> None:
            link = MavlinkLink(sim.connection, sim.name)
            try:
                link.connect(timeout=20.0)
                tel = take_off(link, HOVER_ALTITUDE_M)
                if sim.name in facing and tel.position is not None:
                    turn_to(link, self._bearing_to_operator(sim.name, tel.position))
            except Exception as exc:
                errors.append(f"{sim.name}: {exc}")
            finally:
                link.close()

        self.say(f"taking off {len(self.sims)} simulated drones to {HOVER_ALTITUDE_M} m ...")
        if facing:
            self.say(f"turning {', '.join(sorted(facing))} to face the operator ...")
        threads = [threading.Thread(target=one, args=(sim,)) for sim in self.sims]
        for th in threads:
            th.start()
        for th in threads:
            th.join()
        if errors:
            raise RuntimeError("simulated drones not ready: " + "; ".join(errors))

    def _bearing_to_operator(self, name: str, position: tuple[float, float, float]) -> float:
        """Yaw (radians) from a drone's local position toward `view.operator_position`."""
        from proxima.drone.heading import HeadingPolicy, bearing

        policy = HeadingPolicy.from_drones(
            self.settings.drones, self.settings.view.operator_position
        )
        return bearing(position, policy.operator_ne[name])

    # --- the replay loop -------------------------------------------------------------------
    def _replays_ended(self, engine: Any) -> bool:
        replay = [s.name for s in self.settings.streams if s.kind == "replay"]
        return bool(replay) and all(engine.stats[n].done for n in replay if n in engine.stats)

    def _loop(self) -> None:
        while not self.stop_requested.wait(0.5):
            rt = self.runtime
            engine = rt.engine if rt is not None else None
            if engine is None or not self._replays_ended(engine):
                continue
            try:
                self._restart_engine()
            except Exception as exc:  # report, keep the console up
                self.say(f"replay loop stopped: {type(exc).__name__}: {exc}")
                return

    def _restart_engine(self) -> None:
        """Play the replays again: a fresh engine (new stream time, disarmed) with the
        classifier the old one ran (so a model promoted in the console stays)."""
        if self.stop_requested.is_set() or self.runtime is None:
            return
        self.runtime.restart_engine()
        self.loops += 1

    # --- stop ----------------------------------------------------------------------------
    def wait(self) -> None:
        """Block until a stop is requested (`stop_requested.set()`, e.g. by a signal)."""
        while not self.stop_requested.wait(0.5):
            pass

    def child_pids(self) -> list[int]:
        """PIDs of the simulator processes the demo started."""
        return [sim.pid for sim in self.sims]

    def stop(self) -> dict[str, int]:
        """Stop everything in order; the simulators' exit codes."""
        self.stop_requested.set()
        if self._stopped:
            return {}
        self._stopped = True
        if self._loop_thread is not None:
            self._loop_thread.join(5.0)
        if self.server is not None:
            self.server.stop()
        if self.runtime is not None:
            self.runtime.close()
        deadline = time.monotonic() + 10.0
        codes = stop_all(self.sims, timeout=max(deadline - time.monotonic(), 1.0))
        return codes
