"""One browser tab: its design state, its scene and panels, its workers.

Every tab has its own ``Session`` (built in ``server.on_client_connect``) and draws only
through ``client.scene`` and ``client.gui``, so two tabs never share state. Handlers take
the session lock; a burst of slider events is coalesced to the newest value.
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

import viser

from app.errors import HandbenchError
from app.explorer import url_state
from app.explorer.input_commit import commit_script_html
from app.explorer.latency_log import mark
from app.explorer.live_score import DEBOUNCE_S, FirstEstimate, ScoreWorker, read_snapshot
from app.explorer.map_data import TOTAL, map_points
from app.explorer.page_toasts import toast_script_html
from app.explorer.panel_design import DesignPanel
from app.explorer.panel_import import ImportPanel
from app.explorer.panel_map import MapPanel, render_base, with_star
from app.explorer.panel_replay import ReplayPanel, outcome_markdown
from app.explorer.panel_score import ScorePanel
from app.explorer.panel_share import SharePanel, request_share_url
from app.explorer.scene_hand import HandView
from app.explorer.scene_object import ObjectView
from app.explorer.units import MM
from app.explorer.views import DEFAULT_VIEW, MAP, VIEWS, camera_pose, map_camera_pose
from app.model.design import BASELINE, ThumbDesign
from app.model.hand.model import Hand, build_hand
from app.model.objects import available_keys, load_object
from app.quality.judge import judge
from app.quality.outcome import GraspOutcome
from app.quality.settings import SimSettings
from app.runs.executors import Executor
from app.runs.keys import design_key, object_key
from app.runs.store import ResultStore
from app.sim.closing_settings import ClosingSettings
from app.sim.hypotheses import Hypotheses
from app.sim.hypothesis_sets import cached_hypotheses
from app.sim.replay import Replay, replay
from app.sim.simulate import Grasp, HandKit, base_kit

REPLAY_HZ = 30.0
LINK_TIMEOUT_S = 60.0
"""How long a new tab may take to report its link (retried requests, busy browsers)."""
FLOOR_GAP_MM = 12.0
"""The floor grid sits this far under the lowest point of the object and the hand."""
SCENE_AFTER_ESTIMATE_S = 0.5
"""On a page without a GPU, a design change's scene batch waits at most this long (s, from
the request) for the S_GAS panel's first estimate, when that estimate is computed at once
(not after a drag's debounce, nor for a stored design) ..."""
PAGE_PAINT_S = 0.5
"""... and then this long more (s): the page finishes the frame it may be drawing (viser
redraws once a second even when idle; without a GPU such a frame takes up to ~0.45 s of a
2-core machine whose workers are busy) and paints the estimate before the scene batch
arrives, which would hold the estimate back by one more such frame."""
GHOST_HOLD_S = 4.0
"""The previous design's thumb stays as a ghost this long after the last design change."""


@dataclass
class ExplorerContext:
    """What every session shares (read-only, or thread-safe)."""

    store: ResultStore
    """Results store (thread-safe)."""
    objects: tuple[str, ...]
    """Objects of the S_GAS panel and the design map."""
    executor: Executor
    """Runs the S_GAS tasks (shared by the tabs; each tab cancels its own)."""
    shots_dir: Path
    """Where 'Save PNG' writes."""
    url_base: str
    """'http://127.0.0.1:8080' for the state links."""
    server: viser.ViserServer
    """The viser server (share URL)."""
    default_object: str = "chips_can"
    debounce_s: float = DEBOUNCE_S
    reference_dir: Path | None = None
    """Shipped reference sweep (table.csv + meta.json); None: docs/results."""


@dataclass
class Timings:
    """Measured latencies of this tab (seconds)."""

    scene_redraw: list[float] = field(default_factory=list)
    """Design change: handler start until the new hand and its re-simulated grasp were sent
    (after the S_GAS panel's first estimate, when that is computed at once)."""
    last_drawn: ThumbDesign | None = None
    """The design whose hand and grasp were sent last."""


def warm_up(ctx: ExplorerContext) -> None:
    """Compute, without a tab, what a new tab computes for its first scene: the default
    design's grasp of the first GH of the default object (simulated and judged), the design's
    stored S_GAS and the design map. What that loads on first use stays loaded for every tab
    (the quality checks' code, the shipped reference table, the map's drawing code and fonts);
    the server calls this at start so that its first tab does not wait for it."""
    settings = SimSettings()
    obj, hyps = load_object(ctx.default_object), cached_hypotheses(ctx.default_object)
    kit = HandKit(build_hand(BASELINE.cmc_deg, BASELINE.mcp_deg, cmc_tilt=BASELINE.cmc_tilt))
    rep = replay(kit, obj, hyps, 0, settings, base_kit=base_kit(BASELINE))
    judge(rep.grasp, obj, settings, rep.base.queries + rep.grasp.queries)
    read_snapshot(ctx.store, BASELINE, ctx.objects, settings, ctx.reference_dir)
    points = map_points(ctx.store, ctx.objects, settings, BASELINE.cmc_tilt, ctx.reference_dir)
    with_star(render_base(points, TOTAL), BASELINE.cmc_deg, BASELINE.mcp_deg)


class Session:
    """The state and handlers of one tab."""

    def __init__(self, client: viser.ClientHandle, ctx: ExplorerContext) -> None:
        self.client = client
        self.ctx = ctx
        self.lock = threading.RLock()
        self.ready = threading.Event()
        """Set once the link state is applied and the first scene is sent."""
        self.timings = Timings()
        self.design = BASELINE
        self.mode = "sequential"
        self.object_key = ctx.default_object
        self.hand: Hand = build_hand(self.design.cmc_deg, self.design.mcp_deg)
        self.kit = HandKit(self.hand)
        self.obj = load_object(self.object_key)
        self.hyps: Hypotheses = cached_hypotheses(self.object_key)
        self.gh = 0
        self.last: Replay | None = None
        self.outcome: GraspOutcome | None = None
        self._closed = False
        self._player: threading.Thread | None = None
        self._last_player: threading.Thread | None = None
        self._player_cancel = threading.Event()
        self._req_lock = threading.Lock()
        self._req: ThumbDesign | None = None
        self._busy = False
        self._ghost_timer: threading.Timer | None = None
        self.link_error: str | None = None
        """Why this tab's link was not applied (None: applied, or no link)."""
        self.webgl_renderer: str | None = None
        """The page's WebGL renderer, as its probe reported it (None: not reported)."""

        self._setup_scene()
        self._setup_gui()
        self.worker = ScoreWorker(
            ctx.store, ctx.objects, self.score_panel.show, self._object_scored,
            executor=ctx.executor, debounce_s=ctx.debounce_s, ref_dir=ctx.reference_dir,
        )  # fmt: skip
        self._probe_key = url_state.new_probe_key()
        self._probe = self.client.gui.add_html(url_state.probe_html(self._probe_key))
        self._start_thread = threading.Thread(target=self._start, name="session-start", daemon=True)
        self._start_thread.start()

    # ------------------------------------------------------------------ set-up
    @property
    def settings(self) -> SimSettings:
        """Simulation settings of this tab (the closing mode is the tab's choice)."""
        return SimSettings(closing=ClosingSettings(mode=self.mode))  # type: ignore[arg-type]

    def _setup_scene(self) -> None:
        scene = self.client.scene
        scene.configure_environment_map(hdri=None)
        scene.set_up_direction("+z")
        scene.add_light_ambient("/lights/ambient", intensity=0.9)
        scene.add_light_directional("/lights/key", intensity=2.2, wxyz=(0.88, 0.28, 0.36, 0.0))
        scene.add_light_directional("/lights/fill", intensity=0.8, wxyz=(0.5, -0.5, 0.5, 0.5))
        # no shadow term: no light casts one, and without it the floor's shader costs a
        # software-WebGL frame (no GPU) ~40 ms less of 0.15-0.2 s
        self.floor = scene.add_grid(
            "/floor", width=0.5, height=0.5, cell_size=0.02, section_size=0.1, shadow_opacity=0.0
        )
        self.hand_view = HandView(scene, self.hand)
        self.ghost = HandView(scene, self.hand, "/ghost", prefix="thumb", ghost=True)
        self.object_view = ObjectView(scene)

    def _setup_gui(self) -> None:
        gui = self.client.gui
        gui.configure_theme(control_width="large")
        gui.add_markdown("**handbench** design explorer")
        gui.add_html(commit_script_html())
        gui.add_html(toast_script_html())
        # object and view above the tabs: reachable from the design and the grasp replays
        keys = available_keys()
        self.object_dd = gui.add_dropdown("Object", options=keys, initial_value=self.object_key)
        self.object_dd.on_update(lambda _: self.on_object(self.object_dd.value))
        self.view_dd = gui.add_dropdown("View", options=VIEWS, initial_value=DEFAULT_VIEW)
        self.view_dd.on_update(lambda _: self.frame_camera())
        tabs = gui.add_tab_group()
        with tabs.add_tab("Design", viser.Icon.HAND_FINGER):
            self.design_panel = DesignPanel(gui, self.on_design, self.hand_view.set_axes_visible)
            self.hand_view.set_axes_visible(self.design_panel.axes.value)
            with gui.add_folder("Live S_GAS"):
                self.score_panel = ScorePanel(gui)
            with gui.add_folder("Import a mesh", expand_by_default=False):
                self.import_panel = ImportPanel(gui, self._imported)
        with tabs.add_tab("Grasp", viser.Icon.PLAYER_PLAY):
            self.replay_panel = ReplayPanel(
                gui, self.on_gh, self.on_play, self.on_mode, self._load_outcomes
            )
        with tabs.add_tab("Map", viser.Icon.MAP):
            self.map_panel = MapPanel(
                gui, self.ctx.store, self.ctx.objects, self._map_select, self.ctx.reference_dir,
                scene=self.client.scene, on_show_scene=self._show_scene_map,
            )  # fmt: skip
        with tabs.add_tab("Share", viser.Icon.SHARE):
            self.share_panel = SharePanel(
                gui,
                state_link=lambda: self.ctx.url_base + "/" + self.state_query(),
                render=lambda h, w: self.client.get_render(
                    h, w, transport_format="png", timeout=30.0
                ),
                shot_name=self._shot_name,
                shots_dir=self.ctx.shots_dir,
                download=self.client.send_file_download,
                share_url=lambda: request_share_url(self.ctx.server),
                port=self.ctx.server.get_port,
            )

    def _start(self) -> None:
        """Read the link state of this tab, draw the first scene, start the S_GAS worker."""
        state = url_state.UrlState()
        try:
            search = self._read_probe(timeout_s=LINK_TIMEOUT_S)
            try:  # the probe writes it just before the link: there by now
                self.webgl_renderer = self._read_probe(url_state.RENDERER_SUFFIX, timeout_s=2.0)
            except (TimeoutError, RuntimeError):
                self.webgl_renderer = None
            if search:
                state = url_state.parse_query(search)
        except (TimeoutError, RuntimeError, HandbenchError) as e:
            self.link_error = str(e)
            self.notify("Link not applied", str(e))
        self._probe.remove()
        if self._closed:
            return
        try:
            self.apply_state(state)
        except HandbenchError as e:
            self.link_error = str(e)
            self.notify("Link not applied", str(e))
            self.apply_state(url_state.UrlState())
        self.ready.set()

    @property
    def software_webgl(self) -> bool:
        """The page renders WebGL without a GPU (see ``_apply_design``)."""
        r = self.webgl_renderer
        return r is not None and url_state.is_software_renderer(r)

    def _read_probe(self, suffix: str = "", timeout_s: float = LINK_TIMEOUT_S) -> str | None:
        """Poll this tab's localStorage for what the probe writes: the link query (``suffix``
        '') or the WebGL renderer (``url_state.RENDERER_SUFFIX``).

        Many tabs opening at once keep the browser busy (software WebGL) for many seconds:
        one request timing out is retried until ``timeout_s`` has passed in all."""
        t_end = time.monotonic() + timeout_s
        while time.monotonic() < t_end and not self._closed:
            left = max(t_end - time.monotonic(), 0.1)
            try:
                v = self.client.local_storage.get_item(
                    self._probe_key + suffix, timeout=min(left, 10.0)
                )
            except TimeoutError:
                continue
            if v is not None:
                self.client.local_storage.remove_item(self._probe_key + suffix)
                return v
            time.sleep(0.05)
        what = "its link" if not suffix else "its WebGL renderer"
        raise TimeoutError(f"the page did not report {what} within {timeout_s:g} s")

    def apply_state(self, s: url_state.UrlState) -> None:
        """Object, design and GH of a link (unset parts keep their values)."""
        with self.lock:
            key = s.object_key or self.object_key
            if key not in available_keys():
                load_object(key)  # raises UnknownObjectError naming the valid keys
            self._set_object(key, redraw=False)
            if s.gh is not None:
                gh: str | int = int(s.gh) if s.gh.isdigit() else s.gh
                self.gh = self.hyps.index_of(gh)
            self.replay_panel.select_index(self.gh)
            c = self.design.cmc_deg if s.cmc_deg is None else s.cmc_deg
            m = self.design.mcp_deg if s.mcp_deg is None else s.mcp_deg
            tilt = self.design.cmc_tilt if s.tilt is None else s.tilt
            design = ThumbDesign(c, m, tilt)  # type: ignore[arg-type]  # checked by parse_query
            # the sliders follow without their callback: the design is applied once, here,
            # with the link's tilt (the callback would apply it a second time, computing its
            # first sample twice)
            self.design_panel.show_design(design.cmc_deg, design.mcp_deg)
            self._apply_design(design)
            self.frame_camera()

    def notify(self, title: str, body: str) -> None:
        """A toast in this tab."""
        try:
            self.client.add_notification(title, body, auto_close_seconds=8.0)
        except Exception:  # noqa: BLE001 - a closed tab cannot be notified
            pass

    # ------------------------------------------------------------------ handlers
    def on_design(self, cmc_deg: float, mcp_deg: float) -> None:
        """Slider handler: coalesce a burst, apply the newest design."""
        with self._req_lock:
            self._req = ThumbDesign(cmc_deg, mcp_deg, self.design.cmc_tilt)
            if self._busy:
                return
            self._busy = True
        while True:
            # the request is taken once the lock is held: while another handler holds it (the
            # link's design, or the previous design waiting for its estimate), this one shows
            # as waiting (``_newer_design_waiting``) and newer values still replace it
            with self.lock:
                with self._req_lock:
                    req, self._req = self._req, None
                    if req is None or self._closed:
                        self._busy = False
                        return
                self._apply_design(req)

    def _apply_design(self, design: ThumbDesign) -> None:
        """The score panel first (its header at once; its worker starts the first sample),
        then the new hand and its grasp in one scene batch; on a page without a GPU, after the
        first estimate (``SCENE_AFTER_ESTIMATE_S``, ``PAGE_PAINT_S``).

        One batch, not three (the ghost, the re-posed hand, then the grasp): viser's page
        applies scene messages at its next frame, and GUI messages at once only when no scene
        message waits, so every scene batch can hold the panel back by a frame. With a GPU a
        frame takes milliseconds. Without one (software WebGL: SwiftShader, llvmpipe) a frame
        of this scene takes 0.15–0.45 s of a 2-core machine, which the sample's workers need
        too, so the scene waits for the estimate there."""
        if self._closed:  # a closed tab computes nothing more (its link may arrive late)
            return
        mark("apply", f"{design.cmc_deg} {design.mcp_deg}")
        t0 = time.perf_counter()
        self._stop_player()
        ghost = design != self.design
        self.design = design
        # the score first: its worker cancels the old design's work and starts this one's
        # while the hand and the grasp are computed
        first_estimate = self.worker.request(design, self.settings)
        t_request = time.monotonic()
        self.map_panel.set_tilt(design.cmc_tilt)
        self.map_panel.set_current(design.cmc_deg, design.mcp_deg)  # the star first: ~1 ms
        self.hand = build_hand(design.cmc_deg, design.mcp_deg, cmc_tilt=design.cmc_tilt)
        self.kit = HandKit(self.hand)
        rep, out = self._simulate_selected()
        if self.software_webgl:
            self._wait_for_estimate(first_estimate, t_request)
            if self._newer_design_waiting():
                return  # it draws next; this scene would only hold its panel back by a frame
        with self.client.atomic():
            if ghost:
                self._show_ghost()  # the hand drawn now, before _draw_final moves it
            self._draw_final(rep, out)
        self.client.flush()
        t1 = time.perf_counter()
        mark("scene_sent")
        self.timings.scene_redraw.append(t1 - t0)
        self.timings.last_drawn = design
        self._refresh_outcomes()
        self.share_panel.update_link()

    def _wait_for_estimate(self, first: FirstEstimate, t_request: float) -> None:
        """On a page without a GPU: wait for the first estimate (until ``t_request`` +
        ``SCENE_AFTER_ESTIMATE_S``), then ``PAGE_PAINT_S`` for the page to paint it, unless a
        newer design is waiting. A scene batch sent first would hold the estimate back by a
        frame, and the frame's rendering slows the sample's workers."""
        deadline = t_request + SCENE_AFTER_ESTIMATE_S
        while not first.done and not self._newer_design_waiting():
            left = deadline - time.monotonic()
            if left <= 0:
                return
            first.wait(min(0.05, left))
        if first.shown:
            t_end = time.monotonic() + PAGE_PAINT_S
            while time.monotonic() < t_end and not self._newer_design_waiting():
                time.sleep(0.02)

    def _newer_design_waiting(self) -> bool:
        """A slider has sent a design that ``on_design`` will apply next."""
        with self._req_lock:
            return self._req is not None

    def on_object(self, key: str) -> None:
        """Object dropdown."""
        with self.lock:
            if key == self.object_key:
                return
            self._set_object(key, redraw=True)
            self.frame_camera()

    def _set_object(self, key: str, redraw: bool) -> None:
        """Every control that depends on the object first (GH range, filters, outcomes),
        then the scene, in one batch: no frame shows the old object's grasp on the new one."""
        self._stop_player()
        self._hide_ghost()
        obj, hyps = load_object(key), cached_hypotheses(key)
        with self.client.atomic():
            self.object_key, self.obj, self.hyps = key, obj, hyps
            self.gh = min(self.gh, len(hyps) - 1)
            if self.object_dd.value != key:
                self.object_dd.value = key
            self.replay_panel.set_hypotheses(hyps)
            self.replay_panel.select_index(self.gh)
            self._refresh_outcomes()
            self.object_view.set_object(obj.mesh.vertices, obj.mesh.faces)
            self._show_contacts(None)
            if redraw:
                self._show_final()
                self.share_panel.update_link()

    def on_gh(self, i: int) -> None:
        """GH slider / filters."""
        with self.lock:
            self._stop_player()
            self.gh = i
            self._show_final()
            self.share_panel.update_link()

    def on_mode(self, mode: str) -> None:
        """Closing mode: changes the simulation settings (and so the stored results used)."""
        with self.lock:
            self._stop_player()
            self.mode = mode
            self._show_final()
            self.worker.request(self.design, self.settings)
            self._refresh_outcomes()
            self.map_panel.set_settings(self.settings)

    def _imported(self, key: str) -> None:
        self.object_dd.options = available_keys()
        self.on_object(key)

    def _map_select(self, cmc_deg: float, mcp_deg: float) -> None:
        """'Go to design' and clicks on the in-scene map: one path."""
        self.design_panel.set_design(cmc_deg, mcp_deg)

    def _show_scene_map(self) -> None:
        if self.view_dd.value != MAP:
            self.view_dd.value = MAP  # its on_update frames the camera
        else:
            self.frame_camera()

    # ------------------------------------------------------------------ grasp
    def _show_final(self) -> None:
        """Simulate the selected GH at the current design and draw its final grasp."""
        if self._closed:
            return
        rep, out = self._simulate_selected()
        with self.client.atomic():
            self._draw_final(rep, out)
        self.client.flush()

    def _simulate_selected(self) -> tuple[Replay, GraspOutcome]:
        """The selected GH simulated at the current design, and its judged outcome."""
        s = self.settings
        rep = replay(self.kit, self.obj, self.hyps, self.gh, s, base_kit=base_kit(self.design))
        out = judge(rep.grasp, self.obj, s, rep.base.queries + rep.grasp.queries)
        return rep, out

    def _draw_final(self, rep: Replay, out: GraspOutcome) -> None:
        """The final grasp of ``rep`` in the scene and the replay panel (inside the caller's
        ``client.atomic()``)."""
        self.last, self.outcome = rep, out
        i, g = self.gh, rep.grasp
        self.hand_view.set_pose(self.hand, g.T_object_palm, g.q)
        self.object_view.set_cone(self.hyps, i)
        self.object_view.set_palm_point(
            g.T_object_palm, self.hand.approach_point_palm, self.obj.spec.setup.hand_vector_palm
        )
        self._show_contacts(g)
        self._place_floor(rep)
        self.replay_panel.stage.content = "final grasp"
        self.replay_panel.result.content = outcome_markdown(out, self.hyps.ids[i], len(g.contacts))

    def _show_contacts(self, grasp: Grasp | None) -> None:
        """The grasp's contacts (or none); the object and the links that carry a contact turn
        translucent while they are shown, so every marker is in sight from every view."""
        contacts = None if grasp is None else grasp.contacts
        self.object_view.set_contacts(contacts)
        links = set() if contacts is None else {str(k) for k in contacts.link}
        self.hand_view.set_see_through(links)

    def on_play(self) -> None:
        """Play the replay of the selected GH (approach, back-off, closing stages)."""
        with self.lock:
            self._stop_player()
            rep = self.last
            if rep is None:
                return
            cancel = threading.Event()
            self._player_cancel = cancel
            self._player = threading.Thread(
                target=self._play, args=(rep, self.hand, cancel), name="replay", daemon=True
            )
            self._player.start()
            self._last_player = self._player

    def _play(self, rep: Replay, hand: Hand, cancel: threading.Event) -> None:
        """Draw the frames at REPLAY_HZ. Each frame is drawn under the session lock after a
        cancel check, and every handler cancels under that lock: once a handler (a new
        object, design or GH) has run, no frame of the old replay reaches the scene."""
        with self.lock:
            if cancel.is_set():
                return
            self._show_contacts(None)
        hand_vector = self.obj.spec.setup.hand_vector_palm
        period = 1.0 / REPLAY_HZ
        t_next = time.perf_counter()
        for f in rep.frames:
            with self.lock:
                if cancel.is_set() or self._closed:
                    return
                with self.client.atomic():
                    self.hand_view.set_pose(hand, f.T_object_palm, f.q)
                    self.object_view.set_palm_point(
                        f.T_object_palm, hand.approach_point_palm, hand_vector
                    )
                    self.replay_panel.stage.content = f"replay: {f.label}"
            self.client.flush()
            t_next += period
            time.sleep(max(0.0, t_next - time.perf_counter()))
        with self.lock:
            if not cancel.is_set() and not self._closed:
                self._show_contacts(rep.grasp)
                self.replay_panel.stage.content = "final grasp"

    def _stop_player(self) -> None:
        """Cancel the replay (callers hold ``self.lock``, so it draws no further frame)."""
        self._player_cancel.set()
        self._player = None

    # ------------------------------------------------------------------ ghost
    def _show_ghost(self) -> None:
        """Keep the thumb drawn now (``hand_view``'s hand and pose: the last design whose scene
        was sent, not one skipped for a newer) as a translucent ghost while the design
        changes (inside the caller's ``client.atomic()``)."""
        if not self.ghost.visible:
            hv = self.hand_view
            self.ghost.set_pose(hv.hand, hv.T_object_palm, hv.q)
            self.ghost.set_visible(True)
        if self._ghost_timer is not None:
            self._ghost_timer.cancel()
        self._ghost_timer = threading.Timer(GHOST_HOLD_S, self._hide_ghost)
        self._ghost_timer.daemon = True
        self._ghost_timer.start()

    def _hide_ghost(self) -> None:
        if self._ghost_timer is not None:
            self._ghost_timer.cancel()
            self._ghost_timer = None
        if self.ghost.visible and not self._closed:
            self.ghost.set_visible(False)

    def _place_floor(self, rep: Replay) -> None:
        """The floor grid just under the lowest point of the object and of the hand in every
        frame of the replay (its approach may dip below the final grasp): no finger passes
        through it while the replay plays."""
        hv = self.hand_view
        z = min(float(self.obj.mesh.bounds[0, 2]), float(hv.points_mm()[:, 2].min()))
        for f in rep.frames[:: max(1, len(rep.frames) // 60)] + rep.frames[-1:]:
            z = min(z, float(hv.points_mm_at(self.hand, f.T_object_palm, f.q)[:, 2].min()))
        self.floor.position = (0.0, 0.0, (z - FLOOR_GAP_MM) * MM)

    # ------------------------------------------------------------------ scores
    def _object_scored(self, key: str) -> None:
        if key == self.object_key:
            self._refresh_outcomes()
        # the map shows complete designs only: redrawn once the design's last object is in
        # (each redraw costs the server a render and the page an image, beside the workers)
        snap = read_snapshot(self.ctx.store, self.design, self.ctx.objects, self.settings)
        if all(snap.complete(k) for k in self.ctx.objects):
            self.map_panel.refresh()

    def _keys(self) -> tuple[str, str, str]:
        return design_key(self.design), object_key(self.object_key), self.settings.key()

    def _refresh_outcomes(self) -> None:
        """Which GHs of this design and object have stored outcomes (for the filter)."""
        self.replay_panel.set_known(self.ctx.store.present_ids(*self._keys()))

    def _load_outcomes(self) -> dict[str, GraspOutcome]:
        return self.ctx.store.get_many(*self._keys(), list(self.hyps.ids))

    # ------------------------------------------------------------------ view
    def frame_camera(self) -> None:
        """Point the camera as the View dropdown says (views.py: from the palmar-radial
        side, so the thumb and its opposition are in sight)."""
        view = self.view_dd.value
        self.map_panel.set_scene_visible(view == MAP)
        cam = self.client.camera
        if view == MAP:
            sm = self.map_panel.scene_map
            assert sm is not None
            pose = map_camera_pose(sm.placement, float(cam.fov), float(cam.aspect))
            scale = 1.0  # the map's pose is in metres already
        else:
            hv = self.hand_view
            pose = camera_pose(
                view, hv.T_object_palm, hv.points_mm("thumb"), hv.points_mm(),
                self.obj.mesh.bounds,
            )  # fmt: skip
            scale = MM
        cam.up_direction = tuple(pose.up)
        cam.position = tuple(pose.position * scale)
        cam.look_at = tuple(pose.look_at * scale)  # after position: position moves look_at

    def state_query(self) -> str:
        """The link query of the current state."""
        tilt = None if self.design.cmc_tilt == "ulnar" else self.design.cmc_tilt
        return url_state.UrlState(
            self.design.cmc_deg, self.design.mcp_deg, self.object_key, str(self.gh), tilt=tilt
        ).query()

    def _shot_name(self) -> str:
        """File name of a saved view: design, object, GH and time."""
        d = self.design
        stamp = time.strftime("%Y%m%d-%H%M%S")
        return f"handbench_c{d.cmc_deg:g}_m{d.mcp_deg:g}_{self.object_key}_gh{self.gh}_{stamp}.png"

    # ------------------------------------------------------------------ teardown
    def close(self) -> None:
        """The tab closed: cancel and free its work."""
        self._closed = True
        self._player_cancel.set()
        if self._ghost_timer is not None:
            self._ghost_timer.cancel()
        self.worker.close()

    def join(self, timeout: float) -> bool:
        """After ``close``: wait until this tab's threads have ended (the link reader and the
        first scene, the S_GAS worker, the replay, the map render), at most ``timeout``
        seconds; whether they all did. A thread still computing when the tab closed would
        otherwise refill the shared caches after the server emptied them."""
        t_end = time.monotonic() + timeout
        threads = [self._start_thread, self._last_player, self.map_panel.render_thread]
        for t in threads:
            if t is not None and t is not threading.current_thread():
                t.join(max(0.0, t_end - time.monotonic()))
        done = self.worker.join(max(0.0, t_end - time.monotonic()))
        return done and not any(t is not None and t.is_alive() for t in threads)
