"""Everything a request handler may need, built once per app by `create_app`."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Any

from sqlalchemy import Engine as DbEngine
from sqlalchemy.orm import sessionmaker

from proxima.api.audit import Audit
from proxima.api.hub import WebSocketHub
from proxima.api.interfaces import EmergencyStop, ModelPromoter, TrainingRunner
from proxima.api.live import LiveState
from proxima.api.recorder import SampleRecorder
from proxima.api.throttle import LoginThrottle
from proxima.events import EventBus
from proxima.settings import Settings


@dataclass
class Console:
    settings: Settings
    bus: EventBus
    db_engine: DbEngine
    sessions: sessionmaker
    hub: WebSocketHub
    live: LiveState
    recorder: SampleRecorder
    audit: Audit
    throttle: LoginThrottle
    training: TrainingRunner | None = None
    estop: EmergencyStop | None = None
    promoter: ModelPromoter | None = None
    # The viser server's port on viser_host when one runs: only the console's /viser/
    # proxy connects to it; browsers are never told.
    viz_port: int | None = None
    alarms: Any = None  # proxima.api.alarms.AlarmMonitor

    @cached_property
    def command_log(self) -> Any:
        """The durable command log (proxima.store.command_log) in this database."""
        from proxima.store.command_log import CommandLog

        return CommandLog(self.db_engine)

    @cached_property
    def evaluator(self) -> Any:
        """Figures of checkpoints on the held-out set (proxima.api.model_eval), its clips
        beside the database."""
        from proxima.api.model_eval import ModelEvaluator

        return ModelEvaluator(self.settings.server.db_path.parent / "console-eval")

    @cached_property
    def calibration(self) -> Any:
        """Guided calibration sessions (proxima.api.calibration)."""
        from proxima.api.calibration import CalibrationManager

        return CalibrationManager(self)
