"""Load one or more data folders (`--data` given once or more) into clips."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from proxima.gesture.clip import Clip, DataError
from proxima.gesture.console_samples import load_console_samples
from proxima.gesture.data_source import SAMPLES_PREFIX, resolve_dataset, sha256
from proxima.gesture.laser import load_laser_dir
from proxima.gesture.uavgesture import is_uavgesture_dir, load_uavgesture_dir


@dataclass
class LoadedData:
    clips: list[Clip]
    folders: list[Path]
    uav_dir: Path | None  # the UAV-Gesture folder, if one was given (for its splits)

    def fingerprint(self) -> str:
        """SHA-256 over the SHA-256s of every data file, for the model card."""
        import hashlib

        h = hashlib.sha256()
        for folder in self.folders:
            if folder.is_file():  # a console database (samples:DB)
                h.update(f"{folder.name}:{sha256(folder)}\n".encode())
                continue
            for f in sorted(folder.rglob("*")):
                if f.is_file() and f.suffix in (".csv", ".mat", ".txt", ".json"):
                    h.update(f"{f.relative_to(folder)}:{sha256(f)}\n".encode())
        return h.hexdigest()


def load_data(specs: Sequence[str | Path] | None = None) -> LoadedData:
    """Resolve and load every `--data` folder (default: the LASER set). A synthetic data
    set (`synth:DIR`, or any folder with the manifest of `proxima synth`) loads as
    source `synth`, whose clips every split keeps for training only (windows.py);
    `samples:DB` loads the console's kept samples as source `console`.

    Raises:
        DataError: a folder that is neither a LASER, a UAV-Gesture nor a synthetic data
            set, or bad data.
    """
    from proxima.synth.dataset import is_synth_dir, load_synth_dir

    clips: list[Clip] = []
    folders: list[Path] = []
    uav_dir = None
    chosen: Sequence[str | Path | None] = specs or (None,)
    for spec in chosen:
        folder = resolve_dataset(spec)
        folders.append(folder)
        if str(spec).startswith(SAMPLES_PREFIX):
            clips += load_console_samples(folder)
        elif is_uavgesture_dir(folder):
            uav_dir = folder
            clips += load_uavgesture_dir(folder)
        elif is_synth_dir(folder):  # before LASER: its CSVs are in the LASER format
            clips += load_synth_dir(folder)
        elif any(folder.glob("*.MP4.csv")):
            clips += load_laser_dir(folder)
        else:
            raise DataError(
                f"{folder}: neither a LASER folder (*.MP4.csv), UAV-Gesture (joint_positions/) "
                "nor a synthetic data set (manifest.json)"
            )
    return LoadedData(clips, folders, uav_dir)
