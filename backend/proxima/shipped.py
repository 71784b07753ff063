"""Files that ship with Proxima beside its code: the default gesture model and its card,
the synthetic start of federated runs, the demo's settings (and the closed-loop demo's,
with its scene) and the built console (`static/`).

In a checkout they lie at the repository root (`models/`, `config/`, `static/`); the
wheel carries copies inside the package (`proxima/_shipped/`, written by `setup.py`'s
build step), so an installed `proxima` never looks for a repository. Each path here is
only a default: the settings that use one (`[engine] checkpoint`, `[server] static_dir`,
`proxima demo --config`) can name another file.
"""

from __future__ import annotations

import os
from pathlib import Path

_PACKAGE = Path(__file__).resolve().parent
# Where the wheel's build step puts the shipped files (see setup.py).
PACKAGED_DIR = _PACKAGE / "_shipped"
_REPO = _PACKAGE.parents[1]  # backend/proxima -> the repository root, in a checkout

DEFAULT_CHECKPOINT = "models/gesture-default.pt"
# the synthetic operator's model console federated runs start from (`[training] start`)
FEDERATED_START = "models/synth-only-1560.pt"
DEMO_CONFIG = "config/demo.toml"
SIM_DEMO_CONFIG = "config/demo-sim.toml"  # `proxima demo --sim`
STATIC_DIR = "static"


def checkout_root() -> Path | None:
    """The repository root when Proxima runs from a checkout (or an editable install of
    one); None for an installed wheel."""
    if PACKAGED_DIR.is_dir():
        return None
    if (_REPO / "pyproject.toml").is_file() and (_REPO / "backend" / "proxima").is_dir():
        return _REPO
    return None


def shipped_path(relative: str) -> Path:
    """Where the shipped file or folder `relative` (e.g. `DEFAULT_CHECKPOINT`) lies:
    inside the installed package, else at the checkout's root. The path may not exist
    (a checkout whose console is not built yet); callers say so in their own terms."""
    root = checkout_root()
    return (root if root is not None else PACKAGED_DIR) / relative


def offline() -> bool:
    """True when `PROXIMA_OFFLINE` is set (to anything but "", "0", "false", "no"):
    nothing is downloaded (the pose model, the data sets), and a missing file is an error
    saying where it was looked for. Air-gapped ground stations and the tests set it."""
    return os.environ.get("PROXIMA_OFFLINE", "").strip().lower() not in ("", "0", "false", "no")
