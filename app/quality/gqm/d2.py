"""Q_D2, uniformity of transformation (Roa & Suárez 2014, §D.2).

With the grasp matrix G (6, 3L) of ``app.quality.gqm.grasp_matrix`` and the hand Jacobian J_h
(3L, n_q) of ``app.quality.gqm.hand_jacobian`` (one contact per link, object frame), rigid contact
requires J_h q̇ = Gᵀ ν for the scaled object twist ν = [v; r ω]. The hand–object Jacobian
(least-squares object motion produced by the joint velocities) is

    H = (Gᵀ)⁺ J_h          (6, n_q)

and the measure is the ratio of its extreme singular values (the six of a 6 × n_q matrix):

    Q_D2 = σ_min(H) / σ_max(H)   ∈ [0, 1]

1 when joint velocities map uniformly onto every object-velocity direction; 0 when some
object velocity cannot be produced (rank(H) < 6, e.g. fewer than three non-collinear
contacts, or too few moving links in contact). ν's scaling by r makes H's rows
commensurate (mm/s for translation and r·ω), as G's torque rows are.
"""

from __future__ import annotations

import numpy as np


def hand_object_jacobian(G: np.ndarray, J_h: np.ndarray) -> np.ndarray:
    """H = (Gᵀ)⁺ J_h (6, n_q) from G (6, 3L) and J_h (3L, n_q)."""
    return np.linalg.pinv(G.T) @ J_h


def q_d2(G: np.ndarray, J_h: np.ndarray) -> float:
    """σ_min(H)/σ_max(H) of H = (Gᵀ)⁺ J_h."""
    if G.size == 0:
        return 0.0
    s = np.linalg.svd(hand_object_jacobian(G, J_h), compute_uv=False)
    s = np.concatenate([s, np.zeros(max(0, 6 - len(s)))])[:6]
    return float(s.min() / s.max()) if s.max() > 0 else 0.0
