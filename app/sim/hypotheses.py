"""Anthropomorphic grasp hypotheses (METHOD §3a): approach rays in a cone, standoffs, rolls.

A hypothesis fixes the hand's approach line and orientation; the approach distance (first
contact) is found by the closing stage. Everything here depends on the object and the palm
only, never on the thumb design.

Cone scheme (our decision): ray 0 is the cone axis; rays 1..N-1 follow a spherical
Fibonacci spiral over the cap of half-angle α/2 whose k-th ray has
cos θ_k = 1 - k/(N-1) · (1 - cos(α/2)) (equal-area rings, the last on the rim) and azimuth
k · golden angle. Roll θ turns the hand about the ray by the right-hand rule about the
approach direction (palm toward object); θ = 0 puts the palm's +y as close as possible to
the object's ``palm_y_hint``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from app.errors import UnknownHypothesisError
from app.model.objects import GraspObject

GOLDEN_ANGLE = np.pi * (3.0 - np.sqrt(5.0))


def cone_rays(axis: np.ndarray, cone_angle_rad: float, n_rays: int) -> np.ndarray:
    """(n_rays, 3) unit directions within the cone of full opening ``cone_angle_rad``."""
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    k = np.arange(n_rays)
    if n_rays > 1:
        cos_t = 1.0 - k / (n_rays - 1) * (1.0 - np.cos(cone_angle_rad / 2))
    else:
        cos_t = np.ones(1)
    sin_t = np.sqrt(np.clip(1.0 - cos_t**2, 0.0, None))
    phi = k * GOLDEN_ANGLE
    e1, e2 = _orthonormal_pair(axis)
    d = (
        cos_t[:, None] * axis
        + sin_t[:, None] * np.cos(phi)[:, None] * e1
        + sin_t[:, None] * np.sin(phi)[:, None] * e2
    )
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def _orthonormal_pair(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    helper = np.array([1.0, 0.0, 0.0]) if abs(a[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = np.cross(a, helper)
    e1 /= np.linalg.norm(e1)
    return e1, np.cross(a, e1)


def rotation_about(axis: np.ndarray, angle_rad: float) -> np.ndarray:
    """(3, 3) rotation by ``angle_rad`` about unit ``axis`` (Rodrigues)."""
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + np.sin(angle_rad) * K + (1 - np.cos(angle_rad)) * K @ K


def palm_orientation(
    approach_object: np.ndarray,
    hand_vector_palm: np.ndarray,
    palm_y_hint_object: np.ndarray,
    roll_rad: float,
) -> np.ndarray:
    """R_object_palm such that R @ n_palm = ``approach_object`` (the hand vector points at the
    object) and palm +y is the hint projected off the approach line, then rolled about it."""
    n_w = approach_object / np.linalg.norm(approach_object)
    n_p = hand_vector_palm / np.linalg.norm(hand_vector_palm)
    y_p = np.array([0.0, 1.0, 0.0])
    y_p = y_p - (y_p @ n_p) * n_p  # palm +y off the hand vector (exact for the METHOD's n)
    y_p /= np.linalg.norm(y_p)
    y_w = palm_y_hint_object - (palm_y_hint_object @ n_w) * n_w
    if np.linalg.norm(y_w) < 1e-6:  # hint along the approach: any perpendicular will do
        y_w = _orthonormal_pair(n_w)[0]
    y_w /= np.linalg.norm(y_w)
    B_w = np.stack([n_w, y_w, np.cross(n_w, y_w)], 1)
    B_p = np.stack([n_p, y_p, np.cross(n_p, y_p)], 1)
    return rotation_about(n_w, roll_rad) @ B_w @ B_p.T


@dataclass(frozen=True)
class Hypotheses:
    """The N grasp hypotheses of one object (all arrays on a leading axis of length N)."""

    object_key: str
    """Object key."""
    ids: tuple[str, ...]
    """(N,) stable ids '<object>/r<ray>/d<standoff>/t<roll>'."""
    ray_index: np.ndarray
    """(N,) int index of the approach ray."""
    standoff_index: np.ndarray
    """(N,) int index of the standoff."""
    roll_index: np.ndarray
    """(N,) int index of the roll."""
    ray_object: np.ndarray
    """(N, 3) outward unit ray direction (from the target toward the hand), object frame."""
    target_object: np.ndarray
    """(3,) the point every ray passes through, object frame, mm."""
    standoff_mm: np.ndarray
    """(N,) back-off distance after first contact, mm."""
    roll_rad: np.ndarray
    """(N,) roll about the ray, rad."""
    R_object_palm: np.ndarray
    """(N, 3, 3) hand orientation, object frame."""

    def __len__(self) -> int:
        return len(self.ids)

    def index_of(self, gh: str | int) -> int:
        """Position of a hypothesis given its id or index; UnknownHypothesisError otherwise."""
        if isinstance(gh, int | np.integer):
            if 0 <= gh < len(self):
                return int(gh)
            raise UnknownHypothesisError(
                f"hypothesis index {gh} out of range: {self.object_key} has {len(self)} "
                f"(0..{len(self) - 1})"
            )
        try:
            return self.ids.index(gh)
        except ValueError:
            raise UnknownHypothesisError(
                f"no hypothesis {gh!r} for {self.object_key}; ids look like {self.ids[0]!r} "
                f"(0..{len(self) - 1} also accepted)"
            ) from None


def make_hypotheses(
    object_key: str,
    target_object: np.ndarray,
    normal_object: np.ndarray,
    palm_y_hint_object: np.ndarray,
    hand_vector_palm: np.ndarray,
    cone_angle_rad: float,
    n_rays: int,
    standoffs_mm: tuple[float, ...] | list[float],
    roll_range_deg: tuple[float, float],
    n_rolls: int,
) -> Hypotheses:
    """All N = n_rays · n_standoffs · n_rolls hypotheses, ray-major then standoff then roll."""
    rays = cone_rays(normal_object, cone_angle_rad, n_rays)
    rolls = np.deg2rad(np.linspace(roll_range_deg[0], roll_range_deg[1], n_rolls))
    standoffs = np.asarray(standoffs_mm, float)
    ri, di, ti = np.meshgrid(
        np.arange(n_rays), np.arange(len(standoffs)), np.arange(n_rolls), indexing="ij"
    )
    ri, di, ti = ri.ravel(), di.ravel(), ti.ravel()
    R = np.stack(
        [
            palm_orientation(-rays[r], hand_vector_palm, palm_y_hint_object, rolls[t])
            for r, t in zip(ri, ti, strict=True)
        ]
    )
    ids = tuple(f"{object_key}/r{r:02d}/d{d}/t{t:02d}" for r, d, t in zip(ri, di, ti, strict=True))
    return Hypotheses(
        object_key=object_key,
        ids=ids,
        ray_index=ri,
        standoff_index=di,
        roll_index=ti,
        ray_object=rays[ri],
        target_object=np.asarray(target_object, float),
        standoff_mm=standoffs[di],
        roll_rad=rolls[ti],
        R_object_palm=R,
    )


def hypotheses_for(obj: GraspObject) -> Hypotheses:
    """The anthropomorphic hypotheses of a ``GraspObject`` (from its spec's set-up)."""
    spec = obj.spec
    s = spec.setup
    return make_hypotheses(
        spec.key,
        spec.target_object,
        spec.normal_object,
        spec.palm_y_hint_object,
        s.hand_vector_palm,
        s.cone_angle_rad,
        s.n_rays,
        s.standoffs_mm,
        s.roll_range_deg,
        s.n_rolls,
    )
