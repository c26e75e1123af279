"""Drive Debian's chromium headless with playwright (WebGL in software), the way
/work/shared/notes/browser-testing.md found to work: a fresh profile, SwiftShader flags."""

from __future__ import annotations

import shutil
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from app.errors import HandbenchError

CHROMIUM = "/usr/bin/chromium"
FLAGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--use-angle=swiftshader",
    "--enable-unsafe-swiftshader",
]
HIDE_TOASTS_CSS = ".mantine-Notifications-root { display: none !important; }"


class BrowserMissingError(HandbenchError):
    """Chromium (or playwright) is not installed."""


def chromium_path() -> str:
    """Debian's chromium, or a clear error saying how to install it."""
    p = shutil.which("chromium") if not Path(CHROMIUM).exists() else CHROMIUM
    if not p:
        raise BrowserMissingError(
            f"chromium not found at {CHROMIUM}: install it with `sudo apt-get install chromium`"
        )
    return p


@contextmanager
def browser_context(width: int, height: int, profile_root: Path | None = None) -> Iterator[Any]:
    """A headless chromium context (fresh profile, removed afterwards)."""
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        raise BrowserMissingError(
            "playwright is not installed: `pip install -e '.[test]'`"
        ) from None
    exe = chromium_path()
    if profile_root is not None:
        profile_root.mkdir(parents=True, exist_ok=True)
    tmp = tempfile.mkdtemp(prefix="handbench-chromium-", dir=profile_root)
    try:
        with sync_playwright() as pw:
            ctx = pw.chromium.launch_persistent_context(
                tmp,
                executable_path=exe,
                headless=True,
                args=FLAGS,
                viewport={"width": width, "height": height},
            )
            try:
                yield ctx
            finally:
                ctx.close()
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def wait_drawn(page: Any, client: Any, timeout_s: float = 60.0) -> None:
    """The end of the ready sequence: a WebGL frame rendered, then two animation frames."""
    client.get_render(64, 64, timeout=timeout_s)
    page.evaluate(
        "() => new Promise(r => requestAnimationFrame(() => requestAnimationFrame(() => r(0))))"
    )


def hide_toasts(page: Any) -> None:
    """Hide the notification toasts (the 'software WebGL' warning) before a screenshot."""
    page.add_style_tag(content=HIDE_TOASTS_CSS)
