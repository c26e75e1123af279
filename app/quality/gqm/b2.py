"""Q_B2, area of the grasp polygon (Roa & Suárez 2014, §B.2).

    Q_B2 = area of the convex grasp polygon of ``app.quality.gqm.polygon`` (mm²)

Larger is better (a wider polygon resists torques better). Not normalised: compared only
between grasps of one object. 0 with fewer than three non-collinear contacts.
"""

from __future__ import annotations

import numpy as np

from app.quality.gqm.polygon import grasp_polygon, polygon_area


def q_b2(p: np.ndarray) -> float:
    """Area (mm²) of the grasp polygon of contact points ``p`` (K, 3)."""
    return polygon_area(grasp_polygon(p))
