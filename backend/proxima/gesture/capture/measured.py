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
# Jitter std of the visible landmarks (visibility >= 0.8), torso lengths, per axis, of a
# person the estimator reads confidently (the reference photo, the astronaut):
# JITTER_A + JITTER_B * (REF_HEIGHT / height) ** JITTER_P ("raw_size_law").
REF_HEIGHT = 0.6
JITTER_A = 0.00713
JITTER_B = 0.00018
JITTER_P = 3.880
# A person the estimator reads ambiguously (Grace Hopper: dark clothes, the body's place
# wavers) jitters this many times more ("grace_hopper": "raw_over_reference_law_median").
AMBIGUOUS_READING = 6.4
# Jitter factor against visibility, interpolated between knots (bin medians of every
# landmark's jitter over its run's visible median, non-increasing; "raw_visibility_knots").
VIS_FACTOR_AT = (0.228, 0.424, 0.571, 0.851, 0.999)
VIS_FACTOR = (11.39, 5.58, 5.58, 1.94, 1.0)
# MediaPipe's z jitters this many times more than x/y, in the metric frame
# (z * aspect * Z_SCALE, as geometry.to_metric) ("z_over_xy_median").
Z_OVER_XY = 23.4
# Lag-1 autocorrelation of the visible landmarks' jitter ("autocorr_xy_visible_median"):
# 0.05 pooled, 0.02 for the reference photo (0.26-0.42 for it below height 0.3).
JITTER_CORR = 0.0
# Frame-to-frame step RMS of the visibility itself against the visibility
# ("raw_visibility_factor": median_visibility, visibility_step_rms).
VIS_STEP_AT = VIS_FACTOR_AT
VIS_STEP_RMS = (0.127, 0.216, 0.213, 0.059, 0.001)
# Visibility MediaPipe gives body parts absent from the picture but inside the frame
# (the photos' legs), 25th and 75th percentile ("absent_legs_visibility_p25_p50_p75").
ABSENT_VISIBILITY = (0.379, 0.529)
# Share of the visible landmarks' jitter the tracker's One Euro filter (beta 30) keeps
# ("filter_ratio_visible_median"); for the docs, not used by the model.
ONE_EURO_KEEPS = 0.44


def jitter_torso(height: np.ndarray | float) -> np.ndarray:
    """Jitter std (torso lengths, per axis) of a fully visible landmark of a person
    `height` (fraction of the frame height) tall."""
    h = np.maximum(np.asarray(height, np.float64), 0.05)
    return JITTER_A + JITTER_B * (REF_HEIGHT / h) ** JITTER_P


def visibility_factor(vis: np.ndarray | float) -> np.ndarray:
    """How many times more a landmark of visibility `vis` jitters than a visible one."""
    return np.asarray(np.interp(vis, VIS_FACTOR_AT, VIS_FACTOR))


def visibility_noise_sd(vis: np.ndarray | float) -> np.ndarray:
    """Frame-to-frame std of the visibility itself (white: step RMS / sqrt 2)."""
    return np.asarray(np.interp(vis, VIS_STEP_AT, VIS_STEP_RMS)) / np.sqrt(2.0)


def edge_factor(distance: np.ndarray | float) -> np.ndarray:
    """Visibility factor of a landmark `distance` torso lengths outside the nearest frame
    edge (negative inside); constant beyond the measured range."""
    return np.asarray(np.interp(distance, EDGE_DISTANCE, EDGE_FACTOR))
