"""Q_B3, shape of the grasp polygon (Roa & Suárez 2014, §B.3).

For a grasp polygon with n vertices and interior angles θ_i, the regular polygon's angle is
θ̄ = π (n − 2) / n, and the largest possible total deviation, reached as the polygon
degenerates into a segment (n − 2 angles → π, two → 0), is
θ_max = (n − 2)(π − θ̄) + 2 θ̄. Roa & Suárez minimise Σ|θ_i − θ̄| / θ_max; as a score:

    Q_B3 = 1 − Σ_i |θ_i − θ̄| / θ_max   ∈ [0, 1]

1 for a regular polygon; 0 with no polygon (fewer than three non-collinear contacts).
"""

from __future__ import annotations

import numpy as np

from app.quality.gqm.polygon import grasp_polygon, interior_angles


def q_b3(p: np.ndarray) -> float:
    """Regularity score of the grasp polygon of contact points ``p`` (K, 3)."""
    v = grasp_polygon(p)
    n = len(v)
    if n < 3:
        return 0.0
    theta = interior_angles(v)
    mean = np.pi * (n - 2) / n
    theta_max = (n - 2) * (np.pi - mean) + 2 * mean
    return float(np.clip(1.0 - np.sum(np.abs(theta - mean)) / theta_max, 0.0, 1.0))
