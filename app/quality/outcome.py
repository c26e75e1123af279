"""What one grasp hypothesis produced: the record every run stores and every score counts."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from app.model.contact_set import ContactSet


@dataclass(frozen=True, eq=False)
class GraspOutcome:
    """What one grasp hypothesis produced under one design, object and settings.

    Arrays are normalised on construction (``q_final_rad`` to float64). Compare two outcomes
    with :meth:`same_as` (arrays make ``==`` ambiguous, so it is not defined).
    """

    q_final_rad: np.ndarray
    """(15,) float64 joint values after closing, rad, in the conventions' joint order."""
    contacts: ContactSet
    """The contacts of the final grasp, object frame, mm (stored exactly, dtype kept)."""
    is_fc: bool
    """The grasp is force closure (METHOD §5)."""
    is_correct: bool
    """The grasp is FC and of the object's correct grasp type (PP/CG)."""
    epsilon: float
    """Ferrari–Canny ε of the grasp wrench space (0 when not FC; NaN allowed)."""
    reasons: tuple[str, ...] = ()
    """Why the grasp is not correct (empty when it is), human-readable."""
    n_queries: int = 0
    """Collision/distance queries spent simulating this grasp."""
    extra: dict[str, Any] = field(default_factory=dict)
    """Optional JSON-serialisable details (timings, metric values...)."""

    def __post_init__(self) -> None:
        q = np.ascontiguousarray(self.q_final_rad, dtype=np.float64)
        if q.ndim != 1:
            raise ValueError(f"q_final_rad must be 1-D (n_joints,), got shape {q.shape}")
        object.__setattr__(self, "q_final_rad", q)
        object.__setattr__(self, "reasons", tuple(str(r) for r in self.reasons))
        object.__setattr__(self, "is_fc", bool(self.is_fc))
        object.__setattr__(self, "is_correct", bool(self.is_correct))
        object.__setattr__(self, "epsilon", float(self.epsilon))
        object.__setattr__(self, "n_queries", int(self.n_queries))
        object.__setattr__(self, "extra", dict(self.extra))

    def same_as(self, other: GraspOutcome) -> bool:
        """Exact equality of every field (arrays bit-for-bit in value and dtype; NaN = NaN)."""
        a, b = self.contacts, other.contacts
        return (
            _same_array(self.q_final_rad, other.q_final_rad)
            and _same_array(a.p_object, b.p_object)
            and _same_array(a.n_object, b.n_object)
            and [str(s) for s in a.link] == [str(s) for s in b.link]
            and _same_array(np.asarray(a.palmar, bool), np.asarray(b.palmar, bool))
            and self.is_fc == other.is_fc
            and self.is_correct == other.is_correct
            and (
                self.epsilon == other.epsilon
                or (math.isnan(self.epsilon) and math.isnan(other.epsilon))
            )
            and self.reasons == other.reasons
            and self.n_queries == other.n_queries
            and self.extra == other.extra
        )


def _same_array(a: np.ndarray, b: np.ndarray) -> bool:
    return a.dtype == b.dtype and a.shape == b.shape and np.array_equal(a, b, equal_nan=True)
