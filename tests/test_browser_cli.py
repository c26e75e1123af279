"""The ``handbench screenshot`` command in a real browser (its own playwright and chromium,
so it runs outside test_browser.py's shared browser)."""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import numpy as np
import pytest

pytestmark = pytest.mark.browser

if not Path("/usr/bin/chromium").exists():
    pytest.skip(
        "Debian's chromium is missing at /usr/bin/chromium: `sudo apt-get install chromium`",
        allow_module_level=True,
    )
pytest.importorskip("playwright.sync_api", reason="playwright is not installed")

BUILD = Path(__file__).resolve().parents[1] / "build" / "test_browser_cli"


def not_blank(img: np.ndarray) -> bool:
    """More than a flat colour: some pixels differ clearly from the background."""
    rgb = img[..., :3].astype(float)
    return float(rgb.std()) > 5.0 and len(np.unique(rgb.reshape(-1, 3), axis=0)) > 50


def test_screenshot_command(monkeypatch: pytest.MonkeyPatch) -> None:
    from app.explorer.screenshot import screenshot_cli

    monkeypatch.setenv("HANDBENCH_EXPLORER_OBJECTS", "small_marker")
    monkeypatch.setenv("HANDBENCH_EXPLORER_WORKERS", "0")
    import shutil

    shutil.rmtree(BUILD, ignore_errors=True)
    cwd = BUILD / "cwd"
    cwd.mkdir(parents=True)
    monkeypatch.chdir(cwd)  # the command must not write a profile here
    monkeypatch.setenv("XDG_CACHE_HOME", str(BUILD / "cache"))
    out = BUILD / "cli.png"
    args = argparse.Namespace(
        cmc=30.0, mcp=75.0, cmc_tilt="ulnar", object="small_marker", gh="3", out=str(out),
        size="900x600", view="scene", store=str(BUILD / "cli_store.sqlite"), no_wait=True,
    )  # fmt: skip
    assert screenshot_cli(args) == 0
    assert list(cwd.iterdir()) == []
    assert (BUILD / "cache" / "handbench" / "chromium").is_dir()
    import matplotlib.pyplot as plt

    img = plt.imread(out)
    assert img.shape[:2] == (600, 900)
    assert not_blank((img * 255).astype(np.uint8))
    assert os.path.getsize(out) > 10_000
