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


def _screen(camera, p, box) -> tuple[float, float]:  # noqa: ANN001
    """Page pixel of world point ``p`` (m) seen by viser's camera on the canvas ``box``."""
    pos, look = np.asarray(camera.position, float), np.asarray(camera.look_at, float)
    f = (look - pos) / np.linalg.norm(look - pos)
    r = np.cross(f, np.asarray(camera.up_direction, float))
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    v = np.asarray(p, float) - pos
    t = np.tan(float(camera.fov) / 2)
    nx = float(v @ r) / (float(v @ f) * t * float(camera.aspect))
    ny = float(v @ u) / (float(v @ f) * t)
    return box["x"] + (nx + 1) / 2 * box["width"], box["y"] + (1 - ny) / 2 * box["height"]


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
            # the value labels' size on screen: 9 pt at 100 dpi in the layout (12.5 px)
            label_px = 9 / 72 * 100
            shown = page.evaluate(
                "() => Math.max(...[...document.images].filter(i => i.naturalWidth === 400)"
                ".map(i => i.clientWidth / i.naturalWidth))"
            )
            print(f"panel map: shown at {shown:.2f}x, value labels {label_px * shown:.1f} px")

            # the clickable map in the scene: show it, click a design, time the star
            page.get_by_role("button", name="Pick a design on the map (3-D view)").click()
            sm = s.map_panel.scene_map
            assert sm is not None
            t_end = time.monotonic() + 30
            while not (sm.visible and sm.shown_at) and time.monotonic() < t_end:
                time.sleep(0.05)
            wait_drawn(page, s.client, 60)
            page.wait_for_timeout(500)
            base = s.map_panel._scene_base  # noqa: SLF001
            assert base is not None
            cam, box = s.client.camera, page.locator("canvas").first.bounding_box()
            assert box is not None
            top = _screen(cam, sm.placement.world_of_pixel(0, 0, base.size), box)
            bottom = _screen(cam, sm.placement.world_of_pixel(0, base.size[1], base.size), box)
            scale = (bottom[1] - top[1]) / base.size[1]
            print(
                f"scene map: {base.size[1]} px image shown {bottom[1] - top[1]:.0f} px tall, "
                f"value labels {label_px * base.scale * scale:.1f} px"
            )
            page.screenshot(path=str(out / "map_scene.png"))
            target = _screen(
                cam, sm.placement.world_of_pixel(*base.pixel(15.0, 60.0), base.size), box
            )
            t0 = time.monotonic()
            page.mouse.click(*target)
            while s.map_panel.star_at != (15.0, 60.0) and time.monotonic() - t0 < 10:
                time.sleep(0.01)
            t_star = time.monotonic() - t0
            while sm.shown_at < t0 and time.monotonic() - t0 < 10:
                time.sleep(0.01)
            t_scene = sm.shown_at - t0
            print(
                f"click on CMC 15°, MCP 60°: picks {sm.picks}, design "
                f"({s.design.cmc_deg:g}, {s.design.mcp_deg:g}); star in the panel map "
                f"{t_star:.2f} s, in the scene map {t_scene:.2f} s after the click"
            )
            wait_drawn(page, s.client, 60)
            page.wait_for_timeout(500)
            page.screenshot(path=str(out / "map_scene_clicked.png"))
    finally:
        srv.stop()
    print(
        f"wrote {out}/design_c30_m45.png, design_c30_m75.png, replay_three_colours.png, "
        "map_tab.png, map_scene.png, map_scene_clicked.png"
    )


if __name__ == "__main__":
    main()
