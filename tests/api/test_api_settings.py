"""Settings: environment over TOML over defaults, clear errors, no default secrets."""

from __future__ import annotations

from pathlib import Path

import pytest

from proxima.settings import Settings, SettingsError

TOML = """
[[streams]]
name = "front"
uri = "replay:/data/front.csv@30"
drone = "main"

[[streams]]
name = "side"
uri = "rtsp://pilot:secret@10.0.0.5/live"
drone = "main"
priority = 1

[[drones]]
name = "main"
connection = "udpin:127.0.0.1:14550"

[recognition]
debounce_s = 3.5

[server]
port = 9000
"""


def test_toml_then_environment(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    path = tmp_path / "proxima.toml"
    path.write_text(TOML)
    s = Settings.load(path)
    assert [x.name for x in s.streams] == ["front", "side"]
    assert s.stream("side").kind == "camera" and s.stream("front").kind == "replay"
    assert s.recognition.debounce_s == 3.5 and s.recognition.threshold == 0.9  # default
    assert s.server.port == 9000 and s.server.host == "127.0.0.1"
    monkeypatch.setenv("PROXIMA_SERVER__PORT", "9100")
    monkeypatch.setenv("PROXIMA_RECOGNITION__DEBOUNCE_S", "1.5")
    s = Settings.load(path)
    assert s.server.port == 9100 and s.recognition.debounce_s == 1.5
    monkeypatch.setenv("PROXIMA_CONFIG", str(path))
    assert Settings.load().server.port == 9100


def test_errors_name_the_file_and_field(tmp_path: Path) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text("[server]\nport = 'eighty'\nprot = 1\n")
    with pytest.raises(SettingsError) as err:
        Settings.load(bad)
    msg = str(err.value)
    assert str(bad) in msg and "server.port" in msg and "server.prot" in msg
    broken = tmp_path / "broken.toml"
    broken.write_text("[server\nport = 1\n")
    with pytest.raises(SettingsError, match=r"broken\.toml: not valid TOML.*line 1"):
        Settings.load(broken)
    with pytest.raises(SettingsError, match="not found"):
        Settings.load(tmp_path / "missing.toml")
    wrong = tmp_path / "wrong.toml"
    wrong.write_text(TOML.replace('drone = "main"\npriority', 'drone = "ghost"\npriority'))
    with pytest.raises(SettingsError, match="ghost"):
        Settings.load(wrong)
    scheme = tmp_path / "scheme.toml"
    scheme.write_text(TOML.replace("replay:/data", "ftp://data"))
    with pytest.raises(SettingsError, match="must start with one of"):
        Settings.load(scheme)


@pytest.mark.parametrize("password", ["admin", "password", "changeme", "short", "Proxima"])
def test_default_or_weak_secrets_are_refused(password: str) -> None:
    with pytest.raises(SettingsError, match="admin_password refused"):
        Settings.load(config=None, admin_user="boss", admin_password=password)


def test_admin_user_needs_password(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("PROXIMA_ADMIN_USER", "boss")
    with pytest.raises(SettingsError, match="both"):
        Settings.load(config=None)
    monkeypatch.setenv("PROXIMA_ADMIN_PASSWORD", "a-fine-long-passphrase")
    s = Settings.load(config=None)
    assert s.admin_user == "boss"
    assert "a-fine-long-passphrase" not in repr(s)  # secrets never print
