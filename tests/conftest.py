"""Shared test set-up: temp folders under build/."""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
(ROOT / "build").mkdir(exist_ok=True)  # pytest's --basetemp=build/pytest lives here
