"""The design map as a clickable image in the 3-D scene (the 'design map' view).

viser reports no clicks on GUI images, but a scene image node has ``on_click`` with the
click's ray: the ray meets the image plane at a pixel, the pixel is a (CMC, MCP) point of the
map, and the nearest computed design is selected (``map_pick``)."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Sequence

import numpy as np
import viser
from numpy.typing import ArrayLike

from app.explorer.map_pick import MAP_WXYZ, MapPlacement, nearest_design
from app.model.design import CMC_RANGE_DEG, MCP_RANGE_DEG

SCENE_SCALE = 2.0
"""The in-scene map has twice the panel map's pixels (same layout): it is shown larger."""
PLACEMENT = MapPlacement(centre=(0.0, 2.0, 0.3), width=0.40, height=0.44)
"""Two metres from the object, clear of the hand and the floor; seen only in its view."""
PICK_RADIUS_DEG = 10.0
"""A click picks the nearest design within this many degrees ..."""
PICK_MARGIN_DEG = 3.0
"""... inside the axes (this much beyond the design ranges): none on the title or bar."""


class SceneMap:
    """One image node; a click on it calls ``on_pick(cmc_deg, mcp_deg)``. While hidden it
    keeps the newest picture and sends it when shown (no PNG per slider step)."""

    def __init__(
        self,
        scene: viser.SceneApi,
        on_pick: Callable[[float, float], None],
        placement: MapPlacement = PLACEMENT,
    ) -> None:
        self.placement = placement
        self._on_pick = on_pick
        self._lock = threading.Lock()
        self._pending: np.ndarray | None = None
        self._size = (40, 44)
        self._to_degrees: Callable[[float, float], tuple[float, float]] | None = None
        self._designs: list[tuple[float, float]] = []
        self.picks: list[tuple[float, float]] = []
        """Designs picked by a click, in order."""
        self.shown_at = 0.0
        """When a picture was last sent (monotonic s)."""
        self.node = scene.add_image(
            "/design_map", np.full((44, 40, 3), 255, np.uint8), placement.width,
            placement.height, format="png", cast_shadow=False, receive_shadow=False,
            wxyz=MAP_WXYZ, position=placement.centre, visible=False,
        )  # fmt: skip
        self.node.on_click(self._clicked)

    @property
    def visible(self) -> bool:
        return bool(self.node.visible)

    def set_visible(self, visible: bool) -> None:
        """Show (sending the newest picture first) or hide the map."""
        if visible:
            self._flush()
        self.node.visible = visible

    def update(
        self,
        image: np.ndarray,
        to_degrees: Callable[[float, float], tuple[float, float]],
        designs: Sequence[tuple[float, float]],
    ) -> None:
        """A new picture (``image``), its pixel-to-degrees map and the designs on it."""
        with self._lock:
            self._pending = image
            self._size = (int(image.shape[1]), int(image.shape[0]))
            self._to_degrees = to_degrees
            self._designs = list(designs)
        if self.visible:
            self._flush()

    def _flush(self) -> None:
        with self._lock:
            img, self._pending = self._pending, None
        if img is not None:
            self.node.image = img
            self.shown_at = time.monotonic()

    def pick_at_ray(self, origin: ArrayLike, direction: ArrayLike) -> tuple[float, float] | None:
        """The design a click ray selects (None: off the map, or no design near)."""
        with self._lock:
            to_degrees, designs, size = self._to_degrees, self._designs, self._size
        if to_degrees is None:
            return None
        px = self.placement.pixel_of_ray(origin, direction, size)
        if px is None:
            return None
        c, m = to_degrees(*px)
        inside = (
            CMC_RANGE_DEG[0] - PICK_MARGIN_DEG <= c <= CMC_RANGE_DEG[1] + PICK_MARGIN_DEG
            and MCP_RANGE_DEG[0] - PICK_MARGIN_DEG <= m <= MCP_RANGE_DEG[1] + PICK_MARGIN_DEG
        )
        if not inside:
            return None
        k = nearest_design(designs, c, m, max_deg=PICK_RADIUS_DEG)
        return None if k is None else designs[k]

    def _clicked(self, event: viser.SceneNodePointerEvent) -> None:
        d = self.pick_at_ray(event.ray_origin, event.ray_direction)
        if d is not None:
            self.picks.append(d)
            self._on_pick(*d)
