"""The console's federated runs default to the measured recipe from the synthetic
operator's model (`[training] start` and `run_defaults`); bad values are refused when the
settings load, named. A real console run from these defaults: tests/ui/test_ui_training.py."""

from __future__ import annotations

from pathlib import Path

import pytest

from proxima.federated.settings import RUN_DEFAULTS, TrainingSettings
from proxima.gesture.classifier import GestureClassifier
from proxima.settings import Settings, SettingsError
from proxima.shipped import FEDERATED_START, shipped_path


def test_console_runs_start_from_the_synthetic_model_with_the_measured_recipe() -> None:
    cfg = TrainingSettings().run_config(window=30)
    assert (cfg.strategy, cfg.local_epochs, cfg.mirror, cfg.keep_round) == (
        "scaffold", 20, True, "best")  # fmt: skip
    assert (cfg.fraction_evaluate, cfg.window) == (1.0, 30)
    assert Path(cfg.init) == shipped_path(FEDERATED_START).resolve()
    # a start the console's runs can take: their model and pipeline, no real data in it
    start = GestureClassifier.load(cfg.init)
    assert (start.model_name, start.pipeline.name) == (cfg.model, cfg.pipeline)
    assert all(d.startswith("runs/synth-") for d in start.metadata["data"])
    assert TrainingSettings(start="none").run_config().init == ""
    own = TrainingSettings(run_defaults={"local-epochs": 3}).run_config()
    assert (own.local_epochs, own.strategy) == (3, "fedavg")  # the rest: FLConfig's own
    assert RUN_DEFAULTS["local-epochs"] == 20  # the table in docs/federated.md
    with pytest.raises(ValueError, match="'window'"):  # the live model's length, checked
        TrainingSettings().run_config(window=5)


@pytest.mark.parametrize(
    ("toml", "named"),
    [
        ("run_defaults = { local-epochs = 0 }", "'local-epochs'"),
        ("run_defaults = { epochs = 5 }", "'epochs': unknown key"),
        ('run_defaults = { init = "a.pt" }', "not 'init'"),
        ('start = "no/such/start.pt"', "no/such/start.pt"),
    ],
)
def test_bad_run_defaults_are_refused_when_the_settings_load(
    tmp_path: Path, toml: str, named: str
) -> None:
    path = tmp_path / "console.toml"
    path.write_text(f"[training]\n{toml}\n")
    with pytest.raises(SettingsError) as err:
        Settings.load(path)
    msg = str(err.value)
    assert str(path) in msg and "training" in msg and named in msg, msg


def test_a_missing_shipped_start_is_named_when_a_run_needs_it(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # The settings still load (the console starts; build_runtime notes the runner as
    # unavailable with this message), so a missing start never keeps the console down.
    import proxima.federated.settings as training

    monkeypatch.setattr(training, "FEDERATED_START", "models/no-such-start.pt")
    settings = TrainingSettings()
    with pytest.raises(ValueError, match=r"shipped synthetic start is missing .*no-such-start"):
        settings.run_config()
    assert TrainingSettings(start="none").run_config().init == ""
