"""Test helpers: analytic stand-in objects (exact SDF) for closing, contact and force-closure
tests, and deterministic outcomes for store tests."""

from __future__ import annotations

from dataclasses import dataclass

import fcl
import numpy as np

from app.model.contact_set import LINK_NAMES, ContactSet
from app.model.objects.shapes import Piece
from app.quality.outcome import GraspOutcome
from app.sim.hypotheses import Hypotheses, make_hypotheses


@dataclass(frozen=True)
class StandInSpec:
    """The part of an object file a stand-in needs (``app.model.target.TargetSpec``)."""

    key: str
    grasp_type: str
    grip_axis_object: np.ndarray | None


@dataclass(frozen=True)
class Body:
    """Centroid and torque scale only (``app.model.target.RigidBody``), for GQM tests."""

    centroid_object: np.ndarray
    max_radius: float


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
        self.spec = StandInSpec(
            key=self.key,
            grasp_type=self.grasp_type,
            grip_axis_object=T[:3, :3] @ np.array([0.0, 0.0, 1.0]),
        )

    def collision_objects(self) -> list[fcl.CollisionObject]:
        return self._pieces

    @property
    def pieces(self) -> tuple[Piece, ...]:
        """The one FCL cylinder as a ``Piece`` (the compiled closing engine reads it)."""
        return (
            Piece(fcl.Cylinder(self.radius, self.height), self.T[:3, :3], self.centroid_object),
        )

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


def make_outcome(seed: int, k: int | None = None, dtype: type = np.float64) -> GraspOutcome:
    """A deterministic outcome with ``k`` contacts (random k when None)."""
    rng = np.random.default_rng(seed)
    k = int(rng.integers(0, 12)) if k is None else k
    link = np.empty((k,), dtype=object)
    link[:] = [LINK_NAMES[int(i)] for i in rng.integers(0, len(LINK_NAMES), k)]
    fc = bool(rng.random() < 0.6)
    return GraspOutcome(
        q_final_rad=rng.normal(size=15),
        contacts=ContactSet(
            rng.normal(size=(k, 3)).astype(dtype) * 50,
            rng.normal(size=(k, 3)).astype(dtype),
            link,
            rng.random(k) < 0.5,
        ),
        is_fc=fc,
        is_correct=fc and bool(rng.random() < 0.5),
        epsilon=float(rng.random()) if fc else 0.0,
        reasons=() if fc else ("not force closure", "no palmar contact on the thumb"),
        n_queries=int(rng.integers(0, 5000)),
    )


def can_hypotheses(
    target=(37.5, 0, 125.0), normal=(1.0, 0, 0), hint=(0, 1.0, 0), n_rays=28
) -> Hypotheses:
    """Cylindrical-grip hypotheses on ``AnalyticCylinder()`` (the chips can's cone and rolls)."""
    return make_hypotheses(
        "can",
        np.array(target),
        np.array(normal),
        np.array(hint),
        np.array([0.41, 0, 0.91]),
        0.2,
        n_rays,
        [0.0],
        (-20, -50),
        15,
    )
