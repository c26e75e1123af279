"""Q_A2, volume of the grasp ellipsoid in wrench space (Roa & Suárez 2014, §A.2).

    Q_A2 = √det(G Gᵀ) = σ_1 σ_2 ⋯ σ_6

(proportional to the volume of the ellipsoid of wrenches produced by unit-norm contact
forces). Larger is better; 0 when G loses rank. Dimensionless, not normalised.
"""

from __future__ import annotations

import numpy as np


def q_a2(singular_values: np.ndarray) -> float:
    """Product of the (6,) singular values of G."""
    return float(np.prod(singular_values))
