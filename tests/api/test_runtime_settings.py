"""The console's [recognition] section reaches the engine's decision settings."""

from __future__ import annotations

import pytest
from pydantic import ValidationError

from proxima.api.runtime import control_settings
from proxima.control import ControlSettings
from proxima.settings import Settings


def test_recognition_overrides_reach_control_settings() -> None:
    assert control_settings(Settings()) == ControlSettings()
    s = Settings.model_validate(
        {"recognition": {"threshold": 0.8, "confirm": 3, "confirm_by_command": {"land": 12}}}
    )
    control = control_settings(s)
    assert control.threshold == 0.8 and control.confirm == 3
    assert control.confirm_by_command == {"land": 12}
    with pytest.raises(ValidationError, match="confirm_by_command"):
        Settings.model_validate({"recognition": {"confirm_by_command": {"land": "x"}}})
