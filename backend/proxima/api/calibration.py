"""Guided calibration of one stream's camera (the Calibration page): a take of each
gesture, recorded by the console's recorder and stored as a kept sample of the stream's
drone; the model's reading of each take; then, in the background, the model that stream
runs fine-tuned on the takes' first parts (gesture/take_calibration.py), scored before
and after on their held-out last parts, saved in models/calibration/, and offered for
promotion for that stream only.

Sessions live in memory (a restart forgets them); what they make does not: the takes
are samples in the database (a redone take's earlier sample is marked deleted, never
removed) and the candidate is a checkpoint in models/ with a card beside it.
"""

from __future__ import annotations

import json
import logging
import threading
import time
import uuid
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from proxima.types import GESTURES

log = logging.getLogger(__name__)

# Torch threads of a calibration: one, so the live engine on the same cores keeps up.
CALIBRATION_THREADS = 1
CALIBRATION_DIR = "calibration"  # under the console's models/
MAX_SESSIONS = 20


class CalibrationError(ValueError):
    """A step the session's state refuses; the message says why."""


def describe(gesture: str) -> str:
    """A short description of a gesture to prompt with (the marshalling signal)."""
    from proxima.synth.gestures import SPECS

    spec = SPECS.get(gesture)
    if spec is None or not spec.signal:
        return gesture.replace("_", " ")
    return f"{spec.signal[0].upper()}{spec.signal[1:]}; {spec.arms}."


@dataclass
class Take:
    gesture: str
    description: str
    state: str = "todo"  # todo -> recording -> done | failed (a redo records again)
    recording: str | None = None  # the recorder's id of the newest attempt
    sample_id: int | None = None  # the kept sample of the newest good take
    replaced: list[int] = field(default_factory=list)  # earlier takes' samples (deleted)
    frames: int = 0
    detail: str = ""
    reading: dict[str, Any] | None = None
    warn: bool = False  # the model reads another gesture than the one prompted


@dataclass
class CalibrationSession:
    id: str
    stream: str
    drone: str
    user: str
    gestures: list[str]
    frames: int
    countdown_s: float
    epochs: int
    takes: dict[str, Take]
    created: float = field(default_factory=time.time)
    # recording -> training -> trained | failed; trained -> promoted
    state: str = "recording"
    detail: str = ""
    epoch: int = 0
    member: int = 0  # which model of an ensemble is being fine-tuned (from 1)
    members: int = 1  # the models fine-tuned one after the other (an ensemble's members)
    loss: float | None = None
    model: str = ""  # the checkpoint fine-tuned (the stream's model when training began)
    candidate: str = ""  # the fine-tuned checkpoint's path
    before: dict[str, Any] | None = None
    after: dict[str, Any] | None = None
    seconds: float = 0.0
    promoted_by: str = ""
    override_reason: str = ""


class CalibrationManager:
    """Runs calibration sessions for a console (`proxima.api.services.Console`)."""

    def __init__(self, console: Any) -> None:
        self.console = console
        self._lock = threading.Lock()
        self._train_lock = threading.Lock()  # one fine-tuning at a time (shared cores)
        self._refresh_lock = threading.Lock()
        self._sessions: dict[str, CalibrationSession] = {}
        self._threads: list[threading.Thread] = []

    # -- sessions --------------------------------------------------------------------------
    def start(
        self,
        *,
        stream: str,
        user: str,
        gestures: list[str] | None,
        frames: int,
        countdown_s: float,
        epochs: int,
    ) -> CalibrationSession:
        """A new session for `stream`.

        Raises:
            KeyError: no such stream.
            CalibrationError: a gesture named twice.
        """
        spec = self.console.settings.stream(stream)
        chosen = list(gestures) if gestures else list(GESTURES)
        if len(set(chosen)) != len(chosen):
            raise CalibrationError("each gesture may be named once")
        chosen = [g for g in GESTURES if g in chosen]  # the classifier's order
        session = CalibrationSession(
            id=uuid.uuid4().hex[:12],
            stream=spec.name,
            drone=spec.drone,
            user=user,
            gestures=chosen,
            frames=frames,
            countdown_s=countdown_s,
            epochs=epochs,
            takes={g: Take(g, describe(g)) for g in chosen},
        )
        with self._lock:
            self._sessions[session.id] = session
            while len(self._sessions) > MAX_SESSIONS:
                self._sessions.pop(next(iter(self._sessions)))
        return session

    def get(self, session_id: str) -> CalibrationSession | None:
        """The session, its takes brought up to date with the recorder."""
        with self._lock:
            session = self._sessions.get(session_id)
        if session is not None:
            self._refresh(session)
        return session

    def sessions(self) -> list[CalibrationSession]:
        with self._lock:
            return list(reversed(self._sessions.values()))

    # -- takes -----------------------------------------------------------------------------
    def record(self, session: CalibrationSession, gesture: str, user: str) -> Take:
        """Start a take (or a redo) of `gesture`.

        Raises:
            CalibrationError: not a gesture of the session, training under way, or
                another take recording.
            ValueError: the recorder refused (a recording already runs on the stream).
        """
        self._refresh(session)
        if gesture not in session.takes:
            raise CalibrationError(
                f"{gesture!r} is not one of this calibration's gestures "
                f"({', '.join(session.gestures)})"
            )
        if session.state == "training":
            raise CalibrationError("the calibration is training: wait for it to finish")
        if any(t.state == "recording" for t in session.takes.values()):
            raise CalibrationError("a take is recording: wait for it to finish")
        take = session.takes[gesture]
        rec = self.console.recorder.start(
            stream=session.stream,
            drone=session.drone,
            frames=session.frames,
            countdown_s=session.countdown_s,
            user=user,
            label=gesture,
        )
        take.state, take.recording, take.detail = "recording", rec.id, ""
        if session.state in ("trained", "failed", "promoted"):  # a new take: train again
            session.state, session.detail = "recording", ""
        return take

    def _refresh(self, session: CalibrationSession) -> None:
        with self._refresh_lock:  # two pages polling must not take one recording twice
            self._refresh_takes(session)

    def _refresh_takes(self, session: CalibrationSession) -> None:
        for take in session.takes.values():
            if take.state != "recording" or take.recording is None:
                continue
            rec = self.console.recorder.get(take.recording)
            if rec is None or rec.state == "failed":
                take.state = "failed"
                take.detail = rec.detail if rec is not None else "the recording was forgotten"
                if take.sample_id is not None:
                    take.detail += f" (the earlier take, sample {take.sample_id}, stays)"
            elif rec.state == "done" and rec.sample_id is not None:
                self._take_done(session, take, rec.sample_id)

    def _take_done(self, session: CalibrationSession, take: Take, sample_id: int) -> None:
        """Keep the new take's sample (labelled with the gesture prompted), mark the one
        it replaces deleted, and read it with the model the stream runs."""
        from proxima.api.reading import model_in_use, model_reading
        from proxima.api.routers.models import _name
        from proxima.store.audit import AuditAction
        from proxima.store.samples import Sample, SampleStatus, review_sample

        with self.console.sessions() as db:
            sample = db.get(Sample, sample_id)
            if sample is None:
                take.state, take.detail = "failed", f"sample {sample_id} is gone"
                return
            review_sample(db, sample, status=SampleStatus.KEPT, label=take.gesture, by=session.user)
            xyz = sample.arrays().xyz.copy()
            if take.sample_id is not None and take.sample_id != sample_id:
                old = db.get(Sample, take.sample_id)
                if old is not None:
                    review_sample(db, old, status=SampleStatus.DELETED, label=None,
                                  by=session.user)  # fmt: skip
                take.replaced.append(take.sample_id)
        self.console.audit.record(AuditAction.SAMPLE_KEEP, actor=session.user,
                                  target=str(sample_id), label=take.gesture, drone=session.drone,
                                  calibration=session.id)  # fmt: skip
        take.sample_id, take.frames, take.state, take.detail = sample_id, len(xyz), "done", ""
        try:
            clf, path = model_in_use(self.console, session.stream)
            take.reading = {"model": _name(self.console, path), **model_reading(clf, xyz)}
            take.warn = take.reading["gesture"] != take.gesture
        except (FileNotFoundError, ValueError) as exc:
            take.reading, take.warn = None, False
            take.detail = f"no model reading: {exc}"

    # -- training --------------------------------------------------------------------------
    def train(self, session: CalibrationSession) -> None:
        """Start fine-tuning on the session's takes in the background.

        Raises:
            CalibrationError: a take missing or recording, training under way, or another
                calibration training.
        """
        self._refresh(session)
        missing = [g for g, t in session.takes.items() if t.sample_id is None]
        if missing:
            raise CalibrationError(f"record a take of {', '.join(missing)} first")
        if any(t.state == "recording" for t in session.takes.values()):
            raise CalibrationError("a take is recording: wait for it to finish")
        if session.state == "training":
            raise CalibrationError("this calibration is training already")
        if not self._train_lock.acquire(blocking=False):
            raise CalibrationError("another calibration is training: try again when it is done")
        session.state, session.detail, session.epoch, session.loss = "training", "", 0, None
        session.member = 0  # set as each model of the checkpoint starts (`next_member`)
        session.before = session.after = None
        session.candidate = ""
        thread = threading.Thread(target=self._train, args=(session,), daemon=True,
                                  name=f"calib-{session.id}")  # fmt: skip
        self._threads = [t for t in self._threads if t.is_alive()] + [thread]
        thread.start()

    def _train(self, session: CalibrationSession) -> None:
        try:
            self._fine_tune(session)
        except Exception as exc:  # shown on the page, never kills the server
            log.exception("calibration %s failed", session.id)
            session.state = "failed"
            session.detail = f"{type(exc).__name__}: {exc}"
        finally:
            self._train_lock.release()

    def _fine_tune(self, session: CalibrationSession) -> None:
        from proxima.gesture.classifier import default_checkpoint
        from proxima.gesture.console_samples import row_clip
        from proxima.gesture.take_calibration import calibrate_takes
        from proxima.store.samples import Sample

        promoter = self.console.promoter
        active = promoter.active_checkpoint(session.stream) if promoter else None
        session.model = str(active or default_checkpoint())
        takes = []
        with self.console.sessions() as db:
            for take in session.takes.values():
                row = db.get(Sample, take.sample_id)
                if row is None:
                    raise CalibrationError(f"the sample of {take.gesture} is gone: record it again")
                takes.append(row_clip(row, take.gesture))
        out = self.candidate_path(session)

        def progress(epoch: int, epochs: int, loss: float) -> None:
            session.epoch, session.loss = epoch, round(loss, 4)

        def next_member(member: int, members: int) -> None:
            session.member, session.members, session.epoch = member, members, 0

        result = calibrate_takes(
            session.model,
            takes,
            out,
            epochs=session.epochs,
            threads=CALIBRATION_THREADS,
            metadata={
                "command": f"console calibration {session.id} by {session.user}",
                "stream": session.stream,
                "drone": session.drone,
                "samples": [t.sample_id for t in session.takes.values()],
            },
            on_epoch=progress,
            on_member=next_member,
        )
        session.before, session.after = result.before, result.after
        session.seconds = round(result.seconds, 1)
        session.candidate = str(result.checkpoint)
        card = {
            "calibration": {
                "stream": session.stream,
                "drone": session.drone,
                "by": session.user,
                "fine_tuned": session.model,
                "takes": {g: t.sample_id for g, t in session.takes.items()},
                "held_out_before": result.before,
                "held_out_after": result.after,
                "epochs": result.epochs,
                "train_windows": result.train_windows,
            }
        }
        out.with_suffix(".json").write_text(json.dumps(card, indent=1))
        session.state = "trained"

    def candidate_path(self, session: CalibrationSession) -> Path:
        root = Path(self.console.settings.server.models_dir) / CALIBRATION_DIR
        return root / f"{session.stream}-{session.id}.pt"

    # -- promotion -------------------------------------------------------------------------
    def concerns(self, session: CalibrationSession) -> list[str]:
        """Why promoting the candidate needs an override ([] when it does not): worse than
        the model it was tuned from on the held-out parts, overall or on the abort."""
        from proxima.api.model_eval import ABORT

        before, after = session.before or {}, session.after or {}
        if not before or not after:
            return []
        tol = self.console.settings.server.promotion_tolerance
        out = []
        if after["accuracy"] < before["accuracy"] - tol:
            out.append(
                f"held-out accuracy {after['accuracy']:.3f} is below the model's before "
                f"calibration ({before['accuracy']:.3f})"
            )
        b, a = before["per_gesture"].get(ABORT), after["per_gesture"].get(ABORT)
        if a and b and a["accuracy"] < b["accuracy"] - tol:
            out.append(
                f"{ABORT} (the abort) held-out accuracy {a['accuracy']:.3f} is below the "
                f"model's before calibration ({b['accuracy']:.3f})"
            )
        return out

    def promote(
        self, session: CalibrationSession, user: str, override_reason: str = ""
    ) -> dict[str, Any]:
        """Put the candidate into the live engine for the session's stream only.

        Raises:
            CalibrationError: not trained, or worse without an override reason.
            RuntimeError: no live engine runs.
            ValueError: the engine refused the checkpoint.
        """
        if session.state not in ("trained", "promoted") or not session.candidate:
            raise CalibrationError("nothing to promote: train the calibration first")
        if self.console.promoter is None:
            raise RuntimeError("no live engine runs in this server to promote to")
        concerns = self.concerns(session)
        if concerns and not override_reason:
            raise CalibrationError(
                f"not promoted: {'; '.join(concerns)}. Give an override reason to promote it "
                "anyway."
            )
        result: dict[str, Any] = self.console.promoter.promote(
            session.candidate, streams=[session.stream]
        )
        session.state, session.promoted_by = "promoted", user
        session.override_reason = override_reason
        return result

    def join(self, timeout: float = 60.0) -> None:
        """Wait for training threads (tests, shutdown)."""
        for t in list(self._threads):
            t.join(timeout)
