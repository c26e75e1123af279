"""Q_A1, minimum singular value of the grasp matrix (Roa & Suárez 2014, §A.1).

    Q_A1 = σ_min(G),  G (6, 3K) of ``app.quality.gqm.grasp_matrix`` (torque rows / r).

Larger is better: the grasp is far from a singular configuration (0 when G loses rank,
e.g. two hard-finger contacts). Dimensionless (per unit contact force).
"""

from __future__ import annotations

import numpy as np


def q_a1(singular_values: np.ndarray) -> float:
    """σ_min from the (6,) singular values of G."""
    return float(np.min(singular_values))
