"""Q_C2, volume of the grasp wrench space (R&S §C.2, Miller & Allen 1999).

    Q_C2 = vol₆(conv(W_link))

the 6-D volume of the hull of the primitive wrenches (``app.quality.gqm.wrench_space``, unit
normal force per cone edge, torques divided by r) of ONE contact per contacting link (patch
centroid, mean normal: ``app.quality.gqm.contacts``), whatever ``GQMSettings.wrench_contacts`` says.
Larger is better; 0 when W does not span R⁶ (fewer than two touching links, or all of them
collinear with their cones). Dimensionless, not normalised.

Decision (GQM_VERSION 2; version 1 used every patch point): the per-link model is the
contact model of the grasp-matrix measures (Q_A*, Q_B*, Q_D2) and of GraspIt!-style contact
lists, and its hull costs 13–23 ms, where the full-patch volume (250–700 wrenches, 30,000+
facets) costs 0.2–0.65 s per grasp: nearly all of the stage, and unlike ε (``app.quality.gqm.c1``)
a volume needs every facet. ``docs/bruteforce.md`` gives the rank correlation of the two.
"""

from __future__ import annotations

from app.quality.gqm.wrench_space import WrenchSpace


def q_c2(ws: WrenchSpace) -> float:
    """6-D hull volume of a grasp wrench space (build it on per-link contacts)."""
    return ws.volume
