"""The console's settings nest each subsystem's own model: every engine, control and
safety parameter can be set from the TOML file, and renamed keys still work, warned."""

from __future__ import annotations

import logging
import warnings
from pathlib import Path
from typing import Any

import pytest
from pydantic import ValidationError

from proxima.control import ControlSettings
from proxima.drone.safety import SafetyConfig
from proxima.engine import EngineSettings, StreamSpec
from proxima.settings import DEPRECATED_KEYS, Settings, SettingsError


def test_sections_are_the_subsystem_models_with_their_defaults() -> None:
    s = Settings()
    assert isinstance(s.recognition, ControlSettings) and s.recognition == ControlSettings()
    assert isinstance(s.engine, EngineSettings) and s.engine == EngineSettings()
    assert isinstance(s.safety, SafetyConfig) and s.safety == SafetyConfig()
    s = Settings(streams=[{"name": "front", "uri": "replay:a.csv@30", "priority": 1}])
    assert s.streams == [StreamSpec(name="front", uri="replay:a.csv@30", drone="front", priority=1)]


def test_every_engine_control_and_safety_parameter_is_set_from_toml(tmp_path: Path) -> None:
    # One value off its default per field, so a field that does not reach its model fails.
    changed: dict[str, dict[str, Any]] = {
        "engine": {"checkpoint": "models/other.pt", "stride": 3, "max_gap_s": 0.5,
                   "pose_every": 2, "num_poses": 3, "pose_model": "models/pose.task",
                   "stale_after_s": 2.0, "torch_threads": 2, "fusion": "on",
                   "fusion_max_age_s": 0.3, "fusion_min_visibility": 0.6,
                   "fusion_overrule_below": 0.9, "fusion_arms": False,
                   "smooth_replays": False,
                   "window_clock": "time"},
        "recognition": {"filter_size": 4, "threshold": 0.8,
                        "threshold_by_command": {"wave_off": 0.6}, "confirm": 3,
                        "confirm_by_command": {"land": 7}, "debounce_s": 1.5,
                        "release_s": 3.0, "repeat_s": 6.0, "filter_reset_s": 2.0,
                        "thumb_hand": "left", "hand_visibility": 0.6, "idle_disarm_s": 30.0,
                        "hold_s": 0.5, "regain_s": 0.75, "rearm_on_handover": False,
                        "decision": "evidence", "evidence_threshold": 5.0,
                        "evidence_threshold_by_command": {"land": 6.0},
                        "evidence_prior_by_command": {"have_command": 2.0},
                        "evidence_half_life_s": 1.5, "evidence_clip": 2.0,
                        "evidence_bridged_weight": 0.75, "evidence_pair_margin": 8.0,
                        "thumb_raise": 0.4},
        "safety": {"geofence_radius_m": 20.0, "min_altitude_m": 2.0, "max_altitude_m": 12.0,
                   "max_step_m": 2.0, "min_interval_s": 0.5, "operator_lost_s": 4.0,
                   "estop_confirm_s": 8.0},
    }  # fmt: skip
    models = {"engine": EngineSettings, "recognition": ControlSettings, "safety": SafetyConfig}
    for section, model in models.items():
        assert set(changed[section]) == set(model.model_fields), f"[{section}] misses a field"
    lines = []
    for section, values in changed.items():
        lines.append(f"[{section}]")
        for key, value in values.items():
            lines.append(f"{key} = {_toml(value)}")
    path = tmp_path / "all.toml"
    path.write_text("\n".join(lines) + "\n")
    s = Settings.load(path)
    for section, values in changed.items():
        loaded = getattr(s, section).model_dump()
        for key, value in values.items():
            expected = Path(value) if key in ("checkpoint", "pose_model") else value
            assert loaded[key] == expected, f"[{section}] {key}"


def test_bad_values_name_the_file_and_the_field(tmp_path: Path) -> None:
    path = tmp_path / "console.toml"
    path.write_text("[recognition]\nconfirm_by_command = { lnad = 9 }\n")
    with pytest.raises(SettingsError) as err:
        Settings.load(path)
    msg = str(err.value)
    assert str(path) in msg and "recognition.confirm_by_command" in msg
    assert "unknown gesture lnad" in msg
    path.write_text("[engine]\nstride = 0\n[safety]\nmin_altitude_m = 5.0\nmax_altitude_m = 2.0\n")
    with pytest.raises(SettingsError) as err:
        Settings.load(path)
    msg = str(err.value)
    assert str(path) in msg and "engine.stride" in msg and "min_altitude_m" in msg
    path.write_text('[recognition]\nthumb_hand = "both"\n')
    with pytest.raises(SettingsError, match=r"recognition\.thumb_hand"):
        Settings.load(path)
    with pytest.raises(ValidationError, match="confirm_by_command"):
        Settings.model_validate({"recognition": {"confirm_by_command": {"land": "x"}}})
    with pytest.raises(ValidationError, match="less than or equal to 1"):
        Settings.model_validate({"recognition": {"threshold_by_command": {"wave_off": 1.5}}})


# A valid value for each renamed key, as TOML, and as the new field reads it.
ALIAS_VALUES: dict[tuple[str, ...], tuple[str, Any]] = {
    ("recognition", "checkpoint"): ('"models/old.pt"', Path("models/old.pt")),
    ("recognition", "stride"): ("3", 3),
    ("recognition", "filter_window"): ("4", 4),
    ("recognition", "arming_timeout_s"): ("30", 30.0),
    ("recognition", "handover_hold_s"): ("0.5", 0.5),
    ("recognition", "operator_lost_hover_s"): ("4.0", 4.0),
    ("safety", "min_command_interval_s"): ("0.5", 0.5),
    ("safety", "geofence", "radius_m"): ("25.0", 25.0),
    ("safety", "geofence", "min_alt_m"): ("1.5", 1.5),
    ("safety", "geofence", "max_alt_m"): ("15.0", 15.0),
    ("training", "engine"): ('"simulation"', "simulation"),
}


def test_every_deprecated_key_has_a_test_value() -> None:
    assert set(ALIAS_VALUES) == set(DEPRECATED_KEYS)


@pytest.mark.parametrize("old", sorted(DEPRECATED_KEYS), ids=".".join)
def test_a_deprecated_key_still_works_with_a_warning(
    old: tuple[str, ...], tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    new = DEPRECATED_KEYS[old]
    text, expected = ALIAS_VALUES[old]
    path = tmp_path / "old.toml"
    path.write_text(f"[{'.'.join(old[:-1])}]\n{old[-1]} = {text}\n")
    old_name = f"[{'.'.join(old[:-1])}] {old[-1]}"
    new_name = f"[{'.'.join(new[:-1])}] {new[-1]}"
    with (
        caplog.at_level(logging.WARNING, logger="proxima.settings"),
        pytest.warns(DeprecationWarning) as warned,
    ):
        s = Settings.load(path)
    message = f"{path}: {old_name} is deprecated; use {new_name}"
    assert [str(w.message) for w in warned] == [message]
    assert [r.getMessage() for r in caplog.records] == [message]
    assert getattr(getattr(s, new[0]), new[1]) == expected
    # Both the old and the new key: refused, both named.
    path.write_text(
        f"[{'.'.join(old[:-1])}]\n{old[-1]} = {text}\n"
        + (f"[{new[0]}]\n" if new[0] != old[0] or len(old) > 2 else "")
        + f"{new[1]} = {text}\n"
    )
    with pytest.raises(SettingsError) as err, warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        Settings.load(path)
    assert str(path) in str(err.value) and old_name in str(err.value)
    assert new_name in str(err.value)


def test_the_old_geofence_table_and_environment_keys(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = tmp_path / "demo.toml"  # as config/demo.toml had it
    path.write_text(
        "[safety]\nmax_step_m = 3.0\n"
        "geofence = { radius_m = 28.0, min_alt_m = 1.0, max_alt_m = 18.0 }\n"
    )
    with pytest.warns(DeprecationWarning) as warned:
        s = Settings.load(path)
    assert [str(w.message).split(": ", 1)[1] for w in warned] == [
        f"[safety.geofence] {old} is deprecated; use [safety] {new}"
        for old, new in [
            ("radius_m", "geofence_radius_m"),
            ("min_alt_m", "min_altitude_m"),
            ("max_alt_m", "max_altitude_m"),
        ]
    ]
    assert (s.safety.geofence_radius_m, s.safety.max_altitude_m) == (28.0, 18.0)
    path.write_text("[safety]\ngeofence = { radius_m = 28.0, height_m = 3.0 }\n")
    with pytest.raises(SettingsError, match=r"safety\.geofence"), warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        Settings.load(path)  # an unknown key left in the old table is still an error
    monkeypatch.setenv("PROXIMA_RECOGNITION__FILTER_WINDOW", "5")
    with pytest.warns(DeprecationWarning, match="PROXIMA_RECOGNITION__FILTER_WINDOW") as w:
        s = Settings.load(config=None)
    assert "PROXIMA_RECOGNITION__FILTER_SIZE" in str(w[0].message)
    assert s.recognition.filter_size == 5
    path.write_text("[recognition]\nfilter_size = 2\n")  # the environment still wins
    with pytest.warns(DeprecationWarning):
        assert Settings.load(path).recognition.filter_size == 5


def test_a_bad_value_under_a_deprecated_key_names_the_file_and_the_new_field(
    tmp_path: Path,
) -> None:
    path = tmp_path / "old.toml"
    path.write_text("[recognition]\nfilter_window = 0\n")
    with pytest.raises(SettingsError) as err, pytest.warns(DeprecationWarning):
        Settings.load(path)
    assert str(path) in str(err.value) and "recognition.filter_size" in str(err.value)


def _toml(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{k} = {_toml(v)}" for k, v in value.items()) + " }"
    return repr(value)
