"""Constants the drone tests import (a module of its own: `conftest` is not importable by
name once several test folders each have one)."""

# Fast but realistic limits, so a whole flight fits in a few seconds of real time.
FAST = ("--max-accel", "8", "--max-climb", "4", "--land-speed", "3")
FAST_SIM = {"max_accel": 8.0, "max_climb": 4.0, "land_speed": 3.0}  # the same, in-memory
