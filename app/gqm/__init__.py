"""The ten grasp quality measures (GQMs) of Roa & Suárez (2014) used by METHOD §6.

Every measure is a score, larger is better (each module's docstring gives its formula and
normalisation):

=====  ===============================================  ==========  ===================
name   measure                                          module      range / unit
=====  ===============================================  ==========  ===================
Q_A1   minimum singular value of G                      ``a1``      ≥ 0
Q_A2   volume of the G ellipsoid, Π σ_i                 ``a2``      ≥ 0
Q_A3   isotropy σ_min/σ_max of G                        ``a3``      [0, 1]
Q_B1   contact centroid near the centre of mass         ``b1``      [0, 1]
Q_B2   area of the grasp polygon                        ``b2``      mm²
Q_B3   regularity of the grasp polygon                  ``b3``      [0, 1]
Q_C1   Ferrari–Canny ε                                  ``c1``      ≥ 0
Q_C2   volume of the grasp wrench space                 ``c2``      ≥ 0
Q_D1   finger joints near mid-range                     ``d1``      [0, 1]
Q_D2   uniformity of transformation of H = (Gᵀ)⁺ J_h    ``d2``      [0, 1]
=====  ===============================================  ==========  ===================

Contact model: hard-finger point contacts, one per contacting link (``contacts``: patch
centroid, mean normal) for G, the polygon and J_h; every patch point for the wrench space
by default (``GQMSettings.wrench_contacts``). G maps contact forces (3 per contact) to
object wrenches ``[f; (p − c) × f / r]``, c the object's centroid, r its largest radius.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Literal, Protocol

import numpy as np

from app.contact_set import ContactSet
from app.gqm.a1 import q_a1
from app.gqm.a2 import q_a2
from app.gqm.a3 import q_a3
from app.gqm.b1 import q_b1
from app.gqm.b2 import q_b2
from app.gqm.b3 import q_b3
from app.gqm.c1 import q_c1
from app.gqm.c2 import q_c2
from app.gqm.contacts import LinkContacts, link_contacts
from app.gqm.d1 import q_d1
from app.gqm.d2 import q_d2
from app.gqm.grasp_matrix import grasp_matrix, grasp_singular_values
from app.gqm.hand_jacobian import hand_jacobian
from app.gqm.wrench_space import WrenchSpace, grasp_wrench_space
from app.store import stable_hash

#: The ten measures, in table order.
GQM_NAMES: tuple[str, ...] = (
    "Q_A1", "Q_A2", "Q_A3", "Q_B1", "Q_B2", "Q_B3", "Q_C1", "Q_C2", "Q_D1", "Q_D2",
)  # fmt: skip

#: Version of the GQMs' definitions and code: part of ``GQMSettings.key()``, so stored
#: values (``ResultStore.put_gqms``) are recomputed when a measure changes. Bump it with any
#: change of a value beyond floating-point noise.
GQM_VERSION = 1


@dataclass(frozen=True)
class GQMSettings:
    """Contact model of the GQMs."""

    mu: float = 0.4
    """Coulomb friction of the wrench space (METHOD §5)."""
    n_edges: int = 8
    """Edges per linearised friction cone."""
    wrench_contacts: Literal["patch", "link"] = "patch"
    """Wrench-space contact points: every patch point (the FC model) or one per link."""
    posture_joints: tuple[int, ...] = tuple(range(15))
    """Joint indices of Q_D1 (the closing joints: all of them in the brute-force set)."""

    def key(self) -> str:
        """Store key of these settings and ``GQM_VERSION`` (``ResultStore.put_gqms``)."""
        return stable_hash({"gqm_version": GQM_VERSION, **asdict(self)})


class GraspLike(Protocol):
    """What the GQMs need of a grasp (``app.simulate.Grasp`` has it)."""

    q: np.ndarray
    T_object_palm: np.ndarray
    contacts: ContactSet


def compute_gqms(
    grasp: GraspLike, obj: object, hand: object, settings: GQMSettings | None = None
) -> dict[str, float]:
    """The ten GQMs of one grasp of ``obj`` (a ``GraspObject``) by ``hand`` (a ``Hand``)."""
    s = settings or GQMSettings()
    c = np.asarray(obj.centroid_object, float)  # type: ignore[attr-defined]
    r = float(obj.max_radius)  # type: ignore[attr-defined]
    lc = link_contacts(grasp.contacts)
    sv = grasp_singular_values(lc.p, c, r)
    ws = wrench_space_of(grasp.contacts, lc, c, r, s)
    G = grasp_matrix(lc.p, c, r)
    J = hand_jacobian(hand, grasp.q, grasp.T_object_palm, lc.links, lc.p)
    return {
        "Q_A1": q_a1(sv),
        "Q_A2": q_a2(sv),
        "Q_A3": q_a3(sv),
        "Q_B1": q_b1(lc.p, c, r),
        "Q_B2": q_b2(lc.p),
        "Q_B3": q_b3(lc.p),
        "Q_C1": q_c1(ws),
        "Q_C2": q_c2(ws),
        "Q_D1": q_d1(grasp.q, hand.q_lower, hand.q_upper, s.posture_joints),  # type: ignore[attr-defined]
        "Q_D2": q_d2(G, J),
    }


def wrench_space_of(
    contacts: ContactSet, lc: LinkContacts, c: np.ndarray, r: float, s: GQMSettings
) -> WrenchSpace:
    """The grasp wrench space under ``s.wrench_contacts``."""
    if s.wrench_contacts == "link":
        return grasp_wrench_space(lc.p, lc.n, c, r, s.mu, s.n_edges)
    return grasp_wrench_space(
        np.asarray(contacts.p_object, float), np.asarray(contacts.n_object, float), c, r,
        s.mu, s.n_edges,
    )  # fmt: skip


__all__ = [
    "GQM_NAMES",
    "GQM_VERSION",
    "GQMSettings",
    "GraspLike",
    "compute_gqms",
    "wrench_space_of",
]
