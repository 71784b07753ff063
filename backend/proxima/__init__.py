"""Proxima: proximal control of several drones by whole-body gestures."""

__version__ = "0.1.0"
