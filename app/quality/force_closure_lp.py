"""Independent force-closure and ε checks (LP and QP), used by the tests of ``force_closure``.

None of this uses qhull, so it cross-checks ``app.quality.force_closure`` by other mathematics:

* **FC by LP** (``scipy.optimize.linprog``, HiGHS). With ``W`` (M, 6) the primitive
  wrenches, solve

      t* = max t   s.t.   Wᵀ λ = 0,   Σ λ_i = 1,   λ_i ≥ t.

  ``t* > 0`` means the origin is a strictly positive convex combination of ALL the points,
  i.e. it lies in the relative interior of conv(W); with rank(W) = 6 the relative interior
  is the interior. So FC ⟺ rank(W) = 6 (``np.linalg.matrix_rank``) and ``t* > tol``.
  (Conversely, an interior origin is always such a combination, so the test is exact.)

* **Support function** ``h(u) = max_i W_i · u`` for unit ``u``. For an FC set,
  ``ε = min_{|u|=1} h(u)``: every direction gives an upper bound ``h(u) ≥ ε``, and the
  minimising facet normal attains it.

* **Minimum-norm point by QP** (osqp): the distance from a point ``x`` to conv(W),

      min ½ |y − x|²   s.t.   y = Wᵀ λ,   Σ λ = 1,   λ ≥ 0,

  over (λ, y). For a non-FC set of full rank, the origin's distance is > 0 when it lies
  outside the hull (exactly 0 only when it is on the boundary). For an FC set, the point
  ``(1 + δ) ε u*`` (``u*`` the hull's closest facet normal) is outside (distance > 0), and
  ``(1 − δ) ε u`` is inside (distance ≈ 0) for any unit ``u``: ε is the inscribed radius.
"""

from __future__ import annotations

import numpy as np
import osqp
import scipy.sparse as sp
from scipy.optimize import linprog

#: Matrix-rank tolerance relative to σ_1 (independent of force_closure.RANK_REL_TOL's code).
LP_RANK_REL_TOL = 1e-9
#: FC needs t* > LP_T_TOL (t* is a convex weight, dimensionless).
LP_T_TOL = 1e-9


def lp_margin(W: np.ndarray) -> float:
    """``t* = max t s.t. Wᵀλ = 0, Σλ = 1, λ_i ≥ t`` (the smallest weight, maximised).

    Args:
        W: (M, 6) wrenches.

    Returns:
        t* (≤ 1/M); ``-inf`` when infeasible (the origin is outside conv(W)).
    """
    W = np.asarray(W, dtype=float)
    m = W.shape[0]
    # variables x = [λ (M), t]; minimise −t
    c = np.zeros(m + 1)
    c[-1] = -1.0
    A_eq = np.zeros((7, m + 1))
    A_eq[:6, :m] = W.T
    A_eq[6, :m] = 1.0
    b_eq = np.zeros(7)
    b_eq[6] = 1.0
    # λ_i − t ≥ 0  →  −λ_i + t ≤ 0
    A_ub = np.hstack([-np.eye(m), np.ones((m, 1))])
    b_ub = np.zeros(m)
    bounds = [(0.0, None)] * m + [(None, None)]
    res = linprog(c, A_ub=A_ub, b_ub=b_ub, A_eq=A_eq, b_eq=b_eq, bounds=bounds, method="highs")
    if res.status == 2:  # infeasible
        return float("-inf")
    if res.status != 0:
        raise RuntimeError(f"linprog failed: {res.message}")
    return float(res.x[-1])


def is_force_closure_lp(W: np.ndarray) -> bool:
    """FC by LP: rank(W) = 6 and ``lp_margin(W) > LP_T_TOL``. W (M, 6)."""
    W = np.asarray(W, dtype=float)
    if W.ndim != 2 or W.shape[1] != 6 or W.shape[0] < 7:
        return False
    s = np.linalg.svd(W, compute_uv=False)
    if np.linalg.matrix_rank(W, tol=LP_RANK_REL_TOL * s[0]) < 6:
        return False
    return lp_margin(W) > LP_T_TOL


def support(W: np.ndarray, U: np.ndarray) -> np.ndarray:
    """Support function ``h(u) = max_i W_i · u``.

    Args:
        W: (M, 6) wrenches.
        U: (D, 6) directions (normalised here).

    Returns:
        (D,) support values.
    """
    U = np.asarray(U, dtype=float).reshape(-1, 6)
    U = U / np.linalg.norm(U, axis=1, keepdims=True)
    return np.max(U @ np.asarray(W, dtype=float).T, axis=1)


def distance_to_hull(W: np.ndarray, x: np.ndarray | None = None) -> tuple[float, np.ndarray]:
    """Euclidean distance from ``x`` (default the origin) to conv(W), by QP (osqp).

    ``min ½|y − x|² s.t. y − Wᵀλ = 0, Σλ = 1, λ ≥ 0`` over ``z = [λ (M), y (6)]``.

    Args:
        W: (M, 6) wrenches.
        x: (6,) query point.

    Returns:
        (distance, y): the distance and the closest point y (6,) of conv(W).
    """
    W = np.asarray(W, dtype=float)
    m = W.shape[0]
    x = np.zeros(6) if x is None else np.asarray(x, dtype=float).reshape(6)
    P = sp.block_diag([sp.csc_matrix((m, m)), sp.eye(6)], format="csc")
    q = np.concatenate([np.zeros(m), -x])
    A = sp.vstack(
        [
            sp.hstack([-sp.csc_matrix(W.T), sp.eye(6)]),  # y − Wᵀλ = 0
            sp.hstack([sp.csc_matrix(np.ones((1, m))), sp.csc_matrix((1, 6))]),  # Σλ = 1
            sp.hstack([sp.eye(m), sp.csc_matrix((m, 6))]),  # λ ≥ 0
        ],
        format="csc",
    )
    lo = np.concatenate([np.zeros(6), [1.0], np.zeros(m)])
    hi = np.concatenate([np.zeros(6), [1.0], np.full(m, np.inf)])
    prob = osqp.OSQP()
    prob.setup(
        P,
        q,
        A,
        lo,
        hi,
        eps_abs=1e-10,
        eps_rel=1e-10,
        max_iter=200_000,
        polishing=True,
        verbose=False,
    )
    res = prob.solve(raise_error=False)
    if not str(res.info.status).lower().startswith("solved"):
        raise RuntimeError(f"osqp failed: {res.info.status}")
    z = np.asarray(res.x, dtype=float)
    lam = np.clip(z[:m], 0.0, None)
    lam /= lam.sum()
    y = W.T @ lam  # an exactly feasible hull point from the QP weights
    return float(np.linalg.norm(y - x)), y
