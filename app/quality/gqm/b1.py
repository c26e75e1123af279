"""Q_B1, distance between the contact centroid and the object's centre of mass (R&S §B.1).

Roa & Suárez minimise the distance d = |p̄ − c|, p̄ the mean of the (one per link) contact
points, c the centroid. As a score (larger is better), normalised by the object's largest
radius r and clipped:

    Q_B1 = clip(1 − d / r, 0, 1)

1 when the contacts are centred on the centre of mass (gravity and inertia produce the
least torque about the grasp).
"""

from __future__ import annotations

import numpy as np


def q_b1(p: np.ndarray, centroid: np.ndarray, r: float) -> float:
    """Score of contacts ``p`` (K, 3) about ``centroid`` (3,), object radius ``r`` (mm)."""
    p = np.asarray(p, float).reshape(-1, 3)
    if len(p) == 0:
        return 0.0
    d = float(np.linalg.norm(p.mean(axis=0) - np.asarray(centroid, float)))
    return float(np.clip(1.0 - d / float(r), 0.0, 1.0))
