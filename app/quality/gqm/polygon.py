"""The grasp polygon of Q_B2 and Q_B3: contact points in their best-fit plane.

The one-per-link contact points (K, 3) are centred and projected onto their two principal
directions (SVD: the least-squares plane); the polygon is the 2-D convex hull of the
projections, vertices counter-clockwise. Points inside the hull (more than three contacts
not in convex position) do not count as vertices. Fewer than three points, or collinear
points, give no polygon.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import ConvexHull, QhullError


def plane_projection(p: np.ndarray) -> np.ndarray:
    """(K, 2) coordinates of ``p`` (K, 3) in their best-fit plane (origin at their mean)."""
    p = np.asarray(p, float).reshape(-1, 3)
    c = p - p.mean(axis=0)
    _, _, vt = np.linalg.svd(c, full_matrices=False)
    return c @ vt[:2].T


def grasp_polygon(p: np.ndarray, rel_tol: float = 1e-9) -> np.ndarray:
    """(n, 2) convex-polygon vertices, counter-clockwise; (0, 2) when there is none."""
    p = np.asarray(p, float).reshape(-1, 3)
    if len(p) < 3:
        return np.zeros((0, 2))
    xy = plane_projection(p)
    scale = float(np.max(np.abs(xy))) if xy.size else 0.0
    s = np.linalg.svd(xy, compute_uv=False)
    if scale == 0 or s[1] <= rel_tol * max(s[0], 1e-300):
        return np.zeros((0, 2))
    try:
        hull = ConvexHull(xy)
    except QhullError:
        return np.zeros((0, 2))
    return xy[hull.vertices]  # scipy orders 2-D hull vertices counter-clockwise


def polygon_area(v: np.ndarray) -> float:
    """Area of a simple polygon (n, 2) by the shoelace formula (0 for n < 3)."""
    if len(v) < 3:
        return 0.0
    x, y = v[:, 0], v[:, 1]
    return 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))


def interior_angles(v: np.ndarray) -> np.ndarray:
    """(n,) interior angles (rad) of a convex polygon (n, 2) given in order."""
    a = np.roll(v, 1, axis=0) - v
    b = np.roll(v, -1, axis=0) - v
    cos = np.sum(a * b, axis=1) / (np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1))
    return np.arccos(np.clip(cos, -1.0, 1.0))
