"""Grasp-type correctness of a grasp: pulp pinch (PP) and cylindrical grip (CG), METHOD §5.

Palmar contact: a contact point of a link is palmar when the angle between its contact
normal ``n_contact`` (from the link into the object) and the link's ``n_palmar`` is below
``palmar_angle_deg``:  ``n̂_contact · n̂_palmar > cos(palmar_angle_deg)``.

PP correct: palmar contacts on the thumb distal phalanx and on the distal phalanx of exactly
one long finger, and no contact (palmar or not) with the palm.

CG correct: the line angle between the thumb's n_main and the object's grip axis,
``arccos |n̂_main · â|`` ∈ [0°, 90°], is greater than ``cg_thumb_axis_min_angle_deg``; palmar
contacts on the thumb (any thumb link); palmar contacts on at least
``cg_min_phalanges_per_finger`` distinct phalanges of each of at least
``cg_min_long_fingers`` long fingers; a palmar contact on the palm.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import NamedTuple

import numpy as np
import numpy.typing as npt

from app.errors import SettingsError
from app.model.contact_set import LONG_FINGERS, PHALANGES, THUMB_LINKS, ContactSet

GRASP_TYPES: tuple[str, ...] = ("PP", "CG")

_WORDS = {0: "no", 1: "one", 2: "two", 3: "three", 4: "four"}


@dataclass(frozen=True)
class GraspTypeSettings:
    """Thresholds of the palmar and grasp-type tests. Angles in degrees."""

    palmar_angle_deg: float = 75.0
    """A contact is palmar when the angle between its normal and the link's n_palmar is
    below this (degrees, in (0, 180))."""
    cg_min_long_fingers: int = 3
    """CG: at least this many long fingers must each have enough palmar phalanx contacts
    (1 to 4)."""
    cg_min_phalanges_per_finger: int = 2
    """CG: distinct phalanges with a palmar contact that make a long finger count (1 to 3);
    the experimental protocol asks for 3, the published simulation relaxed it to 2."""
    cg_thumb_axis_min_angle_deg: float = 60.0
    """CG: the line angle between the thumb's n_main and the object's grip axis must be
    greater than this (degrees, in [0, 90))."""

    def __post_init__(self) -> None:
        a = self.palmar_angle_deg
        if not (_is_real(a) and 0 < a < 180):
            raise SettingsError(f"palmar_angle_deg must be in (0, 180) degrees, got {a!r}")
        n = self.cg_min_long_fingers
        if not (_is_int(n) and 1 <= n <= len(LONG_FINGERS)):
            raise SettingsError(f"cg_min_long_fingers must be an integer in 1..4, got {n!r}")
        n = self.cg_min_phalanges_per_finger
        if not (_is_int(n) and 1 <= n <= len(PHALANGES)):
            raise SettingsError(
                f"cg_min_phalanges_per_finger must be an integer in 1..3, got {n!r}"
            )
        a = self.cg_thumb_axis_min_angle_deg
        if not (_is_real(a) and 0 <= a < 90):
            raise SettingsError(
                f"cg_thumb_axis_min_angle_deg must be in [0, 90) degrees, got {a!r}"
            )

    def as_dict(self) -> dict[str, object]:
        """Plain dict (for hashing and JSON)."""
        return asdict(self)


def _is_real(x: object) -> bool:
    return isinstance(x, int | float) and not isinstance(x, bool) and math.isfinite(x)


def _is_int(x: object) -> bool:
    return isinstance(x, int | np.integer) and not isinstance(x, bool)


class Verdict(NamedTuple):
    """Grasp-type correctness with every failed criterion in plain words."""

    correct: bool
    reasons: tuple[str, ...]
    """Empty when correct."""


def is_palmar(n_contact: npt.ArrayLike, n_palmar: npt.ArrayLike, angle_deg: float) -> np.ndarray:
    """Palmar test ``angle(n_contact, n_palmar) < angle_deg``, i.e. ``n̂_c · n̂_p > cos(angle)``.

    Args:
        n_contact: (..., 3) contact normals (link → object); need not be unit.
        n_palmar: (..., 3) the links' palmar normals, same frame; need not be unit.
        angle_deg: threshold in degrees.

    Returns:
        (...,) bool.
    """
    nc = np.asarray(n_contact, dtype=float)
    npl = np.asarray(n_palmar, dtype=float)
    cos = np.sum(nc * npl, axis=-1) / (np.linalg.norm(nc, axis=-1) * np.linalg.norm(npl, axis=-1))
    return cos > math.cos(math.radians(angle_deg))


def _fingers_text(fingers: list[str]) -> str:
    return ", ".join(fingers) if fingers else "none"


def check_pp(contacts: ContactSet) -> Verdict:
    """Pulp-pinch correctness (see the module docstring)."""
    palmar = contacts.palmar_links()
    reasons: list[str] = []
    if "thumb_distal" not in palmar:
        reasons.append("no palmar contact on the thumb distal phalanx")
    distal = [f for f in LONG_FINGERS if f"{f}_distal" in palmar]
    if not distal:
        reasons.append(
            "no palmar contact on the distal phalanx of any long finger; "
            "pulp pinch needs exactly one"
        )
    elif len(distal) > 1:
        reasons.append(
            f"palmar contacts on the distal phalanges of {len(distal)} long fingers "
            f"({_fingers_text(distal)}); pulp pinch needs exactly one"
        )
    if "palm" in contacts.links:
        reasons.append("contact with the palm")
    return Verdict(not reasons, tuple(reasons))


def line_angle_deg(a: npt.ArrayLike, b: npt.ArrayLike) -> np.ndarray:
    """Angle between the lines along ``a`` and ``b``: ``arccos(|â · b̂|)`` in [0, 90] degrees.

    Args:
        a, b: (..., 3) non-zero direction vectors.

    Returns:
        (...,) degrees.
    """
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    na = np.linalg.norm(a, axis=-1)
    nb = np.linalg.norm(b, axis=-1)
    if np.any(na == 0) or np.any(nb == 0):
        raise ValueError("line_angle_deg needs non-zero direction vectors")
    c = np.abs(np.sum(a * b, axis=-1)) / (na * nb)
    return np.degrees(np.arccos(np.clip(c, 0.0, 1.0)))


def check_cg(
    contacts: ContactSet,
    thumb_n_main_object: npt.ArrayLike,
    grip_axis_object: npt.ArrayLike,
    settings: GraspTypeSettings | None = None,
) -> Verdict:
    """Cylindrical-grip correctness (see the module docstring).

    Args:
        contacts: the grasp's contacts (``palmar`` already classified).
        thumb_n_main_object: (3,) the thumb's n_main in the object frame.
        grip_axis_object: (3,) the object's grip axis in the object frame (sign irrelevant).
        settings: thresholds (default ``GraspTypeSettings()``).
    """
    s = settings or GraspTypeSettings()
    reasons: list[str] = []
    angle = float(line_angle_deg(thumb_n_main_object, grip_axis_object))
    if not angle > s.cg_thumb_axis_min_angle_deg:
        reasons.append(
            f"thumb axis at {angle:.0f}° to the grip axis; "
            f"needs > {s.cg_thumb_axis_min_angle_deg:g}°"
        )
    palmar = contacts.palmar_links()
    if not palmar.intersection(THUMB_LINKS):
        reasons.append("no palmar contact on the thumb")
    k = s.cg_min_phalanges_per_finger
    good = [f for f in LONG_FINGERS if sum(f"{f}_{p}" in palmar for p in PHALANGES) >= k]
    if len(good) < s.cg_min_long_fingers:
        k_words = _WORDS.get(k, str(k))
        what = "phalanx" if k == 1 else "phalanges"
        if good:
            reasons.append(
                f"palmar contacts on {k_words} {what} of only {len(good)} long "
                f"finger{'s' if len(good) != 1 else ''} ({_fingers_text(good)}); "
                f"needs {s.cg_min_long_fingers}"
            )
        else:
            reasons.append(
                f"no long finger has palmar contacts on {k_words} {what}; "
                f"needs {s.cg_min_long_fingers}"
            )
    if "palm" not in palmar:
        reasons.append("no palmar contact on the palm")
    return Verdict(not reasons, tuple(reasons))


def check_grasp_type(
    grasp_type: str,
    contacts: ContactSet,
    thumb_n_main_object: npt.ArrayLike | None = None,
    grip_axis_object: npt.ArrayLike | None = None,
    settings: GraspTypeSettings | None = None,
) -> Verdict:
    """Dispatch to ``check_pp`` ("PP") or ``check_cg`` ("CG", which needs both axes).

    Raises:
        SettingsError: ``grasp_type`` not one of ``GRASP_TYPES``.
        ValueError: "CG" without ``thumb_n_main_object`` or ``grip_axis_object``.
    """
    if grasp_type == "PP":
        return check_pp(contacts)
    if grasp_type == "CG":
        if thumb_n_main_object is None or grip_axis_object is None:
            raise ValueError("CG correctness needs thumb_n_main_object and grip_axis_object")
        return check_cg(contacts, thumb_n_main_object, grip_axis_object, settings)
    raise SettingsError(f"grasp type {grasp_type!r} unknown; choose one of {GRASP_TYPES}")
