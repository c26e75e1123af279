"""The GQMs' contact model: one hard-finger contact per contacting link.

A link touching the object along a line or an area yields a patch of K_l points
(``ContactSet``); the grasp-matrix measures (Q_A*, Q_B*, Q_D2) reduce it to one contact:

    p_l = mean of the patch points,   n_l = normalised mean of the patch normals.

So does the wrench-space volume Q_C2; ε, Q_C1, keeps every patch point by default (METHOD
§5's force-closure model), see ``app.quality.gqm`` and ``app.quality.gqm.epsilon``.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from app.model.contact_set import LINK_NAMES, ContactSet


class LinkContacts(NamedTuple):
    """One contact per contacting link, in ``LINK_NAMES`` order."""

    links: tuple[str, ...]
    """(L,) link names."""
    p: np.ndarray
    """(L, 3) patch centroids, object frame, mm."""
    n: np.ndarray
    """(L, 3) unit mean normals (link → object)."""


def link_contacts(contacts: ContactSet) -> LinkContacts:
    """Reduce a contact set to one contact per link (see the module docstring)."""
    names = np.asarray([str(s) for s in contacts.link], dtype=object)
    links = tuple(n for n in LINK_NAMES if np.any(names == n))
    p = np.zeros((len(links), 3))
    n = np.zeros((len(links), 3))
    for i, name in enumerate(links):
        m = names == name
        p[i] = np.asarray(contacts.p_object, float)[m].mean(axis=0)
        nn = np.asarray(contacts.n_object, float)[m].mean(axis=0)
        norm = np.linalg.norm(nn)
        n[i] = nn / norm if norm > 1e-12 else nn
    return LinkContacts(links, p, n)
