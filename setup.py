"""The wheel's one build step beyond pyproject.toml: copy the files that ship beside the
code (the default gesture model and its card, the demo's settings, the built console)
from the repository root into the package as `proxima/_shipped/`, where
`proxima.shipped` finds them in an installed wheel. Editable installs skip the copy:
they read the same files at the repository root.

The console must be built first (`make frontend`); the build stops with a message
saying so rather than ship a wheel whose `proxima serve` has no pages.
"""

from __future__ import annotations

import shutil
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

ROOT = Path(__file__).resolve().parent
# Relative to the repository root; the same names inside proxima/_shipped/.
SHIPPED_FILES = (
    "models/gesture-default.pt",
    "models/gesture-default.md",
    "models/synth-only-1560.pt",
    "models/synth-only-1560.md",
    "config/demo.toml",
    "config/demo-sim.toml",
    "config/scenes/demo.toml",
)
STATIC = "static"


class BuildPyWithShipped(build_py):
    """`build_py`, then the shipped files into `<build_lib>/proxima/_shipped/`."""

    def run(self) -> None:
        super().run()
        if self.editable_mode:
            return
        index = ROOT / STATIC / "index.html"
        if not index.is_file():
            raise SystemExit(
                f"{index} is missing: build the console before the wheel "
                "(`make frontend`, or `cd frontend && npm ci && npm run build`)"
            )
        dest = Path(self.build_lib) / "proxima" / "_shipped"
        if dest.exists():
            shutil.rmtree(dest)
        for rel in SHIPPED_FILES:
            (dest / rel).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(ROOT / rel, dest / rel)
        shutil.copytree(ROOT / STATIC, dest / STATIC, ignore=shutil.ignore_patterns(".*"))


setup(cmdclass={"build_py": BuildPyWithShipped})
