"""The console's [recognition] section reaches the engine's decision settings."""

from __future__ import annotations

from pathlib import Path

import pytest
from pydantic import ValidationError

from proxima.api.runtime import control_settings
from proxima.control import ControlSettings
from proxima.settings import Settings, SettingsError


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


def test_per_command_thresholds_reach_control_settings_and_are_checked() -> None:
    assert ControlSettings().threshold_by_command == {"wave_off": 0.7}
    s = Settings.model_validate({"recognition": {"threshold_by_command": {"wave_off": 0.6}}})
    assert control_settings(s).threshold_by_command == {"wave_off": 0.6}
    with pytest.raises(ValidationError, match="unknown gesture wavoff"):
        ControlSettings(threshold_by_command={"wavoff": 0.7})
    with pytest.raises(ValidationError, match="less than or equal to 1"):
        Settings.model_validate({"recognition": {"threshold_by_command": {"wave_off": 1.5}}})


def test_a_misspelt_gesture_in_confirm_by_command_is_refused(tmp_path: Path) -> None:
    # Silently ignoring `lnad` would leave land on the shorter default agreement.
    path = tmp_path / "console.toml"
    path.write_text("[recognition]\nconfirm_by_command = { lnad = 9 }\n")
    with pytest.raises(SettingsError) as err:
        Settings.load(path)
    msg = str(err.value)
    assert str(path) in msg and "recognition.confirm_by_command" in msg
    assert "unknown gesture lnad" in msg
    with pytest.raises(ValidationError, match="unknown gesture lnad"):
        ControlSettings(confirm_by_command={"lnad": 9})
    with pytest.raises(ValidationError, match="greater than or equal to 1"):
        ControlSettings(confirm_by_command={"land": 0})


def test_the_thumb_hand_is_set_from_the_console_file(tmp_path: Path) -> None:
    path = tmp_path / "console.toml"
    path.write_text('[recognition]\nthumb_hand = "left"\n')
    assert control_settings(Settings.load(path)).thumb_hand == "left"
    assert control_settings(Settings()).thumb_hand == "right"
    path.write_text('[recognition]\nthumb_hand = "both"\n')
    with pytest.raises(SettingsError) as err:
        Settings.load(path)
    assert "recognition.thumb_hand" in str(err.value)
