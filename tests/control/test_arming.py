"""Arming on explicit command sequences."""

from proxima.control import Arming


def test_disarmed_allows_only_have_command() -> None:
    a = Arming()
    assert not a.allows("move_to_left")
    assert a.allows("have_command")
    assert a.on_command(1.0, "have_command") == (True, "have_command")
    assert a.allows("move_to_left")


def test_wave_off_disarms_and_idle_disarms() -> None:
    a = Arming(idle_disarm_s=5.0)
    a.on_command(0.0, "have_command")
    assert a.on_command(1.0, "wave_off") == (False, "wave_off")
    assert not a.allows("land")
    a.on_command(2.0, "have_command")
    a.on_command(4.0, "move_ahead")  # activity restarts the idle clock
    assert not a.check_idle(8.9)
    assert a.check_idle(9.0)
    assert not a.armed
