"""Picking a design on the in-scene map (viser-free): where the map image hangs in the scene,
which pixel a click ray hits, and which design is nearest to it.

The map image hangs upright, facing a camera that looks along world +y with +z up: image
columns run along world +x, rows downward along world -z. viser draws an image node as a
plane in its local x-y (x right, y down, seen along local +z), so its orientation is a
rotation of -90° about x.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

MAP_WXYZ = (math.cos(-math.pi / 4), math.sin(-math.pi / 4), 0.0, 0.0)
"""Orientation of the image node: local x -> world +x, local y (rows) -> world -z,
local z (the viewing direction) -> world +y."""
_R = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])
"""The rotation matrix of ``MAP_WXYZ`` (columns: the local axes in the world)."""


@dataclass(frozen=True)
class MapPlacement:
    """Where the map image is in the scene (metres)."""

    centre: tuple[float, float, float]
    width: float
    """Along world +x (the image's columns)."""
    height: float
    """Along world -z (the image's rows)."""

    def pixel_of_ray(
        self,
        origin: ArrayLike,
        direction: ArrayLike,
        image_size: tuple[int, int],
    ) -> tuple[float, float] | None:
        """Pixel (x, y) of an image of ``image_size`` (W, H) that a click ray hits, or None
        when the ray misses the image (parallel, behind the camera, outside it)."""
        o = np.asarray(origin, float)
        d = np.asarray(direction, float)
        c = np.asarray(self.centre, float)
        n = _R[:, 2]
        dn = float(d @ n)
        if abs(dn) < 1e-12:
            return None
        t = float((c - o) @ n) / dn
        if t <= 0:
            return None
        local = _R.T @ (o + t * d - c)
        u, v = local[0] / self.width + 0.5, local[1] / self.height + 0.5
        if not (0.0 <= u <= 1.0 and 0.0 <= v <= 1.0):
            return None
        return (u * image_size[0], v * image_size[1])

    def world_of_pixel(
        self, x: float, y: float, image_size: tuple[int, int]
    ) -> tuple[float, float, float]:
        """World point (m) of pixel (x, y) of an image of ``image_size`` (W, H)."""
        local = np.array(
            [(x / image_size[0] - 0.5) * self.width, (y / image_size[1] - 0.5) * self.height, 0.0]
        )
        p = np.asarray(self.centre, float) + _R @ local
        return (float(p[0]), float(p[1]), float(p[2]))


def nearest_design(
    designs: Sequence[tuple[float, float]],
    cmc_deg: float,
    mcp_deg: float,
    max_deg: float,
) -> int | None:
    """Index of the design nearest to (cmc_deg, mcp_deg), or None when none is within
    ``max_deg`` degrees (a click on the title or the colour bar picks nothing)."""
    if not designs:
        return None
    a = np.asarray(designs, float)
    dist = np.hypot(a[:, 0] - cmc_deg, a[:, 1] - mcp_deg)
    k = int(np.argmin(dist))
    return k if dist[k] <= max_deg else None
