"""Shared test set-up: temp folders under build/, and the tests folder on sys.path."""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
(ROOT / "build").mkdir(exist_ok=True)  # pytest's --basetemp=build/pytest lives here
sys.path.insert(0, str(Path(__file__).parent))  # analytic_objects
