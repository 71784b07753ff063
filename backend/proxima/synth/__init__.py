"""The synthetic operator: a kinematic body with anthropometric proportions performing
the 13 marshalling gestures, seen through virtual pinhole cameras as MediaPipe would
report it (docs/synth.md)."""
