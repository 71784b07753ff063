"""The demo's replay loop restarts the console's live engine: the fresh engine keeps the
model promoted into the old one, and later promotions reach the fresh one."""

from __future__ import annotations

import shutil
from pathlib import Path

from api_helpers import laser_clip

from proxima.api.runtime import build_runtime
from proxima.events import ArmingEvent
from proxima.settings import Settings


def test_a_restarted_engine_keeps_the_promoted_model_and_the_promoter(
    tmp_path: Path, checkpoint_path: Path
) -> None:
    copy = tmp_path / "models" / "copy.pt"
    copy.parent.mkdir()
    shutil.copy(checkpoint_path, copy)
    settings = Settings.load(
        config=None,
        streams=[{"name": "front", "uri": f"replay:{laser_clip('hover_f')}@30"}],
        engine={"checkpoint": str(checkpoint_path)},
        server={"db_path": str(tmp_path / "c.db"), "models_dir": str(copy.parent)},
    )
    runtime = build_runtime(
        settings, engine=True, drones=False, view=False, training=False, realtime=False
    )
    assert runtime.engine is not None and runtime.promoter is not None, runtime.notes
    try:
        old = runtime.engine
        assert old.wait(60)
        result = runtime.promoter.promote(str(copy))
        assert result["pending"] == []  # the stream had ended: applied at once
        promoted = old.classifier("front")
        fresh = runtime.restart_engine()
        assert runtime.engine is fresh and fresh is not old
        assert fresh.classifier("front") is promoted
        assert fresh.wait(60) and fresh.stats["front"].frames == old.stats["front"].frames
        runtime.promoter.promote(str(checkpoint_path))
        assert fresh.classifier("front") is not promoted  # the promoter follows the engine
        assert old.classifier("front") is promoted
        assert runtime.promoter.active_checkpoint() == str(checkpoint_path)
    finally:
        runtime.close()


def test_a_restarted_engine_is_shown_disarmed(tmp_path: Path) -> None:
    """Finding 2 of issue 26: after the loop restarted the engine, ARMED stayed on screen.
    A replayed have_command arms the stream; the restart publishes the fresh engine's
    disarmed state, which the console's live state (what every tile shows) follows."""
    settings = Settings.load(
        config=None,
        streams=[{"name": "front", "uri": f"replay:{laser_clip('have_command_f')}@30"}],
        server={"db_path": str(tmp_path / "c.db")},
    )
    runtime = build_runtime(
        settings, engine=True, drones=False, view=False, training=False, realtime=False
    )
    assert runtime.engine is not None, runtime.notes
    try:
        live = runtime.app.state.console.live
        seen: list[tuple[bool, str, bool]] = []  # (armed, reason, what the live state says)

        def on_event(event: object) -> None:  # after LiveState's listener (made first)
            if isinstance(event, ArmingEvent):
                seen.append((event.armed, event.reason, live.streams()["front"].armed))

        runtime.bus.add_listener(on_event)
        assert runtime.engine.wait(60)
        assert live.streams()["front"].armed, live.streams()["front"]
        runtime.restart_engine()
        restart = [i for i, s in enumerate(seen) if "engine restarted" in s[1]]
        assert restart and any(s[0] for s in seen[: restart[0]]), seen
        assert seen[restart[0]][0] is False and seen[restart[0]][2] is False
    finally:
        runtime.close()
