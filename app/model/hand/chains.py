"""Fast per-finger forward kinematics for the closing loop.

A finger is a serial chain of three revolute joints about their local +x. The placements
come from the Pinocchio model (the one source of truth); this module only avoids the
per-call overhead of a whole-hand FK in the inner loop. ``tests/test_hand.py`` checks it
against ``pinocchio.forwardKinematics``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from app.model.hand.geometry import CapsuleShape
from app.model.hand.model import FINGER_JOINTS, FINGER_LINKS, Hand


def _rx(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    T = np.eye(4)
    T[1, 1], T[1, 2], T[2, 1], T[2, 2] = c, -s, s, c
    return T


@dataclass(frozen=True)
class FingerChain:
    """Kinematics and shapes of one finger (3 links moved by 3 joints)."""

    finger: str
    """'thumb', 'index', 'middle', 'ring' or 'little'."""
    joints: tuple[int, int, int]
    """Indices of its joints in the hand's q (proximal to distal)."""
    link_indices: tuple[int, int, int]
    """Indices of its links in ``LINK_NAMES`` order."""
    placements: np.ndarray
    """(3, 4, 4) joint placement of each joint in its parent's frame (first: in the palm)."""
    shapes: tuple[CapsuleShape, CapsuleShape, CapsuleShape]
    """Capsule of each link, link frame."""
    T_link_fcl: np.ndarray
    """(3, 4, 4) pose of FCL's capsule frame in each link frame."""
    q_lower: np.ndarray
    """(3,) lower limits, rad."""
    q_upper: np.ndarray
    """(3,) upper limits, rad."""
    ends_link: np.ndarray
    """(3, 2, 3) capsule segment ends of each link, link frame."""
    radii: np.ndarray
    """(3,) capsule radii."""
    mid_link: np.ndarray
    """(3, 3) capsule segment midpoints, link frame."""
    reach: np.ndarray
    """(3,) radius of the sphere about ``mid_link`` enclosing each capsule."""

    def link_poses(self, q_finger: np.ndarray) -> np.ndarray:
        """(3, 4, 4) T_palm_link of the three links at the finger's joint angles (3,)."""
        out = self.placements.copy()
        c, s = np.cos(q_finger), np.sin(q_finger)
        # right-multiplying by Rx(q) mixes columns 1 and 2 of each placement
        y, z = out[:, :3, 1].copy(), out[:, :3, 2].copy()
        out[:, :3, 1] = y * c[:, None] + z * s[:, None]
        out[:, :3, 2] = z * c[:, None] - y * s[:, None]
        out[1] = out[0] @ out[1]
        out[2] = out[1] @ out[2]
        return out


def finger_chains(hand: Hand) -> dict[str, FingerChain]:
    """The five finger chains of a hand, keyed by finger name."""
    out: dict[str, FingerChain] = {}
    for finger, joints in FINGER_JOINTS.items():
        lidx = tuple(hand.link_index[n] for n in FINGER_LINKS[finger])
        shapes = tuple(hand.links[i].shape for i in lidx)
        assert all(isinstance(s, CapsuleShape) for s in shapes)
        placements = np.stack(
            [hand.model.jointPlacements[hand.links[i].pin_joint_id].homogeneous for i in lidx]
        )
        out[finger] = FingerChain(
            finger=finger,
            joints=joints,
            link_indices=lidx,  # type: ignore[arg-type]
            placements=placements,
            shapes=shapes,  # type: ignore[arg-type]
            T_link_fcl=np.stack([s.T_link_fcl() for s in shapes]),
            q_lower=hand.q_lower[list(joints)],
            q_upper=hand.q_upper[list(joints)],
            ends_link=np.stack([np.stack([s.p0_link, s.p1_link]) for s in shapes]),  # type: ignore[union-attr]
            radii=np.array([s.radius for s in shapes]),  # type: ignore[union-attr]
            mid_link=np.stack([(s.p0_link + s.p1_link) / 2 for s in shapes]),  # type: ignore[union-attr]
            reach=np.array([s.length / 2 + s.radius for s in shapes]),  # type: ignore[union-attr]
        )
    return out
