"""The contacts of one grasp: points, normals, the link each lies on, palmar or not."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

#: Link names. A link's finger is the part before the first underscore ("palm" is its own).
LONG_FINGERS = ("index", "middle", "ring", "little")
THUMB_LINKS = ("thumb_metacarpal", "thumb_proximal", "thumb_distal")
PHALANGES = ("proximal", "middle", "distal")
LINK_NAMES = ("palm",) + THUMB_LINKS + tuple(f"{f}_{p}" for f in LONG_FINGERS for p in PHALANGES)


def finger_of(link: str) -> str:
    """'index_distal' -> 'index', 'thumb_proximal' -> 'thumb', 'palm' -> 'palm'."""
    return link.split("_", 1)[0]


@dataclass(frozen=True)
class ContactSet:
    """Contact points of one grasp, expressed in the object frame (mm).

    K contact points; a link touching along a line or an area contributes several points
    (a contact patch).
    """

    p_object: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    """(K, 3) contact points on the link surface, object frame, mm."""
    n_object: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    """(K, 3) unit contact normals pointing from the link toward (into) the object."""
    link: np.ndarray = field(default_factory=lambda: np.zeros((0,), dtype=object))
    """(K,) link name of each point, one of ``LINK_NAMES``."""
    palmar: np.ndarray = field(default_factory=lambda: np.zeros((0,), dtype=bool))
    """(K,) True where the angle between the contact normal and the link's n_palmar < 75°."""

    def __post_init__(self) -> None:
        k = len(self.p_object)
        assert self.p_object.shape == (k, 3), self.p_object.shape
        assert self.n_object.shape == (k, 3), self.n_object.shape
        assert self.link.shape == (k,) and self.palmar.shape == (k,)

    def __len__(self) -> int:
        return len(self.p_object)

    @property
    def links(self) -> set[str]:
        """Names of the links with at least one contact point."""
        return set(map(str, set(self.link.tolist())))

    def palmar_links(self) -> set[str]:
        """Names of the links with at least one palmar contact point."""
        return set(map(str, set(self.link[self.palmar.astype(bool)].tolist())))

    def transformed(self, T_new_object: np.ndarray) -> ContactSet:
        """The same contacts expressed in another frame (rigid motion ``T_new_object``)."""
        R, t = T_new_object[:3, :3], T_new_object[:3, 3]
        return ContactSet(self.p_object @ R.T + t, self.n_object @ R.T, self.link, self.palmar)
