"""The design map tab: a contour image of S_GAS over CMC × MCP from the stored results,
the computed designs and the current one marked, a table, and a design picker."""

from __future__ import annotations

import io
import math
import threading
from collections.abc import Callable, Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import viser  # noqa: E402

from app.explorer.map_data import (  # noqa: E402
    TOTAL,
    MapPoint,
    map_points,
    metric_choices,
    metric_value,
)
from app.explorer.reference import SOURCE_LABEL  # noqa: E402
from app.model.design import CMC_RANGE_DEG, MCP_RANGE_DEG  # noqa: E402
from app.quality.settings import SimSettings  # noqa: E402
from app.reports.design_map import interpolate_map  # noqa: E402
from app.runs.store import ResultStore  # noqa: E402

PICK_NONE: str = "(pick a computed design)"


def render_map(
    points: Sequence[MapPoint], metric: str, current: tuple[float, float], size=(560, 620)
) -> np.ndarray:
    """The map as an RGB image (H, W, 3): contour of ``metric``, designs and current marked."""
    w, h = size
    fig, ax = plt.subplots(figsize=(w / 100, h / 100), dpi=100)
    c = np.array([p.cmc_deg for p in points])
    m = np.array([p.mcp_deg for p in points])
    v = np.array([metric_value(p.score, metric) for p in points])
    ok = np.isfinite(v)
    shipped = np.array([p.source == "shipped" for p in points], bool)
    n_ship = int((ok & shipped).sum())
    title = f"{metric} (%) — {int(ok.sum())} computed designs"
    if n_ship:
        title += f"\n({n_ship} of them from the shipped reference, ◇)"
    if ok.sum() >= 3:
        try:
            gc, gm, Z = interpolate_map(c[ok], m[ok], v[ok], step_deg=1.0)
            cs = ax.contourf(gc, gm, Z, levels=12, cmap="viridis")
            fig.colorbar(cs, ax=ax, fraction=0.05, pad=0.02, label="%")
        except ValueError as e:
            title += f"\n(no interpolation: {e})"
    elif len(points):
        title += "\n(3 or more designs needed for contours)"
    if (~shipped).any():
        ax.scatter(c[~shipped], m[~shipped], s=22, c="white", edgecolors="black",
                   linewidths=0.8, label="your store")  # fmt: skip
    if shipped.any():
        ax.scatter(c[shipped], m[shipped], s=26, marker="D", c="lightgrey", edgecolors="dimgray",
                   linewidths=0.8, label="shipped reference")  # fmt: skip
    for ci, mi, vi in zip(c, m, v, strict=True):
        if math.isfinite(vi):
            ax.annotate(f"{vi:.0f}", (ci, mi), textcoords="offset points", xytext=(4, 3),
                        fontsize=7, color="black")  # fmt: skip
    ax.scatter([current[0]], [current[1]], s=160, marker="*", c="red", edgecolors="black",
               label="current", zorder=5)  # fmt: skip
    ax.set_xlim(*CMC_RANGE_DEG)
    ax.set_ylim(*MCP_RANGE_DEG)
    ax.set_xlabel("thumb CMC axis c (°)")
    ax.set_ylabel("thumb MCP axis m (°)")
    ax.set_title(title, fontsize=9)
    ax.legend(loc="upper right", fontsize=7, framealpha=0.8)
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    plt.close(fig)
    buf.seek(0)
    img = plt.imread(buf)
    return (img[..., :3] * 255).astype(np.uint8)


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
    ) -> None:
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
        self.image = gui.add_image(np.full((62, 56, 3), 255, np.uint8), format="png")
        pick_opts: tuple[str, ...] = (PICK_NONE,)
        self.pick = gui.add_dropdown("Go to design", options=pick_opts,
                                     initial_value=PICK_NONE)  # fmt: skip
        self.refresh_btn = gui.add_button("Reload from store", icon=viser.Icon.REFRESH)
        self.table = gui.add_markdown("")
        self.metric.on_update(lambda _: self._kick(reload=False))
        self.pick.on_update(lambda _: self._picked())
        self.refresh_btn.on_click(lambda _: self.refresh())
        self._lock = threading.Lock()
        self._dirty: bool | None = None  # None: clean; False: redraw; True: reload + redraw
        self._busy = False
        self.renders = 0
        self.refresh()

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
        threading.Thread(target=self._drain, name="map-render", daemon=True).start()

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
            self.image.image = render_map(self.points, self.metric.value, self.current)
            self.renders += 1

    def _picked(self) -> None:
        label = self.pick.value
        for p in self.points:
            if label == p.label:
                self.pick.value = PICK_NONE
                self._on_pick(p.cmc_deg, p.mcp_deg)
                return
