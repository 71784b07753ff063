"""Writing a scenario's result: the JSON file and the flight-path PNG beside it."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

from proxima.scenario.plot import plot_flight


def write_result(result: dict[str, Any], out: Path, title: str) -> Path:
    """Write the JSON to `out` and the flight-path PNG beside it (`out` with .png);
    returns the PNG's path (also recorded in the JSON as `plot`)."""
    png = out.with_suffix(".png")
    homes = {n: d["home_world_enu"] for n, d in result["drones"].items()}
    facing = {n: math.radians(d["facing_deg"]) for n, d in result["drones"].items()}
    expected = {}
    for name, d in result["drones"].items():
        if "expected_landing_ned" in d:
            expected[name] = d["expected_landing_ned"]
        elif "expected_final_ned" in d:
            expected[name] = d["expected_final_ned"]
    status = "PASSED" if result["verdict"]["passed"] else "FAILED"
    plot_flight(
        png, f"{title} - {status}", result["paths"], homes, result["timeline"], facing, expected
    )
    result["plot"] = str(png)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(result, indent=1) + "\n")
    return png
