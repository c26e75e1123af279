"""Q_C2, volume of the grasp wrench space (R&S §C.2, Miller & Allen 1999).

    Q_C2 = vol₆(conv(W))

the 6-D volume of the hull of the primitive wrenches (``app.gqm.wrench_space``, unit
normal force per cone edge, torques divided by r). Larger is better; 0 when W does not
span R⁶. Dimensionless, not normalised.
"""

from __future__ import annotations

from app.gqm.wrench_space import WrenchSpace


def q_c2(ws: WrenchSpace) -> float:
    """6-D hull volume of a grasp wrench space."""
    return ws.volume
