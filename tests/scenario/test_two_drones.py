"""The paper's simulation experiment, through the Python API: two real simulated drones,
each commanded by its own camera's recognised gestures to its final position."""

from __future__ import annotations

from pathlib import Path

import pytest

from proxima.scenario.fleet import pid_alive
from proxima.scenario.result import write_result
from proxima.scenario.two_drones import TwoDronesConfig, run_two_drones


@pytest.mark.slow
@pytest.mark.timeout(240)
def test_two_drones_reach_their_final_positions(tmp_path: Path, checkpoint: Path) -> None:
    import torch

    torch.set_num_threads(1)
    result = run_two_drones(TwoDronesConfig(checkpoint=checkpoint, work_dir=tmp_path / "work"))
    png = write_result(result, tmp_path / "two.json", "two drones")
    assert png.is_file() and png.read_bytes()[:4] == b"\x89PNG"
    assert (tmp_path / "two.json").is_file()

    verdict = result["verdict"]
    assert verdict["passed"] is True, verdict
    for name, gestures in (
        ("uav1", "have_command@uav1, move_to_left@uav1, move_upward@uav1, wave_off@uav1"),
        ("uav2", "have_command@uav2, move_to_right@uav2, move_ahead@uav2, wave_off@uav2"),
    ):
        assert f"{name}: gesture commands as performed: {gestures}" in verdict["reasons"]
        state = result["drones"][name]
        assert state["landed"] == "in_air"
        # Final positions follow the mapping: uav1 1 m left (west) and 1 m up; uav2 (heading
        # north) 1 m right (east) and 1 m ahead (north).
        expected = {"uav1": (0.0, -1.0, -1.0), "uav2": (1.0, 1.0, 0.0)}[name]
        moved = [p - s for p, s in zip(state["position_ned"], state["start_ned"], strict=True)]
        assert all(abs(m - e) < 0.3 for m, e in zip(moved, expected, strict=True)), moved

    # Each drone's commands came from its own camera and went to it alone.
    commands = [e for e in result["timeline"] if e["kind"] == "command" and e["stream"]]
    assert commands and all(c["drone"] == c["stream"] == c["scope"] for c in commands)
    assert result["simulator_exit_codes"] == {"uav1": 0, "uav2": 0}
    pids = result["simulator_pids"]
    assert set(pids) == {"uav1", "uav2"} and not any(pid_alive(p) for p in pids.values())
