"""Stitch dataset clips into long replay streams with a ground-truth script.

A stitched stream performs a script of gestures, each a run of consecutive rows from one
LASER clip (optionally only the temporal test part: the last 30% of each clip, which a
model trained with `--split temporal` never saw), joined by transitions that move every
landmark smoothly from the last pose of one gesture to the first pose of the next. Frame
numbers are renumbered to run on from one segment to the next (gaps inside a clip, where
no person was detected, are kept). The ground truth says which gesture is performed
when; `onset_t` is the first frame of the gesture's own rows (after the transition).

Blanks simulate a camera losing the operator: `feet` sets the visibility of the six foot
landmarks to 0 (the paper's main drone loses the operator's feet), `drop` removes the
frames (nobody detected).

    plan = [("have_command", 5.0), ("move_to_left", 6.0)]
    streams = stitch_views(clips, plan, views=("f", "r"), part="test", seed=1)
    streams["f"].write("main.csv")   # + main.truth.json
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from proxima.gesture.clip import Clip
from proxima.ingest import write_landmark_csv
from proxima.pose import FEET
from proxima.types import GESTURES

PARTS = ("test", "train", "all")
BLANK_KINDS = ("feet", "drop")


class StitchError(ValueError):
    """A stitching request that cannot be met (unknown gesture or view, no such clip)."""


@dataclass(frozen=True)
class Blank:
    """Blank the operator between stream times `start_t` and `end_t` (`kind`: feet, drop)."""

    start_t: float
    end_t: float
    kind: str = "feet"

    def __post_init__(self) -> None:
        if self.kind not in BLANK_KINDS:
            raise StitchError(f"blank kind must be one of {BLANK_KINDS}, got {self.kind!r}")
        if not self.end_t > self.start_t:
            raise StitchError(f"blank needs end > start, got {self.start_t}..{self.end_t}")


@dataclass(frozen=True)
class TruthSegment:
    """One gesture in a stitched stream: performed from `onset_t` to `end_t` (stream
    seconds), preceded by a transition from `transition_t`; taken from `clip` rows
    `rows[0]:rows[1]` (row numbers in the whole clip)."""

    gesture: str
    transition_t: float
    onset_t: float
    end_t: float
    clip: str
    rows: tuple[int, int]


@dataclass
class StitchedStream:
    """A stitched landmark stream and its ground truth."""

    view: str
    fps: float
    frames: np.ndarray  # (F,) 1-based counter_frame
    xyz: np.ndarray  # (F, 33, 3)
    visibility: np.ndarray  # (F, 33)
    segments: list[TruthSegment]
    blanks: list[Blank] = field(default_factory=list)
    part: str = "test"
    seed: int = 0

    @property
    def duration_s(self) -> float:
        return float(self.frames[-1]) / self.fps if len(self.frames) else 0.0

    def truth(self) -> dict:
        """The ground truth as a JSON-ready dict."""
        return {
            "view": self.view,
            "fps": self.fps,
            "part": self.part,
            "seed": self.seed,
            "duration_s": round(self.duration_s, 4),
            "frames": len(self.frames),
            "segments": [asdict(s) for s in self.segments],
            "blanks": [asdict(b) for b in self.blanks],
        }

    def write(self, csv_path: str | Path, truth_path: str | Path | None = None) -> Path:
        """Write the stream as a landmark CSV and the truth beside it (`X.truth.json` for
        `X.csv`); return the truth file's path."""
        csv_path = Path(csv_path)
        csv_path.parent.mkdir(parents=True, exist_ok=True)
        write_landmark_csv(csv_path, self.frames, self.xyz, self.visibility)
        truth_path = Path(truth_path) if truth_path else truth_path_for(csv_path)
        truth_path.write_text(json.dumps(self.truth(), indent=1) + "\n")
        return truth_path


def truth_path_for(csv_path: str | Path) -> Path:
    """Where the truth of a stitched CSV lives by default."""
    p = Path(csv_path)
    return p.with_name(p.name.removesuffix(".csv") + ".truth.json")


def clip_parts(clips: Sequence[Clip], part: str, window: int = 60) -> dict[tuple[str, str], Clip]:
    """(gesture, view) -> the rows of that LASER clip to draw from: `test` (the temporal
    split's last 30%), `train` (its first 70% minus the one-window gap) or `all`.

    Raises:
        StitchError: unknown part.
    """
    if part not in PARTS:
        raise StitchError(f"part must be one of {PARTS}, got {part!r}")
    from proxima.gesture.windows import temporal_parts

    out: dict[tuple[str, str], Clip] = {}
    for clip in clips:
        if part == "all":
            piece = clip
        else:
            train, test = temporal_parts(clip, window)
            piece = test if part == "test" else train
        out[(clip.gesture, clip.view)] = piece
    return out


def _offset(part: Clip, clip: Clip) -> int:
    """Row number in `clip` where `part` starts."""
    return int(np.searchsorted(clip.frames, part.frames[0]))


def random_plan(
    rng: np.random.Generator,
    n: int,
    min_s: float = 3.0,
    max_s: float = 6.0,
    gestures: Sequence[str] = GESTURES,
) -> list[tuple[str, float]]:
    """A random script of `n` gestures for benchmarks: it starts with `have_command`, never
    repeats a gesture back to back, and re-arms (`have_command`) after every `wave_off`,
    so most of it is performed while control is armed."""
    plan: list[tuple[str, float]] = [("have_command", float(rng.uniform(min_s, max_s)))]
    while len(plan) < n:
        last = plan[-1][0]
        if last == "wave_off":
            gesture = "have_command"
        else:
            choices = [g for g in gestures if g != last]
            gesture = choices[int(rng.integers(len(choices)))]
        plan.append((gesture, float(rng.uniform(min_s, max_s))))
    return plan


def smoothstep(x: np.ndarray) -> np.ndarray:
    """Ease 0..1 into 0..1 with zero speed at both ends, so a joined pose starts and
    stops moving gently instead of jerking (a jerk is a motion no operator makes)."""
    return x * x * (3.0 - 2.0 * x)


def stitch_views(
    clips: Sequence[Clip],
    plan: Sequence[tuple[str, float]],
    views: Sequence[str] = ("f",),
    part: str = "test",
    transition_s: float = 0.5,
    fps: float = 30.0,
    blanks: Mapping[str, Sequence[Blank]] | None = None,
    seed: int = 0,
    window: int = 60,
) -> dict[str, StitchedStream]:
    """Stitch `plan` (gesture, seconds) once per view, with identical timing in every
    view (each segment is as long as the shortest available among the views allows), so
    streams of several cameras watch the same performance.

    Raises:
        StitchError: an unknown gesture, or a (gesture, view) with no clip.
    """
    if not plan:
        raise StitchError("the plan has no gestures")
    parts = clip_parts(clips, part, window)
    whole = {(c.gesture, c.view): c for c in clips}
    rng = np.random.default_rng(seed)
    n_trans = max(round(transition_s * fps), 0)
    chosen: list[dict[str, tuple[int, int]]] = []  # per segment, view -> (start, stop) rows
    for gesture, seconds in plan:
        if gesture not in GESTURES:
            raise StitchError(f"unknown gesture {gesture!r}; known: {', '.join(GESTURES)}")
        missing = [v for v in views if (gesture, v) not in parts]
        if missing:
            raise StitchError(f"no clip of {gesture!r} in view(s) {missing}")
        want = max(round(seconds * fps), 1)
        n = min([want] + [len(parts[(gesture, v)]) for v in views])
        rows = {}
        for v in views:
            avail = len(parts[(gesture, v)])
            start = int(rng.integers(0, avail - n + 1))
            rows[v] = (start, start + n)
        chosen.append(rows)

    out: dict[str, StitchedStream] = {}
    for view in views:
        frames_l: list[np.ndarray] = []
        xyz_l: list[np.ndarray] = []
        vis_l: list[np.ndarray] = []
        segments: list[TruthSegment] = []
        next_frame = 1
        for k, (gesture, _) in enumerate(plan):
            piece = parts[(gesture, view)]
            start, stop = chosen[k][view]
            xyz = piece.xyz[start:stop]
            vis = piece.visibility[start:stop]
            transition_t = (next_frame - 1) / fps
            if k > 0 and n_trans > 0:
                a_xyz, a_vis = xyz_l[-1][-1], vis_l[-1][-1]
                alpha = smoothstep(np.arange(1, n_trans + 1) / (n_trans + 1))[:, None, None]
                xyz_l.append(((1 - alpha) * a_xyz + alpha * xyz[0]).astype(np.float32))
                vis_l.append(
                    ((1 - alpha[..., 0]) * a_vis + alpha[..., 0] * vis[0]).astype(np.float32)
                )
                frames_l.append(np.arange(next_frame, next_frame + n_trans))
                next_frame += n_trans
            rel = piece.frames[start:stop] - piece.frames[start]
            frames_l.append(next_frame + rel)
            xyz_l.append(xyz)
            vis_l.append(vis)
            onset = (next_frame - 1) / fps
            next_frame = int(next_frame + rel[-1] + 1)
            clip = whole[(gesture, view)]
            off = _offset(piece, clip)
            segments.append(
                TruthSegment(
                    gesture=gesture,
                    transition_t=round(transition_t, 6),
                    onset_t=round(onset, 6),
                    end_t=round((next_frame - 1) / fps, 6),
                    clip=clip.name,
                    rows=(off + start, off + stop),
                )
            )
        stream = StitchedStream(
            view=view,
            fps=fps,
            frames=np.concatenate(frames_l).astype(np.int64),
            xyz=np.concatenate(xyz_l).astype(np.float32),
            visibility=np.concatenate(vis_l).astype(np.float32),
            segments=segments,
            part=part,
            seed=seed,
        )
        for blank in (blanks or {}).get(view, ()):
            apply_blank(stream, blank)
        out[view] = stream
    return out


def apply_blank(stream: StitchedStream, blank: Blank) -> None:
    """Blank the operator in `stream` between the blank's times (in place)."""
    t = (stream.frames - 1) / stream.fps
    inside = (t >= blank.start_t) & (t < blank.end_t)
    if blank.kind == "feet":
        stream.visibility[np.ix_(inside, np.asarray(FEET))] = 0.0
    else:
        keep = ~inside
        stream.frames = stream.frames[keep]
        stream.xyz = stream.xyz[keep]
        stream.visibility = stream.visibility[keep]
    stream.blanks.append(blank)


def parse_plan(text: str) -> list[tuple[str, float]]:
    """`"have_command:5,move_to_left:6.5"` -> [("have_command", 5.0), ("move_to_left", 6.5)].

    Raises:
        StitchError: an item is not GESTURE:SECONDS, a gesture is unknown or a duration
            is not > 0.
    """
    plan: list[tuple[str, float]] = []
    for item in (p.strip() for p in text.split(",")):
        if not item:
            continue
        name, sep, secs = item.partition(":")
        try:
            seconds = float(secs) if sep else float("nan")
        except ValueError:
            seconds = float("nan")
        if not seconds > 0:
            raise StitchError(f"script item {item!r}: expected GESTURE:SECONDS with SECONDS > 0")
        if name not in GESTURES:
            raise StitchError(f"script item {item!r}: unknown gesture {name!r}")
        plan.append((name, seconds))
    if not plan:
        raise StitchError("empty script")
    return plan


def parse_blank(text: str, kind: str) -> Blank:
    """`"20:35"` -> Blank(20, 35, kind).

    Raises:
        StitchError: not START:END seconds with END > START.
    """
    start, _sep, end = text.partition(":")
    try:
        times = float(start), float(end)
    except ValueError:
        raise StitchError(f"blank {text!r}: expected START:END in seconds") from None
    return Blank(*times, kind)
