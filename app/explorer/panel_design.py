"""The design panel: CMC/MCP sliders (from ``ThumbDesign``'s fields and docstrings),
published designs, baseline, joint axes and the object choice."""

from __future__ import annotations

from collections.abc import Callable

import viser

from app.config_docs import field_docs
from app.errors import DesignError
from app.explorer.latency_log import mark
from app.model.design import BASELINE, CMC_RANGE_DEG, MCP_RANGE_DEG, ThumbDesign, published_designs

CUSTOM = "(custom)"
SLIDER_STEP_DEG = 5.0
"""A drag or an arrow key moves by 5° (the 5° map's grid); the number boxes take any
whole degree."""
TYPED_STEP_DEG = 0.5
"""Values reaching the server are rounded to this (a float drag never gives 74.99999)."""


def snap(value: float, step: float = TYPED_STEP_DEG) -> float:
    """``value`` rounded to a multiple of ``step``."""
    return round(float(value) / step) * step


def checked_design(cmc: object, mcp: object, tilt: str = "ulnar") -> ThumbDesign:
    """The design of two slider values, or ``DesignError`` naming the valid range."""
    vals = []
    for name, v in (("CMC", cmc), ("MCP", mcp)):
        try:
            vals.append(snap(float(v)))  # type: ignore[arg-type]
        except (TypeError, ValueError):
            raise DesignError(f"{name} must be a number of degrees, got {v!r}") from None
    return ThumbDesign(vals[0], vals[1], tilt)  # type: ignore[arg-type]


def design_label(d: ThumbDesign) -> str:
    """Dropdown label of a published design, e.g. 'CMC 15°, MCP 60°'."""
    return f"CMC {d.cmc_deg:g}°, MCP {d.mcp_deg:g}°"


class DesignPanel:
    """Controls of the thumb design; calls ``on_design(cmc_deg, mcp_deg)`` on any valid
    change. An invalid value (out of range, not a number) puts the last valid design back
    and says why under the sliders; it never reaches ``on_design``."""

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
            "CMC (°)", min=CMC_RANGE_DEG[0], max=CMC_RANGE_DEG[1], step=SLIDER_STEP_DEG,
            initial_value=BASELINE.cmc_deg,
            marks=tuple((v, f"{v:g}") for v in (0.0, 15.0, 30.0, 45.0)),
        )  # fmt: skip
        self.mcp = gui.add_slider(
            "MCP (°)", min=MCP_RANGE_DEG[0], max=MCP_RANGE_DEG[1], step=SLIDER_STEP_DEG,
            initial_value=BASELINE.mcp_deg,
            marks=tuple((v, f"{v:g}") for v in (0.0, 45.0, 90.0)),
        )  # fmt: skip
        self.message = gui.add_markdown("")
        # captions, never hover hints: those covered the tab bar
        gui.add_markdown(
            f"<small>c: {docs['cmc_deg']}  \nm: {docs['mcp_deg']}  \n"
            "Type a value and press Enter; drags move by 5°.</small>"
        )
        self.valid = (BASELINE.cmc_deg, BASELINE.mcp_deg)
        """The last valid (cmc, mcp): what an invalid entry falls back to."""
        self._published = {design_label(d): d for d in published_designs()}
        self.published = gui.add_dropdown(
            "Published",
            options=(CUSTOM, *self._published),
            initial_value=design_label(BASELINE),
        )
        self.baseline = gui.add_button("Baseline (0°, 45°)")
        self.axes = gui.add_checkbox("Thumb axes", initial_value=True)
        gui.add_markdown(
            "<small>Published: the 28 published design alternatives. Thumb axes: CMC red, "
            "MCP green, IP blue; magenta: the thumb pad's flexion path (faded: the previous "
            "design).</small>"
        )
        self.cmc.on_update(lambda _: self._changed())
        self.mcp.on_update(lambda _: self._changed())
        self.published.on_update(lambda _: self._snap_published())
        self.baseline.on_click(lambda _: self.set_design(BASELINE.cmc_deg, BASELINE.mcp_deg))
        self.axes.on_update(lambda _: on_axes(self.axes.value))

    def set_design(self, cmc_deg: float, mcp_deg: float) -> None:
        """Move both sliders (one design change, not two)."""
        self._set_sliders(cmc_deg, mcp_deg)
        self._changed()

    def show_design(self, cmc_deg: float, mcp_deg: float) -> None:
        """Move both sliders and the published label to a design without calling
        ``on_design`` (the caller applies the design itself, with its CMC tilt)."""
        self._set_sliders(cmc_deg, mcp_deg)
        self._show(cmc_deg, mcp_deg)

    def _set_sliders(self, cmc_deg: float, mcp_deg: float) -> None:
        self._muted = True
        try:
            self.cmc.value = float(cmc_deg)
            self.mcp.value = float(mcp_deg)
        finally:
            self._muted = False

    def _snap_published(self) -> None:
        d = self._published.get(self.published.value)
        if d is not None and (d.cmc_deg, d.mcp_deg) != (self.cmc.value, self.mcp.value):
            self.set_design(d.cmc_deg, d.mcp_deg)

    def _changed(self) -> None:
        if self._muted:
            return
        mark("slider", f"{self.cmc.value} {self.mcp.value}")
        try:
            d = checked_design(self.cmc.value, self.mcp.value)
        except DesignError as e:
            kept = f"kept CMC {self.valid[0]:g}°, MCP {self.valid[1]:g}°"
            self.message.content = f"<span style='color:#c92a2a'>{e}; {kept}.</span>"
            self._set_sliders(*self.valid)
            return
        c, m = d.cmc_deg, d.mcp_deg
        if (c, m) != (self.cmc.value, self.mcp.value):
            self._set_sliders(c, m)
        self._show(c, m)
        self._on_design(c, m)

    def _show(self, cmc_deg: float, mcp_deg: float) -> None:
        """A valid design is shown: no message, the fallback, the published label."""
        self.message.content = ""
        self.valid = (cmc_deg, mcp_deg)
        label = design_label(ThumbDesign(cmc_deg, mcp_deg))
        want = label if label in self._published else CUSTOM
        if self.published.value != want:
            self.published.value = want
