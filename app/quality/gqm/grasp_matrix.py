"""The grasp matrix G of hard-finger point contacts (shared by Q_A1..Q_A3 and Q_D2).

For K contacts at points p_k (object frame, mm), G (6, 3K) maps the stacked contact forces
f = [f_1; …; f_K] (3K,) to the object wrench about its centroid c, torque scaled by the
object's largest radius r (as in METHOD §5, so force and torque rows are commensurate):

    G = [ I₃           …  I₃          ]
        [ [p_1 − c]×/r …  [p_K − c]×/r ]

Gᵀ maps the scaled object twist ν = [v; r ω] to the contact point velocities.
The force block of G Gᵀ is K·I₃, so singular values grow like √K: a measure that rewards
more contacts (Roa & Suárez 2014 discuss this; we keep it unnormalised).
"""

from __future__ import annotations

import numpy as np


def skew(v: np.ndarray) -> np.ndarray:
    """(..., 3, 3) cross-product matrices ``[v]×`` of (..., 3) vectors."""
    v = np.asarray(v, float)
    out = np.zeros((*v.shape[:-1], 3, 3))
    out[..., 0, 1], out[..., 0, 2] = -v[..., 2], v[..., 1]
    out[..., 1, 0], out[..., 1, 2] = v[..., 2], -v[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -v[..., 1], v[..., 0]
    return out


def grasp_matrix(p: np.ndarray, centroid: np.ndarray, r: float) -> np.ndarray:
    """G (6, 3K) of contacts ``p`` (K, 3) about ``centroid`` (3,), torque rows divided by r."""
    p = np.asarray(p, float).reshape(-1, 3)
    k = len(p)
    G = np.zeros((6, 3 * k))
    G[:3] = np.tile(np.eye(3), (1, k))
    S = skew((p - np.asarray(centroid, float)) / float(r))  # (K, 3, 3)
    G[3:] = S.transpose(1, 0, 2).reshape(3, 3 * k)
    return G


def grasp_singular_values(p: np.ndarray, centroid: np.ndarray, r: float) -> np.ndarray:
    """(6,) singular values of G, descending (zeros padded when 3K < 6)."""
    G = grasp_matrix(p, centroid, r)
    s = np.linalg.svd(G, compute_uv=False) if G.size else np.zeros(0)
    return np.concatenate([s, np.zeros(6 - len(s))]) if len(s) < 6 else s[:6]
