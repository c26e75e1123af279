"""Link shapes: one capsule per phalanx (collision), a box for the palm, visual meshes.

Decision (measured, see docs/design.md): capsules are exact, cheap FCL primitives
(capsule-vs-convex distance ~5 µs); the visual meshes lie inside them so a collision
never happens "in the air" by more than the visual inset.
"""

from __future__ import annotations

from dataclasses import dataclass

import fcl
import numpy as np
import trimesh

#: How much smaller than the collision capsule the visual capsule is (fraction of radius).
VISUAL_INSET = 0.03
VISUAL_CAPSULE_COUNT = (16, 12)
"""Segments of a drawn capsule: around its axis, and over each cap (trimesh's ``count``).
384 triangles a link: the explorer's browser renders the hand without a GPU in many set-ups
(software WebGL), where the hand at (24, 24) (1,152 a link) took a fifth of a frame."""


@dataclass(frozen=True, eq=False)  # hashed by identity (caches)
class CapsuleShape:
    """A capsule in its link frame: the segment p0-p1 swept by a sphere of ``radius``."""

    p0_link: np.ndarray
    """(3,) segment start, link frame, mm."""
    p1_link: np.ndarray
    """(3,) segment end, link frame, mm."""
    radius: float
    """Sphere radius, mm."""

    @property
    def length(self) -> float:
        """Segment length (without the caps), mm."""
        return float(np.linalg.norm(self.p1_link - self.p0_link))

    def T_link_fcl(self) -> np.ndarray:
        """(4, 4) pose of FCL's capsule frame (axis +z, centred) in the link frame."""
        axis = self.p1_link - self.p0_link
        axis = axis / np.linalg.norm(axis)
        # rotation taking +z onto the segment axis
        z = np.array([0.0, 0.0, 1.0])
        v = np.cross(z, axis)
        s, c = np.linalg.norm(v), float(z @ axis)
        if s < 1e-12:
            R = np.eye(3) if c > 0 else np.diag([1.0, -1.0, -1.0])
        else:
            K = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]]) / s
            ang = np.arctan2(s, c)
            R = np.eye(3) + np.sin(ang) * K + (1 - np.cos(ang)) * K @ K
        T = np.eye(4)
        T[:3, :3] = R
        T[:3, 3] = 0.5 * (self.p0_link + self.p1_link)
        return T

    def fcl_geometry(self) -> fcl.CollisionGeometry:
        """The FCL capsule (to be posed with ``T_palm_link @ T_link_fcl``)."""
        return fcl.Capsule(self.radius, self.length)

    def visual_mesh(self, inset: float = VISUAL_INSET) -> trimesh.Trimesh:
        """Capsule mesh a little inside the collision capsule, link frame."""
        m = trimesh.creation.capsule(
            height=self.length, radius=self.radius * (1 - inset), count=list(VISUAL_CAPSULE_COUNT)
        )
        m.apply_transform(self.T_link_fcl())
        return m

    def surface_points(self, spacing: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
        """Quasi-uniform points on the capsule surface and their outward normals.

        Returns ``(p_link (M, 3), n_link (M, 3))``; used to sample contact patches.
        """
        T = self.T_link_fcl()
        r, h = self.radius, self.length
        pts, nrm = [], []
        n_around = max(12, int(np.ceil(2 * np.pi * r / spacing)))
        n_along = max(2, int(np.ceil(h / spacing)) + 1)
        phi = np.linspace(0, 2 * np.pi, n_around, endpoint=False)
        for zc in np.linspace(-h / 2, h / 2, n_along):
            nn = np.stack([np.cos(phi), np.sin(phi), np.zeros_like(phi)], 1)
            pts.append(nn * r + [0, 0, zc])
            nrm.append(nn)
        # hemispherical caps by Fibonacci spirals
        n_cap = max(8, int(np.ceil(2 * np.pi * r * r / spacing**2)))
        k = np.arange(n_cap) + 0.5
        cz = 1 - k / n_cap  # in (0, 1]
        theta = np.pi * (1 + 5**0.5) * k
        sr = np.sqrt(1 - cz**2)
        cap = np.stack([sr * np.cos(theta), sr * np.sin(theta), cz], 1)
        for sign in (1.0, -1.0):
            nn = cap * [1, 1, sign]
            pts.append(nn * r + [0, 0, sign * h / 2])
            nrm.append(nn)
        p = np.concatenate(pts)
        n = np.concatenate(nrm)
        return p @ T[:3, :3].T + T[:3, 3], n @ T[:3, :3].T


@dataclass(frozen=True, eq=False)  # hashed by identity (caches)
class BoxShape:
    """An axis-aligned box in its link frame (the palm)."""

    lo_link: np.ndarray
    """(3,) minimum corner, mm."""
    hi_link: np.ndarray
    """(3,) maximum corner, mm."""
    corner_radius: float
    """Rounding radius of the visual mesh, mm."""

    def T_link_fcl(self) -> np.ndarray:
        """(4, 4) pose of FCL's (centred) box in the link frame."""
        T = np.eye(4)
        T[:3, 3] = 0.5 * (self.lo_link + self.hi_link)
        return T

    def fcl_geometry(self) -> fcl.CollisionGeometry:
        """The FCL box."""
        return fcl.Box(*(self.hi_link - self.lo_link))

    def visual_mesh(self, inset: float = VISUAL_INSET) -> trimesh.Trimesh:
        """Rounded box (hull of corner spheres), inside the collision box."""
        r = self.corner_radius
        pad = inset * r
        lo, hi = self.lo_link + r + pad, self.hi_link - r - pad
        sphere = trimesh.creation.icosphere(subdivisions=2, radius=r)
        corners = np.array(
            [[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]
        )
        pts = (sphere.vertices[None, :, :] + corners[:, None, :]).reshape(-1, 3)
        return trimesh.convex.convex_hull(pts)

    def surface_points(self, spacing: float = 1.5) -> tuple[np.ndarray, np.ndarray]:
        """Grid points on the box faces and their outward normals, link frame."""
        pts, nrm = [], []
        lo, hi = self.lo_link, self.hi_link
        for axis in range(3):
            a1, a2 = [i for i in range(3) if i != axis]
            u = np.linspace(lo[a1], hi[a1], max(2, int((hi[a1] - lo[a1]) / spacing) + 1))
            v = np.linspace(lo[a2], hi[a2], max(2, int((hi[a2] - lo[a2]) / spacing) + 1))
            U, V = np.meshgrid(u, v, indexing="ij")
            for side, val in ((-1.0, lo[axis]), (1.0, hi[axis])):
                p = np.zeros((U.size, 3))
                p[:, a1], p[:, a2], p[:, axis] = U.ravel(), V.ravel(), val
                n = np.zeros_like(p)
                n[:, axis] = side
                pts.append(p)
                nrm.append(n)
        return np.concatenate(pts), np.concatenate(nrm)


Shape = CapsuleShape | BoxShape
