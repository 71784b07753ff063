"""The demo's replayed camera streams: one landmark CSV per configured replay stream,
stitched from the LASER clips so that all cameras watch the same performance of the demo
script from their own side.

A configured `replay:PATH[@FPS]` whose file is missing and whose name ends in
`.<view>.csv` (view `f`, `l` or `r`, the LASER camera views, as `proxima stitch` names
its files) is generated; existing files are used as they are (delete them, or pass
`--regenerate`, to stitch them again). Any other replay file must exist.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from proxima.ingest import parse_replay_uri
from proxima.settings import Settings

# One pass of the operator's performance, played in a loop. The moves cancel out, so
# the main drone comes back where it started on every pass; the pass ends with wave_off
# (control disarmed), so the next pass starts disarmed like the first.
DEMO_SCRIPT: tuple[tuple[str, float], ...] = (
    ("hover", 4.0),
    ("have_command", 4.0),
    ("move_to_left", 4.0),
    ("move_to_right", 4.0),
    ("move_upward", 4.0),
    ("move_downward", 4.0),
    ("wave_off", 4.0),
)
VIEW_FILE = re.compile(r"\.(?P<view>[flr])\.csv$")


class DemoStreamError(ValueError):
    """A configured replay stream the demo cannot provide; the message names it."""


@dataclass(frozen=True)
class ReplayFile:
    """One configured replay stream and its CSV (`generated` when stitched now)."""

    stream: str
    path: Path
    view: str | None
    generated: bool = False


def replay_files(settings: Settings) -> list[ReplayFile]:
    """The replay streams of `settings` with their CSV paths and views (None when the
    file name names no LASER view)."""
    out = []
    for s in settings.streams:
        if not s.uri.startswith("replay:"):
            continue
        path, _fps = parse_replay_uri(s.uri.removeprefix("replay:"))
        match = VIEW_FILE.search(path)
        out.append(ReplayFile(s.name, Path(path), match["view"] if match else None))
    return out


def ensure_replays(
    settings: Settings,
    script: Sequence[tuple[str, float]] = DEMO_SCRIPT,
    data: str | None = None,
    regenerate: bool = False,
    part: str = "all",
) -> list[ReplayFile]:
    """Stitch the missing (or, with `regenerate`, every) replay CSV the settings name.

    Raises:
        DemoStreamError: a missing replay file whose name gives no view.
        proxima.gesture.clip.DataError: the LASER data cannot be found.
    """
    files = replay_files(settings)
    todo = [f for f in files if regenerate or not f.path.is_file()]
    if not todo:
        return files
    unknown = [f for f in todo if f.view is None]
    if unknown:
        names = ", ".join(f"{f.stream} ({f.path})" for f in unknown)
        raise DemoStreamError(
            f"replay file missing and its name does not end in .f.csv, .l.csv or .r.csv, "
            f"so the demo cannot stitch it: {names}"
        )
    from proxima.gesture.data_source import resolve_laser_dir
    from proxima.gesture.laser import load_laser_dir
    from proxima.scenario.rig import ScenarioError, choose_takes

    clips = load_laser_dir(resolve_laser_dir(data))
    views = tuple(sorted({f.view for f in todo if f.view}))
    # Takes in which the main camera sees the whole operator throughout (blinks under
    # half the arbiter's hold time), so the side cameras do not take over and disarm
    # control in the middle of the script; any takes if there are none.
    main = min(settings.streams, key=lambda s: s.priority).name
    full = [f.view for f in todo if f.stream == main and f.view]
    try:
        _, streams = choose_takes(
            clips, script, views, part, None, tries=60, full_views=full, max_blink=10
        )
    except ScenarioError:
        _, streams = choose_takes(clips, script, views, part, 0, require_full=False)
    done = {f.stream for f in todo}
    for f in todo:
        assert f.view is not None
        streams[f.view].write(f.path)
    return [ReplayFile(f.stream, f.path, f.view, f.stream in done) for f in files]
