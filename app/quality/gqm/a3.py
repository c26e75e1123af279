"""Q_A3, grasp isotropy index (Roa & Suárez 2014, §A.3).

    Q_A3 = σ_min(G) / σ_max(G)  ∈ [0, 1]

1 for an isotropic grasp (every wrench direction equally easy), 0 when G loses rank.
"""

from __future__ import annotations

import numpy as np


def q_a3(singular_values: np.ndarray) -> float:
    """σ_min/σ_max from the (6,) singular values of G (0 for an all-zero G)."""
    s_max = float(np.max(singular_values))
    return float(np.min(singular_values)) / s_max if s_max > 0 else 0.0
