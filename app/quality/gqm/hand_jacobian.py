"""The hand Jacobian J_h of the contact points (for Q_D2).

For L contacts (one per contacting link, ``app.quality.gqm.contacts``) at points p_l (object frame),
J_h (3L, n_q) maps joint velocities q̇ (rad/s) to the contact points' velocities (mm/s) as
points fixed to their links, expressed in the object frame:

    ṗ_l = R_object_palm (J_v,l − [p̃_l − o_l]× J_ω,l) q̇

with p̃_l = T_palm_object p_l, and (J_v,l; J_ω,l) (6, n_q) the Pinocchio Jacobian of the
link's joint frame at its origin o_l, in palm-aligned axes (``LOCAL_WORLD_ALIGNED``; the
palm frame is the model's world). Palm contacts have zero rows (the palm does not move).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from app.model.hand.model import Hand
from app.quality.gqm.grasp_matrix import skew


def hand_jacobian(
    hand: Hand,
    q: np.ndarray,
    T_object_palm: np.ndarray,
    links: Sequence[str],
    p_object: np.ndarray,
) -> np.ndarray:
    """J_h (3L, n_q) of contact points ``p_object`` (L, 3) on ``links`` (L,) of a ``Hand``."""
    model = hand.model
    data = model.createData()
    q = np.asarray(q, float)
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    T = np.asarray(T_object_palm, float)
    R, t = T[:3, :3], T[:3, 3]
    p_palm = (np.asarray(p_object, float).reshape(-1, 3) - t) @ R  # R^T (p - t)
    J = np.zeros((3 * len(links), model.nv))
    for k, name in enumerate(links):
        link = hand.links[hand.link_index[name]]
        jid = link.pin_joint_id
        if jid == 0:
            continue  # the palm is the fixed base
        J6 = pin.getJointJacobian(model, data, jid, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
        o = data.oMi[jid].translation
        Jp = J6[:3] - skew(p_palm[k] - o) @ J6[3:]
        J[3 * k : 3 * k + 3] = R @ Jp
    return J
