"""Exact Ferrari–Canny ε of a wrench set without its full hull (Q_C1, ``app.quality.gqm.c1``).

ε(W) of primitive wrenches W (M, 6) is the smallest distance from the origin to a facet
hyperplane of conv(W) (``app.quality.gqm.wrench_space``, ``app.quality.force_closure``).
Equivalently, when the origin is strictly inside conv(W), with the support function
h_W(u) = max_{w∈W} u·w,

    ε(W) = min over unit u of h_W(u)                                                    (1)

(the radius of the largest origin-centred ball in conv(W): the ball of radius ρ lies in
conv(W) iff ρ ≤ h_W(u) for every unit u, and the minimum of h_W over the sphere is attained
at a facet normal, where it is that facet's distance).

The full 6-D hull of 250–700 patch wrenches has 30,000–50,000 facets and costs 0.2–0.65 s;
the facet nearest the origin is found here from hulls of a few dozen wrenches instead:

1. S = the wrenches extreme along ±e_1…±e_6 (and ``n_dirs`` fixed pseudo-random
   directions; none by default: a larger first S only makes every sub-hull dearer).
2. H = conv(S) (qhull, the options of ``wrench_hull``: scipy's default ``Qx``, input used
   exactly); if qhull fails on S (fewer than 7 or affinely dependent wrenches, a precision
   error), the extremes along 16 more pseudo-random directions join S and 2 is repeated. Its
   facets ``a_k·x + b_k ≤ 0`` (|a_k| = 1) have distances d_k = −b_k; F is
   the nearest one, d_F = min_k d_k = ε(S).
3. If no wrench of W lies beyond F's hyperplane by more than ``tol`` (= 1e-12 · max|W|),
   stop: ε(W) = d_F. Otherwise add, for each of the ``per_round`` nearest facets of H with
   a wrench beyond it, the wrench farthest beyond it, and go to 2.

Exactness. S ⊆ W, so H ⊆ conv(W). (a) If d_F > 0, the origin is strictly inside H and, by
(1) for H, the ball of radius d_F lies in H ⊆ conv(W): ε(W) ≥ d_F. (b) If no wrench of W is
beyond F's hyperplane by more than tol, h_W(a_F) ≤ d_F + tol: that hyperplane (moved out by
at most tol) supports conv(W), and by (1) ε(W) ≤ h_W(a_F) ≤ d_F + tol. So at the stop
d_F ≤ ε(W) ≤ d_F + tol (≤ 1e-12 · max|W| apart). Testing F alone is enough, H's other facets
need no check: every facet of conv(W) is at h_W(its normal) ≥ ε(W) ≥ d_F by (a), so none is
nearer than F; and a facet G of H nearer than ε(W) (possible in early rounds, never at the
stop, where F is H's nearest) always has a wrench of W beyond it, else (b) applied to G
would give ε(W) ≤ d_G < ε(W) (``tests/test_gqm.py`` checks this on sub-hulls). Ties
(several facets at d_F) need nothing either: (b) uses F alone. The loop ends: every round
adds at least one wrench not yet in S (a wrench beyond a facet of H by more than tol is not
in H), so after at most M rounds S = W and (b) holds.

Where the argument does not apply, the value comes from the full hull (``wrench_hull``)
so that it is IDENTICAL to what ``WrenchSpace.epsilon`` gives:

- rank(W) < 6 (or fewer than 7 wrenches, non-finite values): ε = 0, like ``wrench_hull``;
- the loop ends with d_F ≤ tol: the origin is not strictly inside conv(W) (or is within tol
  of its boundary), and ε ≤ 0 there is the full hull's most negative facet distance, which
  (1) does not give;
- a round adds no new wrench (rounding, or a qhull error that more directions did not
  cure), or ``max_rounds`` is reached.

On a full set where plain qhull raises a precision error, ``wrench_hull`` falls back to a
joggled hull (``QJ``, ε ~1e-8 relative off); the grown ε avoids that when its sub-hulls are
regular, and is then the more exact value. Cost (``benchmarks/bench_gqm.py``, defaults):
4–10 ms per brute-force grasp on average (25–31 of 290–460 wrenches used), against
0.2–0.65 s for the full hull; ε equal to the full hull's to ≤ 2e-13 relative.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from scipy.spatial import ConvexHull, QhullError

from app.quality.gqm.wrench_space import full_rank, wrench_hull

#: How ``grown_epsilon`` found its value.
EpsilonMethod = Literal["grown", "full hull", "degenerate"]

#: A wrench is beyond a facet when a·w + b > TOL_REL · max|W|.
TOL_REL = 1e-12


@dataclass(frozen=True)
class GrownEpsilon:
    """Ferrari–Canny ε of a wrench set and how it was found."""

    epsilon: float
    """ε(W): > 0 iff the origin is strictly inside conv(W); ≤ 0 otherwise (the full hull's
    value); 0 when rank(W) < 6."""
    method: EpsilonMethod
    """'grown' (a sub-hull's nearest facet supports conv(W)), 'full hull' (the fallback:
    origin not strictly inside, a qhull error on a sub-hull), or 'degenerate' (rank < 6)."""
    n_used: int
    """Wrenches in the last sub-hull ('grown'), len(W) otherwise."""
    rounds: int
    """Sub-hulls built (0 for 'degenerate')."""


def grown_epsilon(
    W: np.ndarray, n_dirs: int = 0, per_round: int = 8, max_rounds: int = 1000
) -> GrownEpsilon:
    """Exact ε of conv(W), W (M, 6), by a growing sub-hull (see the module docstring).

    Args:
        W: (M, 6) primitive wrenches.
        n_dirs: pseudo-random directions of the first sub-hull besides ±e_i.
        per_round: nearest facets of a sub-hull whose farthest wrench beyond is added.
        max_rounds: sub-hulls built at most before falling back to the full hull.
    """
    W = np.asarray(W, float).reshape(-1, 6)
    if not full_rank(W):
        return GrownEpsilon(0.0, "degenerate", len(W), 0)

    def full(rounds: int) -> GrownEpsilon:
        return GrownEpsilon(wrench_hull(W).epsilon, "full hull", len(W), rounds)

    rng = np.random.default_rng(0)
    dirs = np.vstack([np.eye(6), -np.eye(6), rng.normal(size=(n_dirs, 6))])
    idx = np.unique(np.argmax(W @ dirs.T, axis=0))
    tol = TOL_REL * float(np.max(np.abs(W)))
    for rounds in range(1, max_rounds + 1):
        try:
            eq = ConvexHull(W[idx]).equations
        except (QhullError, ValueError):  # S too small or flat: more extremes
            new = np.setdiff1d(np.argmax(W @ rng.normal(size=(6, 16)), axis=0), idx)
            if len(new) == 0:
                return full(rounds)
            idx = np.union1d(idx, new)
            continue
        d = -eq[:, -1]
        near = np.argsort(d, kind="stable")[:per_round]
        S = W @ eq[near, :6].T  # (M, k): a_k · w
        excess = S.max(axis=0) - d[near]  # how far the farthest wrench is beyond each facet
        if excess[0] <= tol:  # the nearest facet supports conv(W) (the docstring's (b))
            d_f = float(d[near[0]])
            if d_f > tol:  # ... and the origin is strictly inside (a)
                return GrownEpsilon(d_f, "grown", len(idx), rounds)
            return full(rounds)
        new = np.setdiff1d(np.argmax(S[:, excess > tol], axis=0), idx)
        if len(new) == 0:
            return full(rounds)
        idx = np.union1d(idx, new)
    return full(max_rounds)


def epsilon(W: np.ndarray) -> float:
    """Ferrari–Canny ε of conv(W) (``grown_epsilon(W).epsilon``); ≤ 0 when not force closure."""
    return grown_epsilon(W).epsilon


__all__ = ["TOL_REL", "EpsilonMethod", "GrownEpsilon", "epsilon", "grown_epsilon"]
