"""Q_C1, the largest minimum resisted wrench ε (Ferrari & Canny 1992; R&S §C.1).

    Q_C1 = ε = min_k (−b_k)  over the facets a_k·x + b_k ≤ 0 (|a_k| = 1) of conv(W)

the radius of the largest origin-centred ball inside the hull of the primitive wrenches
(``app.gqm.wrench_space``): the smallest wrench, over all directions, the grasp resists
with a total normal contact force of 1 (L1 form; torques divided by the object radius r).
Larger is better; ≤ 0 when the grasp is not force closure under the chosen contact points
(clipped to 0 here). Dimensionless.
"""

from __future__ import annotations

from app.gqm.wrench_space import WrenchSpace


def q_c1(ws: WrenchSpace) -> float:
    """max(ε, 0) of a grasp wrench space."""
    return max(ws.epsilon, 0.0)
