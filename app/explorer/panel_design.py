"""The design panel: CMC/MCP sliders (from ``ThumbDesign``'s fields and docstrings),
published designs, baseline, joint axes and the object choice."""

from __future__ import annotations

from collections.abc import Callable

import viser

from app.config_docs import field_docs
from app.model.design import BASELINE, CMC_RANGE_DEG, MCP_RANGE_DEG, ThumbDesign, published_designs

CUSTOM = "(custom)"


def design_label(d: ThumbDesign) -> str:
    """Dropdown label of a published design, e.g. 'CMC 15°, MCP 60°'."""
    return f"CMC {d.cmc_deg:g}°, MCP {d.mcp_deg:g}°"


class DesignPanel:
    """Controls of the thumb design; calls ``on_design(cmc_deg, mcp_deg)`` on any change."""

    def __init__(
        self,
        gui: viser.GuiApi,
        on_design: Callable[[float, float], None],
        on_axes: Callable[[bool], None],
    ) -> None:
        docs = field_docs(ThumbDesign)
        self._on_design = on_design
        self._muted = False
        self.cmc = gui.add_slider(
            "CMC (°)", min=CMC_RANGE_DEG[0], max=CMC_RANGE_DEG[1], step=0.5,
            initial_value=BASELINE.cmc_deg, hint=docs["cmc_deg"],
            marks=tuple((v, f"{v:g}") for v in (0.0, 15.0, 30.0, 45.0)),
        )  # fmt: skip
        self.mcp = gui.add_slider(
            "MCP (°)", min=MCP_RANGE_DEG[0], max=MCP_RANGE_DEG[1], step=0.5,
            initial_value=BASELINE.mcp_deg, hint=docs["mcp_deg"],
            marks=tuple((v, f"{v:g}") for v in (0.0, 45.0, 90.0)),
        )  # fmt: skip
        self._published = {design_label(d): d for d in published_designs()}
        self.published = gui.add_dropdown(
            "Published",
            options=(CUSTOM, *self._published),
            initial_value=design_label(BASELINE),
            hint="Snap to one of the 28 published design alternatives.",
        )
        self.baseline = gui.add_button("Baseline (0°, 45°)", hint="c = 0°, m = 45°")
        self.axes = gui.add_checkbox(
            "Joint axes", initial_value=False, hint="CMC red, MCP green, IP blue"
        )
        self.cmc.on_update(lambda _: self._changed())
        self.mcp.on_update(lambda _: self._changed())
        self.published.on_update(lambda _: self._snap_published())
        self.baseline.on_click(lambda _: self.set_design(BASELINE.cmc_deg, BASELINE.mcp_deg))
        self.axes.on_update(lambda _: on_axes(self.axes.value))

    def set_design(self, cmc_deg: float, mcp_deg: float) -> None:
        """Move both sliders (one design change, not two)."""
        self._muted = True
        try:
            self.cmc.value = float(cmc_deg)
            self.mcp.value = float(mcp_deg)
        finally:
            self._muted = False
        self._changed()

    def _snap_published(self) -> None:
        d = self._published.get(self.published.value)
        if d is not None and (d.cmc_deg, d.mcp_deg) != (self.cmc.value, self.mcp.value):
            self.set_design(d.cmc_deg, d.mcp_deg)

    def _changed(self) -> None:
        if self._muted:
            return
        c, m = float(self.cmc.value), float(self.mcp.value)
        label = design_label(ThumbDesign(c, m))
        want = label if label in self._published else CUSTOM
        if self.published.value != want:
            self.published.value = want
        self._on_design(c, m)
