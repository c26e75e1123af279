"""The design map tab: a contour image of S_GAS over CMC × MCP from the stored results,
the computed designs and the current one marked, a table, and a design picker."""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import viser  # noqa: E402
from matplotlib.path import Path as MplPath  # noqa: E402

from app.explorer.map_data import (  # noqa: E402
    TOTAL,
    MapPoint,
    map_points,
    metric_choices,
    metric_value,
)
from app.explorer.reference import SOURCE_LABEL  # noqa: E402
from app.explorer.scene_map import SCENE_SCALE, SceneMap  # noqa: E402
from app.model.design import CMC_RANGE_DEG, MCP_RANGE_DEG  # noqa: E402
from app.quality.settings import SimSettings  # noqa: E402
from app.reports.design_map import interpolate_map  # noqa: E402
from app.runs.store import ResultStore  # noqa: E402

PICK_NONE: str = "(pick a computed design)"


MAP_SIZE = (400, 440)
"""(width, height) px of the map: the width of the panel, so fonts are shown at their size."""
LABEL_GRID_DEG = 15.0
"""With many designs (the 5° map) only those on the published 15° grid get a value label."""
MAX_LABELS = 40


@dataclass(frozen=True)
class MapImage:
    """A rendered map without the current-design star, and where designs land on it."""

    image: np.ndarray
    """(H, W, 3) uint8."""
    origin_px: tuple[float, float]
    """Pixel (x, y) of CMC 0°, MCP 0°."""
    px_per_deg: tuple[float, float]
    """Pixels per degree along CMC (x, rightward) and MCP (y, upward: negative)."""
    metric: str
    scale: float = 1.0
    """Pixels per layout pixel (``render_base``'s ``scale``)."""

    def pixel(self, cmc_deg: float, mcp_deg: float) -> tuple[float, float]:
        """Pixel (x, y) of a design."""
        return (
            self.origin_px[0] + cmc_deg * self.px_per_deg[0],
            self.origin_px[1] + mcp_deg * self.px_per_deg[1],
        )

    def degrees(self, x: float, y: float) -> tuple[float, float]:
        """(CMC, MCP) degrees at pixel (x, y): the inverse of ``pixel``."""
        return (
            (x - self.origin_px[0]) / self.px_per_deg[0],
            (y - self.origin_px[1]) / self.px_per_deg[1],
        )

    @property
    def size(self) -> tuple[int, int]:
        """(W, H) px."""
        return (int(self.image.shape[1]), int(self.image.shape[0]))


def _labelled(points: Sequence[MapPoint]) -> list[bool]:
    if len(points) <= MAX_LABELS:
        return [True] * len(points)
    return [p.cmc_deg % LABEL_GRID_DEG == 0 and p.mcp_deg % LABEL_GRID_DEG == 0 for p in points]


_RENDERER = ThreadPoolExecutor(max_workers=1, thread_name_prefix="map-renderer")
"""Every map of every tab is drawn on this one thread. Pyplot is not thread-safe, and
matplotlib caches its fonts per thread (``font_manager._get_font`` keys on the thread id; an
entry holds open font files and their FreeType faces, up to 64 entries): maps drawn on each
tab's own thread kept two open font files per render and the server's memory grew with
every tab until that cache was full."""


def render_base(
    points: Sequence[MapPoint], metric: str, size=MAP_SIZE, scale: float = 1.0
) -> MapImage:
    """The map of ``metric``: contours, a horizontal colour bar under the axes (clear of the
    labels), the designs, and value labels placed inside the axes (left of the point at the
    CMC 45° edge, below it at the MCP 90° edge), on a white box. ``scale`` multiplies the
    pixels, not the layout (the in-scene map is drawn at twice the panel's resolution).
    Drawn on the map thread (``_RENDERER``); the caller waits for it."""
    return _RENDERER.submit(_render_base, points, metric, size, scale).result()


def _render_base(
    points: Sequence[MapPoint], metric: str, size: tuple[int, int], scale: float
) -> MapImage:
    w, h = size
    fig = plt.figure(figsize=(w / 100, h / 100), dpi=100 * scale)
    ax = fig.add_axes((0.15, 0.30, 0.80, 0.62))
    cax = fig.add_axes((0.15, 0.12, 0.80, 0.035))
    c = np.array([p.cmc_deg for p in points])
    m = np.array([p.mcp_deg for p in points])
    v = np.array([metric_value(p.score, metric) for p in points])
    ok = np.isfinite(v)
    shipped = np.array([p.source == "shipped" for p in points], bool)
    note = ""
    if ok.sum() >= 3:
        try:
            gc, gm, Z = interpolate_map(c[ok], m[ok], v[ok], step_deg=1.0)
            cs = ax.contourf(gc, gm, Z, levels=12, cmap="viridis")
            cb = fig.colorbar(cs, cax=cax, orientation="horizontal")
            cb.set_label(f"{metric} (%)", fontsize=9)
            cb.ax.tick_params(labelsize=8)
        except ValueError as e:
            note = f" (no contours: {e})"
    else:
        note = " (contours need 3 designs)"
    if not cax.has_data() and not cax.collections:
        cax.set_axis_off()
    if (~shipped).any():
        ax.scatter(c[~shipped], m[~shipped], s=26, c="white", edgecolors="black",
                   linewidths=0.9, zorder=3)  # fmt: skip
    if shipped.any():
        ax.scatter(c[shipped], m[shipped], s=26, marker="D", c="lightgrey", edgecolors="dimgray",
                   linewidths=0.9, zorder=3)  # fmt: skip
    for ci, mi, vi, lab in zip(c, m, v, _labelled(points), strict=True):
        if not (lab and math.isfinite(vi)):
            continue
        right = ci >= CMC_RANGE_DEG[1] - 1e-9
        top = mi >= MCP_RANGE_DEG[1] - 1e-9
        ax.annotate(
            f"{vi:.0f}", (ci, mi), textcoords="offset points",
            xytext=(-7 if right else 7, -6 if top else 5),
            ha="right" if right else "left", va="top" if top else "bottom",
            fontsize=9, color="black", zorder=4, annotation_clip=True,
            bbox={"boxstyle": "round,pad=0.12", "fc": "white", "ec": "none", "alpha": 0.75},
        )  # fmt: skip
    ax.set_xlim(*CMC_RANGE_DEG)
    ax.set_ylim(*MCP_RANGE_DEG)
    ax.set_xticks(np.arange(CMC_RANGE_DEG[0], CMC_RANGE_DEG[1] + 1, 15.0))
    ax.set_yticks(np.arange(MCP_RANGE_DEG[0], MCP_RANGE_DEG[1] + 1, 15.0))
    ax.tick_params(labelsize=9)
    ax.set_xlabel("CMC axis c (°)", fontsize=9, labelpad=1)
    ax.set_ylabel("MCP axis m (°)", fontsize=9)
    ax.set_title(f"{metric} (%), {int(ok.sum())} designs{note}", fontsize=10)
    fig.canvas.draw()
    (x0, y0), (x1, y1) = ax.transData.transform(
        [(CMC_RANGE_DEG[0], MCP_RANGE_DEG[0]), (CMC_RANGE_DEG[1], MCP_RANGE_DEG[1])]
    )
    rgba = np.asarray(fig.canvas.buffer_rgba())  # type: ignore[attr-defined]
    img = rgba[..., :3].copy()
    plt.close(fig)
    H = img.shape[0]  # display y grows upward, pixel rows downward
    span_c = CMC_RANGE_DEG[1] - CMC_RANGE_DEG[0]
    span_m = MCP_RANGE_DEG[1] - MCP_RANGE_DEG[0]
    return MapImage(
        img,
        (
            x0 - CMC_RANGE_DEG[0] * (x1 - x0) / span_c,
            H - y0 + MCP_RANGE_DEG[0] * (y1 - y0) / span_m,
        ),
        ((x1 - x0) / span_c, -(y1 - y0) / span_m),
        metric,
        scale,
    )


def _star_mask(r_out: float, size: int) -> np.ndarray:
    """(size, size) bool: a five-pointed star of outer radius ``r_out`` px, centred."""
    ang = np.pi / 2 + np.arange(10) * np.pi / 5
    rad = np.where(np.arange(10) % 2 == 0, r_out, r_out * 0.45)
    poly = np.stack([rad * np.cos(ang), -rad * np.sin(ang)], axis=1) + size / 2
    yy, xx = np.mgrid[0:size, 0:size]
    return (
        MplPath(poly)
        .contains_points(np.stack([xx.ravel() + 0.5, yy.ravel() + 0.5], 1))
        .reshape(size, size)
    )


_STARS: dict[int, tuple[np.ndarray, np.ndarray]] = {}


def _star(size: int) -> tuple[np.ndarray, np.ndarray]:
    """(edge, fill) masks of a star ``size`` px wide (cached)."""
    if size not in _STARS:
        _STARS[size] = (_star_mask(size * 0.44, size), _star_mask(size * 0.30, size))
    return _STARS[size]


def with_star(base: MapImage, cmc_deg: float, mcp_deg: float) -> np.ndarray:
    """The map with the current design's star (red, black edge): a few ms, no re-render."""
    img = base.image.copy()
    size = int(round(25 * base.scale))
    edge, fill = _star(size)
    x, y = base.pixel(cmc_deg, mcp_deg)
    x0, y0 = int(round(x)) - size // 2, int(round(y)) - size // 2
    H, W = img.shape[:2]
    sx0, sy0 = max(0, -x0), max(0, -y0)
    sx1, sy1 = min(size, W - x0), min(size, H - y0)
    if sx1 <= sx0 or sy1 <= sy0:
        return img
    win = img[y0 + sy0 : y0 + sy1, x0 + sx0 : x0 + sx1]
    win[edge[sy0:sy1, sx0:sx1]] = (0, 0, 0)
    win[fill[sy0:sy1, sx0:sx1]] = (230, 20, 20)
    return img


def render_map(
    points: Sequence[MapPoint], metric: str, current: tuple[float, float], size=MAP_SIZE
) -> np.ndarray:
    """The map as an RGB image (H, W, 3): contour of ``metric``, designs and current marked."""
    return with_star(render_base(points, metric, size), *current)


LEGEND_MD = (
    "○ your store · ◇ shipped reference · <span style='color:rgb(230,20,20)'>★</span> "
    "current design"
)


def table_markdown(points: Sequence[MapPoint]) -> str:
    """Computed designs: CMC, MCP, PP, CG, total, and where the scores come from."""

    def f(x: float | None) -> str:
        return "–" if x is None or math.isnan(x) else f"{x:.1f}"

    rows = ["| CMC | MCP | PP | CG | total | source |", "|---:|---:|---:|---:|---:|---|"]
    for p in points:
        s = p.score
        rows.append(
            f"| {p.cmc_deg:g} | {p.mcp_deg:g} | {f(s.pp_sgas_pct)} | {f(s.cg_sgas_pct)} | "
            f"**{f(s.total_sgas_pct)}** | {'store' if p.source == 'store' else 'shipped'} |"
        )
    if not points:
        rows.append("| – | – | – | – | – | – |")
    if any(p.source == "shipped" for p in points):
        rows += ["", f"*shipped*: {SOURCE_LABEL}; compute a design to replay its grasps."]
    return "\n".join(rows)


class MapPanel:
    """Map image, metric choice, design picker and table. Redraws are coalesced in a thread."""

    def __init__(
        self,
        gui: viser.GuiApi,
        store: ResultStore,
        objects: Sequence[str],
        on_pick: Callable[[float, float], None],
        ref_dir: Path | None = None,
        scene: viser.SceneApi | None = None,
        on_show_scene: Callable[[], None] | None = None,
    ) -> None:
        """``scene``: also draw the map as a clickable image in the 3-D scene
        (``SceneMap``, shown by the 'design map' view; ``on_show_scene`` selects that view)."""
        self.store = store
        self.ref_dir = ref_dir
        self.tilt = "ulnar"
        self.objects = tuple(objects)
        self.settings = SimSettings()
        self.current = (0.0, 45.0)
        self.points: list[MapPoint] = []
        self._on_pick = on_pick
        self.metric = gui.add_dropdown("Map of", options=metric_choices(self.objects),
                                       initial_value=TOTAL)  # fmt: skip
        self.image = gui.add_image(np.full((44, 40, 3), 255, np.uint8), format="png")
        gui.add_markdown(LEGEND_MD)
        self.scene_map = SceneMap(scene, on_pick) if scene is not None else None
        self.scene_btn: viser.GuiButtonHandle | None = None
        if on_show_scene is not None:
            btn = gui.add_button("Pick a design on the map (3-D view)", icon=viser.Icon.POINTER)
            btn.on_click(lambda _: on_show_scene())
            self.scene_btn = btn
        pick_opts: tuple[str, ...] = (PICK_NONE,)
        self.pick = gui.add_dropdown("Go to design", options=pick_opts,
                                     initial_value=PICK_NONE)  # fmt: skip
        self.refresh_btn = gui.add_button("Reload from store", icon=viser.Icon.REFRESH)
        self.table = gui.add_markdown("")
        self.metric.on_update(lambda _: self._new_metric())
        self.pick.on_update(lambda _: self._picked())
        self.refresh_btn.on_click(lambda _: self.refresh())
        self._lock = threading.Lock()
        self._dirty: bool | None = None  # None: clean; False: redraw; True: reload + redraw
        self._busy = False
        self.render_thread: threading.Thread | None = None
        """The latest redraw thread (None before the first)."""
        self._base: MapImage | None = None
        self._scene_base: MapImage | None = None
        self.renders = 0
        """Full renders (contours); moving the star is not one."""
        self.star_at: tuple[float, float] | None = None
        """Where the star was last drawn, and when (``star_time``)."""
        self.star_time = 0.0
        self.refresh()

    def _new_metric(self) -> None:
        self._base = self._scene_base = None
        self._kick(reload=False)

    def set_scene_visible(self, visible: bool) -> None:
        """Show or hide the in-scene map (drawn when first shown, then kept up to date)."""
        if self.scene_map is None or visible == self.scene_map.visible:
            return
        self.scene_map.set_visible(visible)
        if visible:
            self._kick(reload=False)

    def set_current(self, cmc_deg: float, mcp_deg: float) -> None:
        """Move the current-design marker."""
        self.current = (cmc_deg, mcp_deg)
        self._kick(reload=False)

    def set_settings(self, settings: SimSettings) -> None:
        """Show results of other settings (closing mode)."""
        self.settings = settings
        self.refresh()

    def set_tilt(self, tilt: str) -> None:
        """Show the designs of this CMC tilt ('ulnar' or 'radial')."""
        if tilt != self.tilt:
            self.tilt = tilt
            self.refresh()

    def refresh(self) -> None:
        """Re-read the store (a design was completed) and redraw."""
        self._kick(reload=True)

    def _kick(self, reload: bool) -> None:
        with self._lock:
            self._dirty = bool(self._dirty) or reload
            if self._busy:
                return
            self._busy = True
        self.render_thread = threading.Thread(target=self._drain, name="map-render", daemon=True)
        self.render_thread.start()

    def _drain(self) -> None:
        while True:
            with self._lock:
                reload, self._dirty = self._dirty, None
                if reload is None:
                    self._busy = False
                    return
            if reload:
                self.points = map_points(
                    self.store, self.objects, self.settings, self.tilt, self.ref_dir
                )
                self.table.content = table_markdown(self.points)
                opts = (PICK_NONE, *(p.label for p in self.points))
                if tuple(self.pick.options) != opts:
                    self.pick.options = opts
                self._base = self._scene_base = None
            base = self._base
            metric = self.metric.value
            if base is None or base.metric != metric:
                base = self._base = render_base(self.points, metric)
                self.renders += 1
            current = self.current
            self.image.image = with_star(base, *current)
            self.star_at, self.star_time = current, time.monotonic()
            self._draw_scene(current, metric)

    def _draw_scene(self, current: tuple[float, float], metric: str) -> None:
        """The in-scene map with the star, while it is shown (hidden: nothing to send)."""
        sm = self.scene_map
        if sm is None or not sm.visible:
            return
        base = self._scene_base
        if base is None or base.metric != metric:
            base = self._scene_base = render_base(self.points, metric, scale=SCENE_SCALE)
        designs = [(p.cmc_deg, p.mcp_deg) for p in self.points]
        sm.update(with_star(base, *current), base.degrees, designs)

    def _picked(self) -> None:
        label = self.pick.value
        for p in self.points:
            if label == p.label:
                self.pick.value = PICK_NONE
                self._on_pick(p.cmc_deg, p.mcp_deg)
                return
