"""Camera views of the scene (viser-free): where to put the camera so the design shows.

The palm frame is +x radial (toward the thumb), +y distal, +z palmar. Every view looks from
the palmar-radial side of the hand, where the thumb and its opposition to the fingers are
in sight; they differ in what they frame. Lengths in mm, object frame (the world).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from app.errors import HandbenchError
from app.explorer.map_pick import MapPlacement

THUMB = "thumb close-up"
GRASP = "grasp"
OVERVIEW = "overview"
MAP = "design map"
"""Not a view of the hand: the clickable design map hung in the scene (``scene_map``)."""
VIEWS: tuple[str, ...] = (THUMB, GRASP, OVERVIEW, MAP)
DEFAULT_VIEW = GRASP

#: View directions in the palm frame (radial, distal, palmar), before normalising.
_DIRECTION_PALM = {
    THUMB: (1.0, 0.15, 0.75),
    GRASP: (1.0, 0.35, 0.65),
    OVERVIEW: (0.8, 0.5, 0.6),
}
#: Extra world +z in the direction (a little from above), and distance per framed radius.
_LIFT = {THUMB: 0.15, GRASP: 0.25, OVERVIEW: 0.7}
_DISTANCE = {THUMB: 1.5, GRASP: 1.5, OVERVIEW: 1.9}


class UnknownViewError(HandbenchError, KeyError):
    """A camera view that is not one of ``VIEWS``."""

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else ""


@dataclass(frozen=True)
class CameraPose:
    """Camera position, the point it looks at, and its up direction (object frame, mm)."""

    position: np.ndarray
    look_at: np.ndarray
    up: np.ndarray


def camera_pose(
    view: str,
    T_object_palm: np.ndarray,
    thumb_points: np.ndarray,
    hand_points: np.ndarray,
    object_bounds: np.ndarray,
    panel_shift: float = 0.3,
) -> CameraPose:
    """The camera of ``view``.

    ``thumb_points`` (K, 3) and ``hand_points`` (L, 3): link origins (and tips) of the thumb
    and of the whole hand; ``object_bounds`` (2, 3): the object's box. The thumb close-up
    frames the thumb, the grasp view the object and the hand's grasping part (thumb and
    fingers), the overview everything with some room. ``panel_shift`` (of the framed radius)
    moves the framed part left on the screen, clear of the control panel on the right.
    """
    if view not in _DIRECTION_PALM:
        raise UnknownViewError(f"unknown view {view!r}; choose one of {VIEWS}")
    if view == THUMB:
        pts = np.asarray(thumb_points, float)
        margin = 25.0
    elif view == GRASP:  # the hand, and the part of the object within reach of it
        hand = np.vstack([thumb_points, hand_points])
        near_lo, near_hi = hand.min(axis=0) - 40.0, hand.max(axis=0) + 40.0
        ob = np.clip(np.asarray(object_bounds, float), near_lo, near_hi)
        pts = np.vstack([ob, hand])
        margin = 20.0
    else:
        pts = np.vstack([object_bounds, hand_points])
        margin = 40.0
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    centre = (lo + hi) / 2
    radius = float(np.linalg.norm(hi - lo)) / 2 + margin
    R = np.asarray(T_object_palm, float)[:3, :3]
    d = R @ np.asarray(_DIRECTION_PALM[view]) + np.array([0.0, 0.0, _LIFT[view]])
    d /= np.linalg.norm(d)
    up = np.array([0.0, 0.0, 1.0])
    if abs(float(d @ up)) > 0.95:  # looking straight down: the palm's distal axis is up
        up = R[:, 1]
    right = np.cross(-d, up)
    right /= max(float(np.linalg.norm(right)), 1e-9)
    target = centre + right * panel_shift * radius
    return CameraPose(target + d * radius * _DISTANCE[view], target, up)


def map_camera_pose(
    placement: MapPlacement, fov_rad: float, aspect: float, panel_frac: float = 0.33
) -> CameraPose:
    """The camera of the 'design map' view, in metres: square on to the map, which fills
    87 % of the height, moved left on the screen by half the control panel's share
    (``panel_frac``) of the width, so the panel hides none of it."""
    c = np.asarray(placement.centre, float)
    span_h = placement.height / 0.87
    dist = span_h / 2 / np.tan(fov_rad / 2)
    span_w = span_h * aspect
    shift = min(panel_frac / 2 * span_w, max(span_w / 2 - placement.width / 2, 0.0))
    target = c + np.array([shift, 0.0, 0.0])
    return CameraPose(target - np.array([0.0, dist, 0.0]), target, np.array([0.0, 0.0, 1.0]))
