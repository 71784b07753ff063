"""Gesture data, features, models, training and evaluation.

Data flow: data sets (laser.py, uavgesture.py) -> Clip -> windows.py (splits, 60-frame
windows) -> features.py (fitted pipeline) -> models.py -> train.py / evaluate.py;
classifier.py wraps a checkpoint for the live engine.
"""
