"""``handbench screenshot``: open a state of the explorer in headless chromium and save a
picture of the page (3-D view and panels), e.g. for docs and reports.

By default the picture waits until the Live S_GAS panel is complete (``--no-wait``: take it
at once, numbers possibly still computing). Chromium's throw-away profile lives under
``$XDG_CACHE_HOME/handbench/chromium`` (``~/.cache/...``), never in the current folder.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from app import cache_root
from app.errors import HandbenchError, SettingsError
from app.explorer.browser import browser_context, hide_toasts, wait_drawn
from app.explorer.server import ExplorerServer, workers_from_env
from app.explorer.session import Session
from app.explorer.url_state import UrlState


def parse_size(text: str) -> tuple[int, int]:
    """'1400x900' -> (1400, 900)."""
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise SettingsError(f"--size takes WxH in pixels, e.g. 1400x900; got {text!r}") from None
    if not (200 <= w <= 8000 and 200 <= h <= 8000):
        raise SettingsError(f"--size must be between 200x200 and 8000x8000, got {text!r}")
    return w, h


def profile_root() -> Path:
    """Where chromium's throw-away profiles go: ``$XDG_CACHE_HOME/handbench/chromium``."""
    return cache_root() / "chromium"


def take_screenshot(
    out: Path,
    state: UrlState,
    size: tuple[int, int] = (1400, 900),
    view: str = "scene",
    store_path: str | Path | None = None,
    server: ExplorerServer | None = None,
    timeout_s: float = 90.0,
    wait_sgas: bool = True,
    sgas_timeout_s: float = 600.0,
) -> Path:
    """Serve (unless ``server`` is given), open ``state`` in chromium, save a PNG of the page.

    ``wait_sgas``: first wait (up to ``sgas_timeout_s``) for the Live S_GAS computation of
    the design to complete, so the picture shows final numbers."""
    own = server is None
    # the S_GAS panel computes in a thread here (no process pool for one picture)
    workers = workers_from_env()
    srv = server or ExplorerServer(
        "127.0.0.1", 0, store_path, workers=0 if workers is None else workers
    )
    tab = "map" if view == "map" else ("grasp" if state.gh is not None else None)
    url = srv.url + "/" + UrlState(state.cmc_deg, state.mcp_deg, state.object_key,
                                   state.gh, tab, state.tilt).query()  # fmt: skip
    try:
        w, h = size
        with browser_context(w, h, profile_root()) as ctx:
            page = ctx.new_page()
            page.goto(url)
            page.get_by_text("CMC (°)").first.wait_for(timeout=timeout_s * 1000)
            before = set(srv.sessions)
            session = srv.wait_for_session(timeout_s)[-1]
            for s in srv.sessions.values():
                if s.client.client_id not in before:
                    session = s
            wait_drawn(page, session.client, timeout_s)
            if wait_sgas:
                wait_sgas_complete(session, sgas_timeout_s)
            if view == "map":
                page.get_by_role("tab", name="Map").click()
                session.map_panel.refresh()
                t_end = time.monotonic() + timeout_s
                while session.map_panel._busy and time.monotonic() < t_end:  # noqa: SLF001
                    time.sleep(0.05)
            elif state.gh is not None:
                page.get_by_role("tab", name="Grasp").click()
            hide_toasts(page)
            wait_drawn(page, session.client, timeout_s)
            page.wait_for_timeout(500)
            out.parent.mkdir(parents=True, exist_ok=True)
            page.screenshot(path=str(out))
    finally:
        if own:
            srv.stop()
    return out


def wait_sgas_complete(session: Session, timeout_s: float) -> None:
    """Block until the tab's Live S_GAS snapshot is complete (or raise ``TimeoutError``)."""
    t_end = time.monotonic() + timeout_s
    while time.monotonic() < t_end:
        last = session.score_panel.last
        if last is not None and last.state == "complete":
            return
        if last is not None and last.state.startswith("error"):
            raise HandbenchError(f"S_GAS failed: {last.state}")
        time.sleep(0.1)
    raise TimeoutError(f"S_GAS did not complete in {timeout_s:g} s (use --no-wait)")


def screenshot_cli(args: argparse.Namespace) -> int:
    """Entry point of ``handbench screenshot`` (flags parsed in ``app.cli``)."""
    size = parse_size(args.size)
    tilt = getattr(args, "cmc_tilt", None)
    state = UrlState(args.cmc, args.mcp, args.object, args.gh,
                     tilt=None if tilt in (None, "ulnar") else tilt)  # fmt: skip
    t0 = time.perf_counter()
    try:
        out = take_screenshot(
            Path(args.out), state, size, args.view, args.store,
            wait_sgas=not getattr(args, "no_wait", False),
        )  # fmt: skip
    except TimeoutError as e:
        raise HandbenchError(f"the explorer page did not become ready: {e}") from None
    print(f"wrote {out} ({size[0]}x{size[1]}, {time.perf_counter() - t0:.1f} s)", file=sys.stderr)
    return 0
