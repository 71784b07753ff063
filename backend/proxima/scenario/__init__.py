"""Scenarios that fly the whole system end to end in simulation: the paper's real-robot
flight with a handover between two drones (`paper_flight`) and the paper's simulation
experiment with two drones commanded to their final positions (`two_drones`).

Each one stitches replay streams from the LASER clips, runs them through the live
engine, the arbiter and the drone controller over MAVLink to `proxima sim-drone`
processes on 127.0.0.1, and judges what happened (`verdict`). See docs/scenario.md.
"""
