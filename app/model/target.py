"""What the simulation and the judges need of a grasped object: the ``GraspTarget`` protocol.

``app.model.objects.GraspObject`` satisfies it; so do the analytic stand-ins of the tests
(exact SDFs), which is why the sim and quality layers are typed against this protocol and
not against the class.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol

import fcl
import numpy as np


class TargetSpec(Protocol):
    """The part of an object's data file that closing and judging read."""

    @property
    def key(self) -> str:
        """The object key, e.g. 'chips_can'."""
        ...

    @property
    def grasp_type(self) -> str:
        """'PP' (pulp pinch) or 'CG' (cylindrical grip)."""
        ...

    @property
    def grip_axis_object(self) -> np.ndarray | None:
        """(3,) unit grip axis in the object frame (CG objects), else None."""
        ...


class RigidBody(Protocol):
    """Where an object's wrenches are taken about, and their torque scale (METHOD §5)."""

    @property
    def centroid_object(self) -> np.ndarray:
        """(3,) centre of mass, object frame, mm (the torque origin of force closure)."""
        ...

    @property
    def max_radius(self) -> float:
        """Largest distance from the centroid to the surface, mm (the torque scale r)."""
        ...


class GraspTarget(RigidBody, Protocol):
    """A rigid object in its own frame (mm): collision pieces, signed distance, normals."""

    @property
    def spec(self) -> TargetSpec:
        """Key, grasp type and grip axis."""
        ...

    def collision_objects(self) -> Sequence[fcl.CollisionObject]:
        """FCL bodies (convex pieces or a mesh) posed in the object frame."""
        ...

    def sdf(self, p_object: np.ndarray, /) -> np.ndarray:
        """Signed distance (N,) of points (N, 3), object frame, mm; negative inside."""
        ...

    def normal(self, p_object: np.ndarray, /) -> np.ndarray:
        """(N, 3) outward unit normals at (or near) points (N, 3) of the surface."""
        ...
