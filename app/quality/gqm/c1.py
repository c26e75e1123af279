"""Q_C1, the largest minimum resisted wrench ε (Ferrari & Canny 1992; R&S §C.1).

    Q_C1 = ε = min_k (−b_k)  over the facets a_k·x + b_k ≤ 0 (|a_k| = 1) of conv(W)

the radius of the largest origin-centred ball inside the hull of the primitive wrenches W
of every contact-patch point (``GQMSettings.wrench_contacts = "patch"``, default, METHOD §5's
force-closure model; ``"link"``: one contact per link): the smallest wrench, over all
directions, the grasp resists with a total normal contact force of 1 (L1 form; torques
divided by the object radius r). Larger is better; ≤ 0 when the grasp is not force closure
under the chosen contact points (clipped to 0 here). Dimensionless.

Computed exactly without the full hull (``app.quality.gqm.epsilon``: a small hull of extreme
wrenches grown until its nearest facet supports conv(W); 4–10 ms instead of 0.2–0.65 s per
brute-force grasp, the full-hull value to ≤ 2e-13 relative).
"""

from __future__ import annotations

import numpy as np

from app.quality.gqm.epsilon import epsilon


def q_c1(W: np.ndarray) -> float:
    """max(ε, 0) of the primitive wrenches W (M, 6)."""
    return max(epsilon(W), 0.0)
