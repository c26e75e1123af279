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
Q_C1   Ferrari–Canny ε (every patch point)              ``c1``      ≥ 0
Q_C2   volume of the grasp wrench space (per link)      ``c2``      ≥ 0
Q_D1   finger joints near mid-range                     ``d1``      [0, 1]
Q_D2   uniformity of transformation of H = (Gᵀ)⁺ J_h    ``d2``      [0, 1]
=====  ===============================================  ==========  ===================

Contact model: hard-finger point contacts, one per contacting link (``contacts``: patch
centroid, mean normal) for G, the polygon, J_h and the wrench-space volume Q_C2; every
patch point for ε, Q_C1 (METHOD §5's force-closure model; ``GQMSettings.wrench_contacts``
selects Q_C1's contacts, and only Q_C1's). G maps contact forces (3 per contact) to object
wrenches ``[f; (p − c) × f / r]``, c the object's centroid, r its largest radius.

Why Q_C1 and Q_C2 use different contact points (GQM_VERSION 2): version 1 built one 6-D
hull of the primitive wrenches of every patch point (250–700 wrenches) for both, 0.2–0.65 s
per grasp, ~99 % of the stage. ε needs only the hull's nearest facet, found exactly from a
small growing hull (``app.quality.gqm.epsilon``, 4–10 ms); the volume needs every facet, so Q_C2
uses the per-link contacts of the grasp-matrix measures (and of GraspIt!-style contact
lists), whose hull costs 13–23 ms. ``docs/bruteforce.md`` has the measurements.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Literal, Protocol

import numpy as np

from app.hashing import stable_hash
from app.model.contact_set import ContactSet
from app.model.hand.model import Hand
from app.model.target import RigidBody
from app.quality.force_closure import primitive_wrenches
from app.quality.gqm.a1 import q_a1
from app.quality.gqm.a2 import q_a2
from app.quality.gqm.a3 import q_a3
from app.quality.gqm.b1 import q_b1
from app.quality.gqm.b2 import q_b2
from app.quality.gqm.b3 import q_b3
from app.quality.gqm.c1 import q_c1
from app.quality.gqm.c2 import q_c2
from app.quality.gqm.contacts import LinkContacts, link_contacts
from app.quality.gqm.d1 import q_d1
from app.quality.gqm.d2 import q_d2
from app.quality.gqm.grasp_matrix import grasp_matrix, grasp_singular_values
from app.quality.gqm.hand_jacobian import hand_jacobian
from app.quality.gqm.wrench_space import WrenchSpace, grasp_wrench_space

#: The ten measures, in table order.
GQM_NAMES: tuple[str, ...] = (
    "Q_A1", "Q_A2", "Q_A3", "Q_B1", "Q_B2", "Q_B3", "Q_C1", "Q_C2", "Q_D1", "Q_D2",
)  # fmt: skip

#: Version of the GQMs' definitions and code: part of ``GQMSettings.key()``, so stored
#: values (``ResultStore.put_gqms``) are recomputed when a measure changes. Bump it with any
#: change of a value beyond floating-point noise. 1: Q_C1 and Q_C2 on one full hull of every
#: patch point; 2: Q_C1 by the grown hull (``app.quality.gqm.epsilon``: the same ε to ~1e-13, except
#: where the full hull needed ``QJ``), Q_C2 on per-link contacts.
GQM_VERSION = 2


@dataclass(frozen=True)
class GQMSettings:
    """Contact model of the GQMs."""

    mu: float = 0.4
    """Coulomb friction of the wrench space (METHOD §5)."""
    n_edges: int = 8
    """Edges per linearised friction cone."""
    wrench_contacts: Literal["patch", "link"] = "patch"
    """Q_C1's contact points: every patch point (the FC model) or one per link. Q_C2 always
    uses one per link (see the module docstring)."""
    posture_joints: tuple[int, ...] = tuple(range(15))
    """Joint indices of Q_D1 (the closing joints: all of them in the brute-force set)."""

    def key(self) -> str:
        """Store key of these settings and ``GQM_VERSION`` (``ResultStore.put_gqms``)."""
        return stable_hash({"gqm_version": GQM_VERSION, **asdict(self)})


class GraspLike(Protocol):
    """What the GQMs need of a grasp (``app.sim.simulate.Grasp`` has it)."""

    q: np.ndarray
    T_object_palm: np.ndarray
    contacts: ContactSet


def compute_gqms(
    grasp: GraspLike, obj: RigidBody, hand: Hand, settings: GQMSettings | None = None
) -> dict[str, float]:
    """The ten GQMs of one grasp of ``obj`` (a ``GraspObject``) by ``hand`` (a ``Hand``)."""
    s = settings or GQMSettings()
    c = np.asarray(obj.centroid_object, float)
    r = float(obj.max_radius)
    lc = link_contacts(grasp.contacts)
    sv = grasp_singular_values(lc.p, c, r)
    q_c1_value, q_c2_value = wrench_measures(grasp.contacts, lc, c, r, s)
    G = grasp_matrix(lc.p, c, r)
    J = hand_jacobian(hand, grasp.q, grasp.T_object_palm, lc.links, lc.p)
    return {
        "Q_A1": q_a1(sv),
        "Q_A2": q_a2(sv),
        "Q_A3": q_a3(sv),
        "Q_B1": q_b1(lc.p, c, r),
        "Q_B2": q_b2(lc.p),
        "Q_B3": q_b3(lc.p),
        "Q_C1": q_c1_value,
        "Q_C2": q_c2_value,
        "Q_D1": q_d1(grasp.q, hand.q_lower, hand.q_upper, s.posture_joints),
        "Q_D2": q_d2(G, J),
    }


def epsilon_wrenches(
    contacts: ContactSet, lc: LinkContacts, c: np.ndarray, r: float, s: GQMSettings
) -> np.ndarray:
    """Q_C1's primitive wrenches (M, 6) under ``s.wrench_contacts``."""
    if s.wrench_contacts == "link":
        return primitive_wrenches(lc.p, lc.n, c, r, s.mu, s.n_edges)
    p, n = np.asarray(contacts.p_object, float), np.asarray(contacts.n_object, float)
    if len(p) == 0:
        return np.zeros((0, 6))
    return primitive_wrenches(p, n, c, r, s.mu, s.n_edges)


def volume_wrench_space(lc: LinkContacts, c: np.ndarray, r: float, s: GQMSettings) -> WrenchSpace:
    """Q_C2's wrench space: the hull of the per-link contacts' primitive wrenches."""
    return grasp_wrench_space(lc.p, lc.n, c, r, s.mu, s.n_edges)


def wrench_measures(
    contacts: ContactSet, lc: LinkContacts, c: np.ndarray, r: float, s: GQMSettings
) -> tuple[float, float]:
    """(Q_C1, Q_C2) of one grasp (see the module docstring for their contact models)."""
    return q_c1(epsilon_wrenches(contacts, lc, c, r, s)), q_c2(volume_wrench_space(lc, c, r, s))


__all__ = [
    "GQM_NAMES",
    "GQM_VERSION",
    "GQMSettings",
    "GraspLike",
    "compute_gqms",
    "epsilon_wrenches",
    "volume_wrench_space",
    "wrench_measures",
]
