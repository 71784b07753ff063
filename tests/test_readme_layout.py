"""The README's layout section names every package folder of backend/proxima and every
top-level folder, so a newcomer's map matches the tree."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def layout() -> str:
    text = (ROOT / "README.md").read_text()
    section = text.split("## Layout", 1)[1]
    return section.split("```", 2)[1]


def test_every_package_is_in_the_layout() -> None:
    block = layout()
    named = set(re.findall(r"([a-z_]+)/", block))
    pkg = ROOT / "backend" / "proxima"
    missing = [
        p.relative_to(pkg).as_posix()
        for p in sorted(pkg.glob("*/")) + sorted(pkg.glob("*/*/"))
        if (p / "__init__.py").is_file() and p.name not in named
    ]
    assert not missing, f"README layout misses {missing}"


def test_top_level_folders_are_in_the_layout() -> None:
    block = layout()
    tracked = {"backend", "bench", "config", "docs", "frontend", "models", "tests"}
    missing = [d for d in sorted(tracked) if f"{d}/" not in block]
    assert not missing, f"README layout misses {missing}"
