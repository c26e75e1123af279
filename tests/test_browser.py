"""The explorer in a real browser: Debian's chromium, headless, WebGL in software.

Ready sequence of /work/shared/notes/browser-testing.md: the client connected, a known GUI
element visible, a WebGL frame rendered (``client.get_render``), two animation frames.
Checks are made server-side (the tab's session state and its scene-node poses) and on
pictures (not blank, right size).
"""

from __future__ import annotations

import shutil
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

pytestmark = pytest.mark.browser

if not Path("/usr/bin/chromium").exists():
    pytest.skip(
        "Debian's chromium is missing at /usr/bin/chromium: `sudo apt-get install chromium`",
        allow_module_level=True,
    )
pytest.importorskip("playwright.sync_api", reason="playwright is not installed")

from app.explorer.browser import browser_context, hide_toasts, wait_drawn  # noqa: E402
from app.explorer.server import ExplorerServer  # noqa: E402
from app.explorer.session import Session  # noqa: E402

BUILD = Path(__file__).resolve().parents[1] / "build" / "test_browser"
OBJECTS = ["chips_can"]  # one object keeps the live S_GAS work small
NO_SGAS_S = 3600.0
"""The tabs' S_GAS debounce: no computation (it would take the CPU the browser needs) except
in the test that checks it starts."""


def wait_until(cond: Callable[[], Any], timeout: float = 30.0, what: str = "condition") -> Any:
    t_end = time.monotonic() + timeout
    while time.monotonic() < t_end:
        v = cond()
        if v:
            return v
        time.sleep(0.05)
    raise AssertionError(f"timed out after {timeout:g} s waiting for {what}")


def not_blank(img: np.ndarray) -> bool:
    """More than a flat colour: some pixels differ clearly from the background."""
    rgb = img[..., :3].astype(float)
    return float(rgb.std()) > 5.0 and len(np.unique(rgb.reshape(-1, 3), axis=0)) > 50


@pytest.fixture(scope="module")
def server() -> Iterator[ExplorerServer]:
    shutil.rmtree(BUILD, ignore_errors=True)
    BUILD.mkdir(parents=True)
    srv = ExplorerServer(
        "127.0.0.1", 0, BUILD / "store.sqlite", objects=OBJECTS, workers=0,
        shots_dir=BUILD / "shots", debounce_s=NO_SGAS_S,
    )  # fmt: skip
    yield srv
    srv.stop()


@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    """One chromium for the module (each test opens and closes its own tabs; the screenshot
    command, which starts its own playwright, is tested in test_browser_cli.py)."""
    with browser_context(1280, 800, BUILD / "profiles") as ctx:
        yield ctx


def open_tab(server: ExplorerServer, browser: Any, query: str = "") -> tuple[Any, Session]:
    """Open a tab and return it with its session once the ready sequence completed."""
    before = set(server.sessions)
    page = browser.new_page()
    page.goto(server.url + "/" + query)
    page.get_by_text("CMC (°)", exact=True).wait_for(timeout=30_000)
    new = wait_until(lambda: set(server.sessions) - before, 30, "the tab's session")
    session = server.sessions[new.pop()]
    wait_until(session.ready.is_set, 30, "the link state to be applied")
    wait_drawn(page, session.client, 30)
    return page, session


def slider(page: Any, label: str) -> Any:
    """The role=slider of the row labelled ``label``."""
    row = page.locator("div").filter(has=page.get_by_text(label, exact=True))
    return row.filter(has=page.get_by_role("slider")).last.get_by_role("slider")


def closed_toasts(page: Any) -> list[str]:
    """The viser toasts the page script closed ('title | description')."""
    return page.evaluate("() => window.__hbToasts || []")


def test_page_draws_hand(server: ExplorerServer, browser: Any) -> None:
    from app.explorer.page_toasts import WEBGL_TOAST_S

    page, s = open_tab(server, browser)
    try:
        assert set(s.hand_view.nodes) >= {"palm", "thumb_distal", "index_distal"}
        # the software-WebGL toast closes by itself (SwiftShader here)
        webgl = page.get_by_text("Software WebGL rendering detected")
        webgl.wait_for(state="hidden", timeout=(WEBGL_TOAST_S + 10) * 1000)
        assert any(t.startswith("Software WebGL") for t in closed_toasts(page))
        # the tab's probe reported the renderer: the scene then waits for the first estimate
        assert s.webgl_renderer and s.software_webgl, s.webgl_renderer
        # no hover hints (they covered the tab bar): captions instead
        handles = s.client.gui._gui_input_handle_from_uuid.values()  # noqa: SLF001
        hints = [getattr(h, "hint", None) for h in handles]
        assert hints and all(h is None for h in hints)
        img = s.client.get_render(300, 400, transport_format="png", timeout=30)
        assert img.shape[:2] == (300, 400) and not_blank(img)
        hide_toasts(page)
        shot = BUILD / "page.png"
        page.screenshot(path=str(shot))
        import matplotlib.pyplot as plt

        assert not_blank((plt.imread(shot) * 255).astype(np.uint8))
        # Share tab: save the view as PNG (written under shots_dir and sent as a download)
        page.get_by_role("tab", name="Share").click()
        assert "cmc=0&mcp=45&object=chips_can&gh=0" in s.share_panel.link.content
        page.get_by_role("button", name="Save PNG of the view").click()
        wait_until(lambda: "saved" in s.share_panel.saved.content, 30, "the saved PNG")
        saved = list((BUILD / "shots").glob("handbench_c0_m45_chips_can_gh0_*.png"))
        assert saved and not_blank((plt.imread(saved[0]) * 255).astype(np.uint8))
        # the saved path and the link wrap inside the panel
        for text in ("(and sent as a download)", "Link to this state:"):
            el = page.get_by_text(text).last
            el.wait_for()
            fits = el.evaluate("e => e.scrollWidth <= e.clientWidth + 1")
            panel_right = page.get_by_role("tab", name="Share").evaluate(
                "e => e.closest('[role=tablist]').getBoundingClientRect().right"
            )
            box = el.bounding_box()
            assert fits and box["x"] + box["width"] <= panel_right + 2, text
        # import: viser's "File uploaded successfully." toast is closed; the verdict stays
        page.get_by_role("tab", name="Design").click()
        page.get_by_text("Import a mesh").click()
        page.locator("input[type=file]").set_input_files(
            files=[{"name": "flat.stl", "mimeType": "model/stl",
                    "buffer": b"solid flat\nendsolid flat\n"}]
        )  # fmt: skip
        wait_until(lambda: "import failed" in s.import_panel.status.content, 30, "the verdict")
        wait_until(lambda: any("File uploaded successfully" in t for t in closed_toasts(page)),
                   10, "the upload toast closed")  # fmt: skip
        page.get_by_text("File uploaded successfully.").wait_for(state="hidden", timeout=5_000)
    finally:
        page.close()


def test_cmc_slider_moves_thumb_and_starts_sgas(server: ExplorerServer, browser: Any) -> None:
    server.ctx.debounce_s = 0.2  # this tab computes S_GAS
    try:
        page, s = open_tab(server, browser)
    finally:
        server.ctx.debounce_s = NO_SGAS_S
    try:
        cmc0 = s.design.cmc_deg
        thumb0 = s.hand_view.link_position_mm("thumb_distal")
        wxyz0 = np.asarray(s.hand_view.nodes["thumb_metacarpal"].wxyz).copy()
        table0 = s.score_panel.table.content
        knob = slider(page, "CMC (°)")
        knob.focus()
        for _ in range(2):  # step 5° -> +10°
            knob.press("ArrowRight")
        wait_until(
            lambda: s.timings.last_drawn is not None and s.timings.last_drawn.cmc_deg == cmc0 + 10,
            15,
            "the hand to follow the slider",
        )
        assert s.design_panel.cmc.value == pytest.approx(cmc0 + 10.0)
        thumb1 = s.hand_view.link_position_mm("thumb_distal")
        wxyz1 = np.asarray(s.hand_view.nodes["thumb_metacarpal"].wxyz)
        assert np.linalg.norm(thumb1 - thumb0) > 1.0 or not np.allclose(wxyz0, wxyz1)
        want = f"CMC {cmc0 + 10:g}°"
        wait_until(lambda: want in s.score_panel.table.content, 10, "the S_GAS panel")
        text = s.score_panel.table.content
        assert text != table0
        assert any(w in text for w in ("waiting", "computing", "complete"))
        started = ("computing", "complete")
        wait_until(
            lambda: any(w in s.score_panel.table.content for w in started), 10, "the S_GAS worker"
        )
        # one object: no first sample to wait for, so the scene follows at once
        assert s.timings.scene_redraw and max(s.timings.scene_redraw) < 0.5
    finally:
        page.close()


def test_replay_shows_contacts(server: ExplorerServer, browser: Any) -> None:
    page, s = open_tab(server, browser, "?cmc=15&mcp=60&object=chips_can&gh=17")
    try:
        assert (s.design.cmc_deg, s.design.mcp_deg, s.gh) == (15.0, 60.0, 17)
        # the link's design was applied once (not once more by the sliders' callback)
        assert len(s.timings.scene_redraw) == 1 and s.timings.last_drawn == s.design
        page.get_by_role("tab", name="Grasp").click()
        page.get_by_role("button", name="Play replay").click()
        wait_until(lambda: "replay:" in s.replay_panel.stage.content, 10, "the replay to start")
        assert s.object_view.n_contacts == 0  # hidden while the hand moves
        wait_until(lambda: s.replay_panel.stage.content == "final grasp", 30, "the replay end")
        node = s.object_view.contacts_node
        assert node is not None and s.object_view.n_contacts > 0
        assert np.asarray(node.batched_positions).shape == (s.object_view.n_contacts, 3)
        assert "FC:" in s.replay_panel.result.content
        assert "correct:" in s.replay_panel.result.content
        # the links carrying a contact are translucent (no marker hidden behind a finger)
        hv = s.hand_view
        assert s.last is not None
        touching = {str(k) for k in s.last.grasp.contacts.link}
        assert hv.see_through == touching and touching
        assert all((hv.nodes[n].opacity is not None) == (n in touching) for n in hv.nodes)
        # the floor grid is under the hand in every frame of the replay
        floor_mm = s.floor.position[2] / 1e-3
        lowest = min(hv.points_mm_at(s.hand, f.T_object_palm, f.q)[:, 2].min()
                     for f in s.last.frames)  # fmt: skip
        assert floor_mm < lowest
    finally:
        page.close()


def test_two_tabs_keep_separate_states(server: ExplorerServer, browser: Any) -> None:
    pa, a = open_tab(server, browser, "?cmc=0&mcp=30")
    pb, b = open_tab(server, browser, "?cmc=45&mcp=90&object=chips_can&gh=5")
    try:
        assert (a.design.cmc_deg, a.design.mcp_deg) == (0.0, 30.0)
        assert (b.design.cmc_deg, b.design.mcp_deg, b.gh) == (45.0, 90.0, 5)
        ka, kb = slider(pa, "MCP (°)"), slider(pb, "MCP (°)")
        ka.focus()
        kb.focus()
        for _ in range(2):  # both tabs dragging at once (step 5°)
            ka.press("ArrowRight")
            kb.press("ArrowLeft")
        wait_until(lambda: a.design.mcp_deg == 40.0 and b.design.mcp_deg == 80.0, 15, "both tabs")
        assert a.design.cmc_deg == 0.0 and b.design.cmc_deg == 45.0
        assert a.hand.design != b.hand.design
        pa_thumb = a.hand_view.link_position_mm("thumb_distal")
        pb_thumb = b.hand_view.link_position_mm("thumb_distal")
        assert np.linalg.norm(pa_thumb - pb_thumb) > 1.0
        worker = b.worker
        pb.close()
        wait_until(lambda: b.client.client_id not in server.sessions, 15, "the closed tab to go")
        wait_until(lambda: not worker._thread.is_alive(), 10, "its worker to stop")  # noqa: SLF001
        assert a.client.client_id in server.sessions
    finally:
        pa.close()
        if not pb.is_closed():
            pb.close()


def number_box(page: Any, label: str) -> Any:
    """The typed number box of the slider row labelled ``label``."""
    row = page.locator("div").filter(has=page.get_by_text(label, exact=True))
    return row.filter(has=page.get_by_role("slider")).last.locator("input[type=text]")


def test_typed_design_commits_once_and_rejects_bad_input(
    server: ExplorerServer, browser: Any, caplog: pytest.LogCaptureFixture
) -> None:
    from app.explorer.input_commit import MESSAGE_CLASS

    page, s = open_tab(server, browser, "?cmc=30&mcp=45")
    try:
        applied: list[tuple[float, float]] = []
        on_design = s.design_panel._on_design  # noqa: SLF001

        def spy(c: float, m: float) -> None:
            applied.append((c, m))
            on_design(c, m)

        s.design_panel._on_design = spy  # noqa: SLF001
        box = number_box(page, "MCP (°)")
        msg = page.locator(f".{MESSAGE_CLASS}")
        for bad, why in (("500", "outside 0 to 90"), ("-5", "outside"), ("abc", "not a number")):
            box.click()
            box.press("Control+A")
            box.press_sequentially(bad)  # keystroke by keystroke, as a user types
            box.press("Enter")
            msg.wait_for(timeout=5_000)
            assert why in msg.inner_text()
            assert box.input_value() == "45"  # the last valid value is back
        page.wait_for_timeout(300)
        assert applied == [] and s.design.mcp_deg == 45.0
        box.click()
        box.press("Control+A")
        box.press_sequentially("75")  # "7" must not become a design
        box.press("Tab")  # blur commits too
        wait_until(lambda: s.design.mcp_deg == 75.0, 10, "the typed design")
        assert applied == [(30.0, 75.0)]
        assert msg.count() == 0
        # a value outside the range that reaches the server anyway keeps the design
        s.design_panel.mcp.value = 120.0  # runs the slider's on_update, as a client would
        assert s.design.mcp_deg == 75.0 and s.design_panel.mcp.value == 75.0
        assert "outside the design range" in s.design_panel.message.content
        assert not [r for r in caplog.records if r.exc_info]  # no traceback in the log
    finally:
        page.close()


def test_object_switch_during_replay(server: ExplorerServer, browser: Any) -> None:
    page, s = open_tab(server, browser, "?cmc=0&mcp=45&object=chips_can&gh=400")
    try:
        page.get_by_role("tab", name="Grasp").click()
        assert "GH 401 of 420" in s.replay_panel.count.content
        page.get_by_role("button", name="Play replay").click()
        wait_until(lambda: "replay:" in s.replay_panel.stage.content, 10, "the replay to start")
        # the object picker sits above the tabs: reachable while replaying
        page.get_by_role("combobox", name="Object").click()
        page.get_by_role("option", name="power_drill", exact=True).click()
        wait_until(lambda: s.object_key == "power_drill", 10, "the object switch")
        with s.lock:  # the switch handler holds the lock until every control is updated
            n = len(s.hyps)
        assert n == 720
        page.wait_for_timeout(500)  # a stale replay frame would land here
        assert s.replay_panel.stage.content == "final grasp"
        assert f"of {n} shown (of {n})" in s.replay_panel.count.content
        assert s.replay_panel.result.content.startswith("`power_drill/")
        assert s.gh == 400 and s.replay_panel.current() == 400
        assert int(s.replay_panel.gh.max) == n - 1
        assert "object=power_drill" in s.share_panel.link.content
    finally:
        page.close()


def test_eight_tabs_opened_at_once_apply_their_links(server: ExplorerServer, browser: Any) -> None:
    designs = [(c, m) for c in (0.0, 15.0, 30.0, 45.0) for m in (30.0, 60.0)]
    before = set(server.sessions)
    # small tabs: eight software-rendered canvases at once
    pages = [browser.new_page() for _ in designs]
    for page, (c, m) in zip(pages, designs, strict=True):  # no wait between tabs
        page.set_viewport_size({"width": 480, "height": 320})
        page.goto(f"{server.url}/?cmc={c:g}&mcp={m:g}&gh={int(c + m)}", wait_until="commit")
    new = wait_until(
        lambda: (ids := set(server.sessions) - before) and len(ids) == 8 and ids, 120,
        "8 sessions",
    )  # fmt: skip
    sessions = [server.sessions[i] for i in new]
    wait_until(lambda: all(s.ready.is_set() for s in sessions), 120, "8 links applied")
    got = sorted((s.design.cmc_deg, s.design.mcp_deg, s.gh) for s in sessions)
    assert got == sorted((c, m, int(c + m)) for c, m in designs)
    assert [s.link_error for s in sessions] == [None] * 8
    for page in pages:
        page.close()


def screen_point(camera: Any, p: Any, box: dict[str, float]) -> tuple[float, float]:
    """Page pixel (x, y) of world point ``p`` (m) seen by viser's ``camera`` on the canvas
    ``box`` (a pinhole camera: vertical field of view ``fov``, ``aspect`` width/height)."""
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


def test_click_on_scene_map_selects_design(server: ExplorerServer, browser: Any) -> None:
    page, s = open_tab(server, browser, "?cmc=0&mcp=45")
    try:
        sm = s.map_panel.scene_map
        assert sm is not None and not sm.visible  # hidden in the hand's views
        page.get_by_role("tab", name="Map").click()
        page.get_by_role("button", name="Pick a design on the map (3-D view)").click()
        wait_until(lambda: sm.visible and sm.shown_at > 0, 15, "the in-scene map")
        assert s.view_dd.value == "design map"
        wait_until(lambda: (30.0, 75.0) in [(p.cmc_deg, p.mcp_deg) for p in s.map_panel.points],
                   15, "the map's designs")  # fmt: skip
        wait_drawn(page, s.client, 30)
        page.wait_for_timeout(300)  # the camera's move has reached the page
        base = s.map_panel._scene_base  # noqa: SLF001
        assert base is not None
        target = sm.placement.world_of_pixel(*base.pixel(30.0, 75.0), base.size)
        box = page.locator("canvas").first.bounding_box()
        x, y = screen_point(s.client.camera, target, box)
        assert 0 < x < 1280 * 0.66 and 0 < y < 800  # left of the control panel
        before = s.map_panel.star_time
        page.mouse.click(x + 4, y - 3)  # a few px off the point still picks it
        t0 = time.monotonic()
        wait_until(lambda: s.map_panel.star_at == (30.0, 75.0), 10, "the star on the new design")
        t_star = time.monotonic() - t0
        assert sm.picks == [(30.0, 75.0)]
        assert s.map_panel.star_time > before and t_star < 0.5
        wait_until(lambda: (s.design.cmc_deg, s.design.mcp_deg) == (30.0, 75.0), 10, "design")
        assert (s.design_panel.cmc.value, s.design_panel.mcp.value) == (30.0, 75.0)
        page.get_by_role("tab", name="Design").click()  # the page's sliders moved too
        assert number_box(page, "CMC (°)").input_value() == "30"
        assert number_box(page, "MCP (°)").input_value() == "75"
        # a click off the designs (on the title) selects nothing
        title = sm.placement.world_of_pixel(base.size[0] / 2, 12 * base.scale, base.size)
        page.mouse.click(*screen_point(s.client.camera, title, box))
        page.wait_for_timeout(500)
        assert sm.picks == [(30.0, 75.0)]
    finally:
        page.close()


def test_tab_opened_while_the_engine_loads_and_release_keeps_it(browser: Any) -> None:
    """A tab opened while the server still loads its engine (in the background, once
    listening) works; when it closes, even half-way through drawing its first scene, the
    server drops every hand the tabs built and keeps the warm engine it loaded at start."""
    from app.model.objects import load_object
    from app.sim import closing_compiled
    from app.sim.contacts_compiled import link_tables
    from app.sim.simulate import cached_kit

    srv = ExplorerServer(
        "127.0.0.1", 0, BUILD / "preload.sqlite", objects=OBJECTS, workers=0,
        shots_dir=BUILD / "shots", debounce_s=NO_SGAS_S,
    )  # fmt: skip
    hand_caches = (cached_kit.cache_info, link_tables.cache_info)

    def released() -> bool:
        return not srv.sessions and all(info().currsize == 0 for info in hand_caches)

    try:
        page, s = open_tab(srv, browser, "?cmc=15&mcp=60")  # at once: the preload runs
        assert (s.design.cmc_deg, s.design.mcp_deg) == (15.0, 60.0)
        assert s.link_error is None
        assert srv.engine_ready.wait(120)
        page.close()
        wait_until(released, 90, "the release after the last tab closed")
        # a tab closed while it draws its first scene (its link read, the grasp not yet drawn)
        page = browser.new_page()
        page.goto(srv.url + "/?cmc=30&mcp=75", wait_until="commit")
        s = wait_until(lambda: next(iter(srv.sessions.values()), None), 60, "a session")
        t_end = time.monotonic() + 60
        while s.design.cmc_deg != 30.0 and not s.ready.is_set() and time.monotonic() < t_end:
            time.sleep(0.005)
        page.close()
        wait_until(released, 90, "the release after the second tab closed")
        time.sleep(1.0)  # nothing of the closed tab refills the caches afterwards
        assert released()
        obj = load_object(OBJECTS[0])
        assert closing_compiled._CACHE[id(obj)][0] is obj  # noqa: SLF001 - the warm set
    finally:
        srv.stop()
