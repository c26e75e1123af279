"""The grasp wrench space: the qhull hull of primitive wrenches (Q_C2, and Q_C1's fallback).

Primitive wrenches (METHOD §5, ``app.quality.force_closure.primitive_wrenches``): every contact
point p with unit normal n (link → object) and every edge f of its friction cone (μ, E
edges, unit normal component) gives ``w = [f, (p − c) × f / r]`` (6,), c the object's
centroid and r its largest radius. Q_C2 builds this hull on one contact per link (the
grasp-matrix model of ``app.quality.gqm.contacts``); Q_C1 finds ε on every patch point without the
full hull (``app.quality.gqm.epsilon``) and uses this hull only where that argument does not apply
(origin not strictly inside, qhull errors on its sub-hulls).

The hull ``conv(W)`` (``scipy.spatial.ConvexHull``, the same options as
``app.quality.force_closure.fc_and_epsilon``: scipy's default ``Qx``/``Qt`` for 6-D, input used
exactly); its facets ``a_k · x + b_k ≤ 0`` (|a_k| = 1) give ε = min_k(−b_k), identical to
``fc_and_epsilon`` (a test checks it), and its volume. If qhull fails on a
nearly degenerate set (precision errors), the hull is retried once with ``QJ`` (joggled
input, perturbation ~1e-11 relative); if that fails too, ε = volume = 0.

Cost: a hull of the 250–700 patch wrenches of a brute-force grasp takes 0.2–0.65 s
(``benchmarks/bench_gqm.py``): 90–100 % of them are hull vertices and the hull has ~130
facets per vertex, so exact pruning gains little, and the qhull options that are faster
(``Q5``, ``QJ``) change the values. The per-link hull (48–77 wrenches) takes 13–23 ms.
``docs/bruteforce.md`` (Costs) lists what was measured.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from scipy.spatial import ConvexHull, QhullError

from app.quality.force_closure import RANK_REL_TOL, primitive_wrenches


class WrenchSpace(NamedTuple):
    """The hull of the primitive wrenches of one grasp."""

    W: np.ndarray
    """(M, 6) primitive wrenches."""
    equations: np.ndarray
    """(F, 7) facet hyperplanes ``[a_k, b_k]``, ``a_k · x + b_k ≤ 0`` inside, |a_k| = 1;
    (0, 7) when degenerate."""
    volume: float
    """6-D volume of conv(W) (0 when degenerate)."""

    @property
    def epsilon(self) -> float:
        """Ferrari–Canny ε = min_k(−b_k) (≤ 0 when the origin is not inside; 0 if degenerate)."""
        if len(self.equations) == 0:
            return 0.0
        return float(np.min(-self.equations[:, -1]))


def full_rank(W: np.ndarray) -> bool:
    """rank(W) = 6 (σ_6 > RANK_REL_TOL · σ_1) of finite wrenches W (M ≥ 7, 6)."""
    if W.ndim != 2 or W.shape[1] != 6 or len(W) < 7 or not np.all(np.isfinite(W)):
        return False
    s = np.linalg.svd(W, compute_uv=False)
    return bool(s[0] > 0 and s[5] > RANK_REL_TOL * s[0])


def wrench_hull(W: np.ndarray) -> WrenchSpace:
    """Hull of wrenches ``W`` (M, 6) (see the module docstring)."""
    W = np.asarray(W, float).reshape(-1, 6)
    empty = WrenchSpace(W, np.zeros((0, 7)), 0.0)
    if not full_rank(W):
        return empty
    for options in (None, "QJ"):
        try:
            hull = ConvexHull(W, qhull_options=options)
        except (QhullError, ValueError):
            continue
        return WrenchSpace(W, hull.equations, float(hull.volume))
    return empty


def grasp_wrench_space(
    p: np.ndarray, n: np.ndarray, centroid: np.ndarray, r: float, mu: float, n_edges: int
) -> WrenchSpace:
    """Hull of the primitive wrenches of contacts ``p``, ``n`` (K, 3) (object frame, mm)."""
    if len(p) == 0:
        return WrenchSpace(np.zeros((0, 6)), np.zeros((0, 7)), 0.0)
    return wrench_hull(primitive_wrenches(p, n, centroid, r, mu, n_edges))
