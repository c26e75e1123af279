"""Shared test set-up: temp folders under build/."""

from __future__ import annotations

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
(ROOT / "build").mkdir(exist_ok=True)  # pytest's --basetemp=build/pytest lives here


@pytest.fixture(autouse=True)
def _user_objects_in_tmp(
    tmp_path_factory: pytest.TempPathFactory, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Imports saved by a test go to a temporary folder, never to the user's data folder."""
    monkeypatch.setenv("HANDBENCH_USER_OBJECTS", str(tmp_path_factory.mktemp("user_objects")))
