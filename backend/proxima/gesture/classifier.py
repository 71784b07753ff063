"""A trained gesture model in one file, and the inference wrapper the live engine uses.

The checkpoint (torch.save of plain types, loadable with weights_only=True) holds the
weights, the model's name and config, the label list, the window length, the feature
pipeline's name and fitted state, the softmax temperature fitted on held-out windows
(gesture/calibration.py; absent in older checkpoints: 1), and free-form metadata
(command, data hash, metrics). An ensemble file (`ENSEMBLE_FORMAT`, gesture/ensemble.py)
holds several such models and metadata of its own.
"""

from __future__ import annotations

import datetime as dt
import math
from pathlib import Path
from typing import Any

import numpy as np
import torch
from torch import nn

from proxima.gesture.features import Pipeline, make_pipeline
from proxima.gesture.geometry import to_metric
from proxima.gesture.models import build_model, model_config
from proxima.gesture.train import predict_proba
from proxima.shipped import DEFAULT_CHECKPOINT, shipped_path
from proxima.types import GESTURES

FORMAT = "proxima-gesture/1"
# several models in one file, their probabilities averaged (proxima.gesture.ensemble)
ENSEMBLE_FORMAT = "proxima-gesture-ensemble/1"
DEFAULT_NAME = Path(DEFAULT_CHECKPOINT).name


def default_checkpoint() -> Path:
    """The shipped default model: `models/gesture-default.pt` in a checkout, its copy
    inside the package in an installed wheel (see `proxima.shipped`)."""
    return shipped_path(DEFAULT_CHECKPOINT)


def checkpoint_blob(
    model: nn.Module,
    model_name: str,
    pipeline: Pipeline,
    window: int,
    metadata: dict[str, Any],
    temperature: float = 1.0,
) -> dict[str, Any]:
    """One model's checkpoint as plain types (weights as float16); `metadata` as given.

    Raises:
        ValueError: a temperature that is not a positive finite number.
    """
    if not (math.isfinite(temperature) and temperature > 0):
        raise ValueError(f"temperature must be a positive number, got {temperature!r}")
    return {
        "format": FORMAT,
        "model": model_name,
        "config": model_config(model),
        "state_dict": {k: v.detach().cpu().half() if v.is_floating_point() else v
                       for k, v in model.state_dict().items()},
        "labels": list(GESTURES),
        "window": window,
        "temperature": float(temperature),
        "pipeline": {"name": pipeline.name, "state": pipeline.state()},
        "metadata": metadata,
    }  # fmt: skip


def write_blob(path: str | Path, blob: dict[str, Any]) -> Path:
    """torch.save `blob` at `path` atomically (a temp file, then a rename)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(path.suffix + ".tmp")
    torch.save(blob, tmp)
    tmp.replace(path)
    return path


def created_now() -> str:
    """The `created` stamp of a new checkpoint's metadata (UTC, seconds)."""
    return dt.datetime.now(dt.UTC).isoformat(timespec="seconds")


def save_checkpoint(
    path: str | Path,
    model: nn.Module,
    model_name: str,
    pipeline: Pipeline,
    window: int,
    metadata: dict[str, Any],
    temperature: float = 1.0,
) -> Path:
    """Write a self-contained checkpoint (atomically: a temp file, then a rename).

    Raises:
        ValueError: a temperature that is not a positive finite number.
    """
    meta = {"created": created_now(), **metadata}
    return write_blob(path, checkpoint_blob(model, model_name, pipeline, window, meta, temperature))


def read_blob(path: str | Path | None) -> tuple[Path, dict[str, Any]]:
    """(path, contents) of a Proxima checkpoint file, one model's or an ensemble's
    (default: the shipped model).

    Raises:
        FileNotFoundError: no such file.
        ValueError: the file is not a Proxima gesture checkpoint.
    """
    path = Path(path) if path else default_checkpoint()
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such checkpoint")
    try:
        blob = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as exc:
        raise ValueError(f"{path}: not a readable checkpoint ({exc})") from exc
    if not isinstance(blob, dict) or blob.get("format") not in (FORMAT, ENSEMBLE_FORMAT):
        raise ValueError(f"{path}: not a Proxima gesture checkpoint (format {FORMAT})")
    return path, blob


class GestureClassifier:
    """Classifies 60-frame windows of MediaPipe landmarks into the 13 gestures."""

    def __init__(self, model: nn.Module, model_name: str, pipeline: Pipeline, window: int,
                 labels: tuple[str, ...], metadata: dict[str, Any],
                 temperature: float = 1.0) -> None:  # fmt: skip
        self.model = model.eval()
        self.temperature = temperature  # softmax(logits / T): calibrated probabilities
        self.model_name = model_name
        self.pipeline = pipeline
        self.window = window
        self.labels = labels
        self.metadata = metadata

    @property
    def window_clock(self) -> str:
        """The engine window's clock for this model: "time" if its training windows were
        resampled to 30 per second (`TrainConfig.window_clock` time or mixed), else
        "poses" (also every checkpoint made before the option)."""
        clock = self.metadata.get("train_config", {}).get("window_clock", "poses")
        return "time" if clock in ("time", "mixed") else "poses"

    @classmethod
    def load(cls, path: str | Path | None = None) -> GestureClassifier:
        """Load one model's checkpoint (default: the shipped model, which is an ensemble:
        `proxima.gesture.ensemble.load_checkpoint` reads both kinds).

        Raises:
            FileNotFoundError: no such file.
            ValueError: the file is not a Proxima gesture checkpoint, or holds an ensemble.
        """
        path, blob = read_blob(path)
        if blob["format"] == ENSEMBLE_FORMAT:
            n = len(blob.get("members") or [])
            raise ValueError(
                f"{path}: an ensemble of {n} models, where one model is needed; "
                "`proxima ensemble split` writes its members as files"
            )
        return cls.from_blob(blob, path)

    @classmethod
    def from_blob(cls, blob: dict[str, Any], path: str | Path) -> GestureClassifier:
        """The classifier of one model's checkpoint contents (`path` names it in errors).

        Raises:
            ValueError: a field missing or malformed, features or temperature that do not fit.
        """
        if not isinstance(blob, dict) or blob.get("format") != FORMAT:
            raise ValueError(f"{path}: not a Proxima gesture model (format {FORMAT})")
        try:
            return cls._from_fields(blob, path)
        except (KeyError, TypeError, RuntimeError) as exc:  # RuntimeError: weights not fitting
            why = f"{type(exc).__name__}: {exc}"
            raise ValueError(f"{path}: a malformed checkpoint ({why})") from exc

    @classmethod
    def _from_fields(cls, blob: dict[str, Any], path: str | Path) -> GestureClassifier:
        model = build_model(blob["model"], **blob["config"])
        pipeline = make_pipeline(blob["pipeline"]["name"], blob["pipeline"]["state"])
        expected = blob["config"].get("num_features")
        if expected != pipeline.num_features:  # made before the pipeline changed
            raise ValueError(
                f"{path}: made for {expected} features a frame, but the {pipeline.name!r} "
                f"pipeline now gives {pipeline.num_features}; retrain it"
            )
        sd = blob["state_dict"]
        state = {k: v.float() if v.is_floating_point() else v for k, v in sd.items()}
        model.load_state_dict(state)
        temperature = float(blob.get("temperature", 1.0))  # older checkpoints: uncalibrated
        if not (math.isfinite(temperature) and temperature > 0):
            raise ValueError(f"{path}: temperature {temperature!r} is not a positive number")
        return cls(model, blob["model"], pipeline, int(blob["window"]), tuple(blob["labels"]),
                   blob.get("metadata", {}), temperature)  # fmt: skip

    def blob(self) -> dict[str, Any]:
        """This model as checkpoint contents (`checkpoint_blob`), its metadata as it is."""
        return checkpoint_blob(self.model, self.model_name, self.pipeline, self.window,
                               self.metadata, self.temperature)  # fmt: skip

    def features(self, xyz: np.ndarray, aspect: float | np.ndarray = 16 / 9,
                 has_z: bool = True) -> np.ndarray:  # fmt: skip
        """Model input for windows xyz (N, W, 33, 3) in normalised image coordinates."""
        hz = np.full(len(xyz), has_z)
        return self.pipeline.transform(to_metric(xyz, np.broadcast_to(aspect, (len(xyz),))), hz)

    def predict(self, xyz: np.ndarray, aspect: float | np.ndarray = 16 / 9) -> np.ndarray:
        """Softmax probabilities (N, 13) for windows xyz (N, W, 33, 3) (normalised image
        coordinates, as MediaPipe gives them; `aspect` = image width / height)."""
        xyz = np.asarray(xyz, np.float32)
        if xyz.ndim != 4 or xyz.shape[1:] != (self.window, 33, 3):
            raise ValueError(f"expected windows (N, {self.window}, 33, 3), got {xyz.shape}")
        return predict_proba(self.model, self.features(xyz, aspect), temperature=self.temperature)
