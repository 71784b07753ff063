"""The measured constants of the capture model, and the curves made from them.

Two measurements (docs/capture.md has the figures and the reasoning):

- `python -m bench.pose_jitter` (bench/results/pose_jitter.json): the live pose path
  (Tasks PoseLandmarker, VIDEO mode) on still photos at 1280x720 with sensor noise and
  sub-pixel shifts. Jitter is in torso lengths (shoulder midpoint to hip midpoint, x and
  y in one scale), per landmark, against person height and visibility.
- `python -m bench.capture_constants` (bench/results/capture_constants.json): from the
  LASER recordings, person height in torso lengths and visibility at the frame edge.

Tests check these numbers against the two JSON files (tests/gesture/test_capture.py).
"""

from __future__ import annotations

import numpy as np

# --- bench/results/capture_constants.json -----------------------------------------
# Person height / torso length (LASER front view: heel-to-nose span 2.414 torso lengths,
# the nose at 91% of stature).
STATURE_TORSO = 2.653
# Visibility at the frame edge: (signed distance to the nearest edge in torso lengths,
# negative inside; visibility as a factor of the median far inside the frame).
EDGE_DISTANCE = (-1.980, -1.255, -0.783, -0.380, -0.171, -0.056, 0.040, 0.184, 0.365,
                 0.594, 0.852, 1.215, 1.818)  # fmt: skip
EDGE_FACTOR = (1.000, 0.999, 0.974, 0.916, 0.853, 0.795, 0.727, 0.641, 0.330, 0.210,
               0.129, 0.074, 0.040)  # fmt: skip

# --- bench/results/pose_jitter.json ("pooled") --------------------------------------
# Jitter std of the visible landmarks (visibility >= 0.8), torso lengths, per axis:
# JITTER_A + JITTER_B * (REF_HEIGHT / height) ** JITTER_P ("raw_size_law").
REF_HEIGHT = 0.6
JITTER_A = 0.00549
JITTER_B = 0.00270
JITTER_P = 2.494
# Factor for a landmark of visibility v: 1 + VIS_K * (1 - v) ** VIS_Q ("raw_visibility_law").
VIS_K = 12.35
VIS_Q = 1.156
# MediaPipe's z jitters this many times more than x/y, in the metric frame
# (z * aspect * Z_SCALE, as geometry.to_metric) ("z_over_xy_median").
Z_OVER_XY = 12.6
# Lag-1 autocorrelation of the visible landmarks' jitter ("autocorr_xy_visible_median"):
# 0.02 pooled, -0.01 for the astronaut, 0.19 for Grace Hopper's ambiguous readings.
JITTER_CORR = 0.0
# Frame-to-frame step RMS of the visibility itself against the visibility
# ("raw_visibility_factor": median_visibility, visibility_step_rms).
VIS_STEP_AT = (0.081, 0.191, 0.408, 0.593, 0.855, 0.999)
VIS_STEP_RMS = (0.056, 0.101, 0.203, 0.221, 0.129, 0.0012)
# Visibility MediaPipe gives body parts absent from the picture but inside the frame
# (the photos' legs), 25th and 75th percentile ("absent_legs_visibility_p25_p50_p75").
ABSENT_VISIBILITY = (0.333, 0.543)
# Share of the visible landmarks' jitter the tracker's One Euro filter (beta 30) keeps
# ("filter_ratio_visible_median"); for the docs, not used by the model.
ONE_EURO_KEEPS = 0.42


def jitter_torso(height: np.ndarray) -> np.ndarray:
    """Jitter std (torso lengths, per axis) of a fully visible landmark of a person
    `height` (fraction of the frame height) tall."""
    h = np.maximum(np.asarray(height, np.float64), 0.05)
    return JITTER_A + JITTER_B * (REF_HEIGHT / h) ** JITTER_P


def visibility_factor(vis: np.ndarray) -> np.ndarray:
    """How many times more a landmark of visibility `vis` jitters than a visible one."""
    v = np.clip(np.asarray(vis, np.float64), 0.0, 1.0)
    return 1.0 + VIS_K * (1.0 - v) ** VIS_Q


def visibility_noise_sd(vis: np.ndarray) -> np.ndarray:
    """Frame-to-frame std of the visibility itself (white: step RMS / sqrt 2)."""
    return np.interp(vis, VIS_STEP_AT, VIS_STEP_RMS) / np.sqrt(2.0)


def edge_factor(distance: np.ndarray) -> np.ndarray:
    """Visibility factor of a landmark `distance` torso lengths outside the nearest frame
    edge (negative inside); constant beyond the measured range."""
    return np.interp(distance, EDGE_DISTANCE, EDGE_FACTOR)
