"""Pictures of the explorer as a designer sees it (issue 13): the design tab at CMC 30°,
MCP 45° and then 75° (typed into the box, the previous thumb as a ghost), a final grasp with
all three contact colours, and the map tab. Prints what each picture holds.

Usage: PYTHONPATH=. .venv/bin/python benchmarks/explorer_shots.py [--out build/shots]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--out", default=str(ROOT / "build" / "shots"))
    a = ap.parse_args()
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)

    from app.explorer.browser import browser_context, hide_toasts, wait_drawn
    from app.explorer.server import ExplorerServer
    from app.explorer.url_state import UrlState

    build = ROOT / "build" / "explorer_shots"
    build.mkdir(parents=True, exist_ok=True)
    # the shipped reference fills the map; no S_GAS computation (long debounce) for pictures
    srv = ExplorerServer("127.0.0.1", 0, build / "store.sqlite", workers=0, debounce_s=600.0)
    try:
        with browser_context(1400, 900, build / "profiles") as ctx:
            page = ctx.new_page()
            page.goto(srv.url + "/?cmc=30&mcp=45&object=chips_can&gh=0")
            page.get_by_text("CMC (°)", exact=True).wait_for(timeout=60_000)
            s = srv.wait_for_session(60)[0]
            wait_drawn(page, s.client, 60)
            hide_toasts(page)
            s.view_dd.value = "thumb close-up"
            wait_drawn(page, s.client, 60)
            page.wait_for_timeout(500)
            before = s.client.get_render(600, 800, transport_format="png", timeout=60)
            page.screenshot(path=str(out / "design_c30_m45.png"))
            row = page.locator("div:has(> .mantine-Slider-root)").nth(1)
            box = row.locator("input[type=text]")
            box.click()
            box.press("Control+A")
            box.press_sequentially("75")
            box.press("Enter")
            t_end = time.monotonic() + 30
            while s.design.mcp_deg != 75.0 and time.monotonic() < t_end:
                time.sleep(0.05)
            wait_drawn(page, s.client, 60)
            page.wait_for_timeout(300)
            after = s.client.get_render(600, 800, transport_format="png", timeout=60)
            page.screenshot(path=str(out / "design_c30_m75.png"))
            diff = np.abs(before[..., :3].astype(int) - after[..., :3].astype(int)).sum(-1) > 30
            print(
                f"design tab: MCP 45° -> 75° at CMC 30° changed {int(diff.sum())} of "
                f"{diff.size} pixels of the 3-D view (800x600, thumb close-up)"
            )

            # a final grasp with palmar, non-palmar and palm contacts
            s.apply_state(UrlState(0.0, 0.0, "power_drill", "0"))
            page.get_by_role("tab", name="Grasp").click()
            s.view_dd.value = "grasp"
            page.get_by_role("button", name="Play replay").click()
            t_end = time.monotonic() + 60
            while time.monotonic() < t_end:
                if s.replay_panel.stage.content == "final grasp" and s.object_view.n_contacts:
                    break
                time.sleep(0.1)
            wait_drawn(page, s.client, 60)
            page.wait_for_timeout(300)
            page.screenshot(path=str(out / "replay_three_colours.png"))
            print(
                f"replay power_drill GH 0 at CMC 0°, MCP 0°: {s.object_view.n_contacts} contacts, "
                f"classes {sorted(s.object_view.classes)}"
            )

            page.get_by_role("tab", name="Map").click()
            s.design_panel.set_design(30.0, 75.0)
            t0 = time.monotonic()
            while s.map_panel.star_at != (30.0, 75.0) and time.monotonic() - t0 < 10:
                time.sleep(0.01)
            print(
                f"map: star at {s.map_panel.star_at} {time.monotonic() - t0:.2f} s after the design"
            )
            t_end = time.monotonic() + 30
            while s.map_panel._busy and time.monotonic() < t_end:  # noqa: SLF001
                time.sleep(0.05)
            page.wait_for_timeout(800)
            page.screenshot(path=str(out / "map_tab.png"))
            print(f"map: {len(s.map_panel.points)} designs, {s.map_panel.renders} full renders")
    finally:
        srv.stop()
    print(
        f"wrote {out}/design_c30_m45.png, design_c30_m75.png, replay_three_colours.png, map_tab.png"
    )


if __name__ == "__main__":
    main()
