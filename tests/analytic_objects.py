"""Analytic stand-in objects (exact SDF) for closing, contact and force-closure tests."""

from __future__ import annotations

from dataclasses import dataclass
from types import SimpleNamespace

import fcl
import numpy as np


@dataclass
class AnalyticCylinder:
    """Solid cylinder of radius r and height h, axis +z, base at z = 0 (object frame)."""

    radius: float = 37.5
    height: float = 250.0
    grasp_type: str = "CG"
    key: str = "test_cylinder"
    T_world_cyl: np.ndarray | None = None
    """Optional rigid pose of the cylinder in the frame used for every query."""

    def __post_init__(self) -> None:
        T = np.eye(4) if self.T_world_cyl is None else self.T_world_cyl
        self.T = T
        self.centroid_object = T[:3, :3] @ np.array([0.0, 0.0, self.height / 2]) + T[:3, 3]
        self.max_radius = float(np.hypot(self.radius, self.height / 2))
        self._pieces = [
            fcl.CollisionObject(
                fcl.Cylinder(self.radius, self.height),
                fcl.Transform(T[:3, :3], self.centroid_object),
            )
        ]
        self.spec = SimpleNamespace(
            key=self.key,
            grasp_type=self.grasp_type,
            grip_axis_object=T[:3, :3] @ np.array([0.0, 0.0, 1.0]),
        )

    def collision_objects(self) -> list[fcl.CollisionObject]:
        return self._pieces

    def sdf(self, p: np.ndarray) -> np.ndarray:
        p = (np.asarray(p, float) - self.T[:3, 3]) @ self.T[:3, :3]  # into the cylinder frame
        dr = np.hypot(p[:, 0], p[:, 1]) - self.radius
        dz = np.abs(p[:, 2] - self.height / 2) - self.height / 2
        outside = np.hypot(np.maximum(dr, 0), np.maximum(dz, 0))
        return outside + np.minimum(np.maximum(dr, dz), 0)

    def normal(self, p: np.ndarray, h: float = 1e-4) -> np.ndarray:
        p = np.asarray(p, float)
        g = np.stack(
            [(self.sdf(p + h * e) - self.sdf(p - h * e)) / (2 * h) for e in np.eye(3)], axis=1
        )
        return g / np.linalg.norm(g, axis=1, keepdims=True)
