"""The scene boundary: the core works in mm, viser's camera expects about metres."""

from __future__ import annotations

import numpy as np
import viser.transforms as vtf

MM = 1e-3
"""Scene metres per core millimetre: every length goes through this factor once."""


def to_scene(p_mm: np.ndarray) -> np.ndarray:
    """Points in mm (any leading shape, last axis 3) -> scene metres, float32."""
    return (np.asarray(p_mm, dtype=float) * MM).astype(np.float32)


def pose_to_scene(T_mm: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(4, 4) pose with a translation in mm -> (wxyz (4,), position (3,) in metres)."""
    wxyz = vtf.SO3.from_matrix(np.asarray(T_mm[:3, :3], dtype=float)).wxyz
    return np.asarray(wxyz, dtype=float), np.asarray(T_mm[:3, 3], dtype=float) * MM
