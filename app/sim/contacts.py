"""Contact patches after closing (METHOD §5).

A link is in contact when its FCL distance to the object is within ``contact_tol_mm``.
Its patch: points sampled on the link surface (about 1 mm apart) whose signed distance
to the object is within the tolerance; thinned to at most ``max_points_per_link`` by
farthest-point sampling, which keeps the patch's extent (what resists torsion about the
line between two fingers). n_contact = minus the object's outward normal at the point, i.e.
from the link toward the object. Palmar: angle(n_contact, link n_palmar) < threshold.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import fcl
import numpy as np

from app.model.contact_set import ContactSet
from app.model.hand.geometry import Shape
from app.model.target import GraspTarget
from app.sim.closing import fcl_transform, pair_nearest


@dataclass(frozen=True)
class ContactSettings:
    """How contacts are extracted and classified."""

    contact_tol_mm: float = 1.0
    """A link (and a surface point) within this distance of the object touches it."""
    max_points_per_link: int = 6
    """Cap on points per contact patch (farthest-point sampling keeps its extent)."""
    sample_spacing_mm: float = 1.0
    """Spacing of the link-surface sample points."""

    def __post_init__(self) -> None:
        from app.errors import SettingsError

        if not 0 < self.contact_tol_mm <= 10:
            raise SettingsError(f"contact_tol_mm must be in (0, 10] mm, got {self.contact_tol_mm}")
        if self.max_points_per_link < 1:
            raise SettingsError(f"max_points_per_link must be >= 1, got {self.max_points_per_link}")
        if not 0.2 <= self.sample_spacing_mm <= 5:
            raise SettingsError(
                f"sample_spacing_mm must be in [0.2, 5], got {self.sample_spacing_mm}"
            )


@lru_cache(maxsize=512)
def _samples(shape: Shape, spacing: float) -> tuple[np.ndarray, np.ndarray]:
    return shape.surface_points(spacing)


#: A patch holds the link samples within this distance of the link's nearest point (mm).
PATCH_RADIUS_MM = 30.0
#: Cell size of the coarse samples that screen a link's surface samples (mm).
COARSE_CELL_MM = 4.0
#: Lipschitz constant assumed of object SDFs (exact ones: 1; bilinear tables: <= sqrt 2).
SDF_LIPSCHITZ = 1.5


@lru_cache(maxsize=512)
def _coarse(shape: Shape, spacing: float) -> tuple[np.ndarray, np.ndarray, float]:
    """Coarse screening of a shape's surface samples: (indices (C,) of coarse samples, the
    coarse sample (K,) each sample is assigned to (its nearest), largest assignment distance).
    """
    from scipy.spatial import cKDTree

    p, _ = _samples(shape, spacing)
    cell = np.floor(p / COARSE_CELL_MM).astype(np.int64)
    _, first = np.unique(cell, axis=0, return_index=True)
    idx = np.sort(first)
    dist, assign = cKDTree(p[idx]).query(p)
    return idx, np.asarray(assign), float(np.max(dist))


def near_surface(
    obj: GraspTarget,
    shape: Shape,
    T_object_link: np.ndarray,
    centre_link: np.ndarray,
    radius: float,
    tol: float,
    spacing: float,
) -> np.ndarray:
    """Indices of the shape's surface samples within ``radius`` of ``centre_link`` (link
    frame) whose signed distance to the object, with the link posed at ``T_object_link``, is
    <= ``tol``; in sample order.

    Exact screening: the SDF is evaluated on coarse samples first; a sample whose coarse
    sample lies farther than ``tol + L·δ`` from the object (δ the largest sample-to-coarse
    distance, L the SDF's Lipschitz bound) cannot be within ``tol``, so only the others are
    posed and evaluated."""
    p_link, _ = _samples(shape, spacing)
    idx_c, assign, delta = _coarse(shape, spacing)
    R, t = T_object_link[:3, :3], T_object_link[:3, 3]
    pc = p_link[idx_c]
    use_c = np.flatnonzero(((pc - centre_link) ** 2).sum(1) < (radius + delta) ** 2)
    keep_c = np.zeros(len(idx_c), dtype=bool)
    if len(use_c):
        sd_c = obj.sdf(pc[use_c] @ R.T + t)
        keep_c[use_c[sd_c <= tol + SDF_LIPSCHITZ * delta]] = True
    idx = np.flatnonzero(keep_c[assign])
    idx = idx[((p_link[idx] - centre_link) ** 2).sum(1) < radius**2]
    if len(idx) == 0:
        return idx
    sd = obj.sdf(p_link[idx] @ R.T + t)
    return idx[sd <= tol]


def farthest_points(p: np.ndarray, m: int) -> np.ndarray:
    """Indices of up to ``m`` points of ``p`` (K, 3) spread by farthest-point sampling."""
    if len(p) <= m:
        return np.arange(len(p))
    centre = p.mean(0)
    idx = [int(np.argmax(((p - centre) ** 2).sum(1)))]
    d = ((p - p[idx[0]]) ** 2).sum(1)
    for _ in range(m - 1):
        i = int(np.argmax(d))
        idx.append(i)
        d = np.minimum(d, ((p - p[i]) ** 2).sum(1))
    return np.array(idx)


def link_patch(
    obj: GraspTarget,
    shape: Shape,
    T_object_link: np.ndarray,
    nearest_on_link: np.ndarray,
    settings: ContactSettings,
) -> tuple[np.ndarray, np.ndarray]:
    """Patch points (K, 3) and contact normals (K, 3) of one touching link, object frame."""
    p_link, _ = _samples(shape, settings.sample_spacing_mm)
    R, t = T_object_link[:3, :3], T_object_link[:3, 3]
    centre_link = (nearest_on_link - t) @ R  # patches reach at most PATCH_RADIUS_MM from it
    idx = near_surface(
        obj,
        shape,
        T_object_link,
        centre_link,
        PATCH_RADIUS_MM,
        settings.contact_tol_mm,
        settings.sample_spacing_mm,
    )
    p = p_link[idx] @ R.T + t
    if len(p) == 0:  # sampling missed a grazing contact: keep FCL's nearest point
        p = nearest_on_link[None, :]
    p = p[farthest_points(p, settings.max_points_per_link)]
    n_out = obj.normal(p)
    return p, -n_out


def contacts_of_links(
    obj: GraspTarget,
    names: list[str],
    shapes: list[Shape],
    bodies: list[fcl.CollisionObject],
    T_object_links: np.ndarray,
    T_link_fcl: np.ndarray,
    settings: ContactSettings,
    palmar_angle_deg: float,
    counter: list[int] | None = None,
) -> ContactSet:
    """Contacts of the given links (poses (L, 4, 4) in the object frame) with the object."""
    pieces = obj.collision_objects()
    centroid = obj.centroid_object
    r_obj = obj.max_radius
    P, N, L, Pal = [], [], [], []
    for name, shape, body, T, Tf in zip(
        names, shapes, bodies, T_object_links, T_link_fcl, strict=True
    ):
        Tb = T @ Tf
        # bounding-sphere cull: link reach from its FCL frame centre
        reach = _reach(shape)
        if np.linalg.norm(Tb[:3, 3] - centroid) > r_obj + reach + settings.contact_tol_mm:
            continue
        body.setTransform(fcl_transform(Tb))
        best = (np.inf, None)
        for piece in pieces:
            d, pa, _ = pair_nearest(body, piece)
            if counter is not None:
                counter[0] += 1
            if d < best[0]:
                best = (d, pa)
        if best[0] > settings.contact_tol_mm or best[1] is None:
            continue
        p, n = link_patch(obj, shape, T, best[1], settings)
        n_palmar = T[:3, 2]
        cos_lim = np.cos(np.deg2rad(palmar_angle_deg))
        P.append(p)
        N.append(n)
        L.append(np.full(len(p), name, dtype=object))
        Pal.append(n @ n_palmar > cos_lim)
    if not P:
        return ContactSet()
    return ContactSet(np.concatenate(P), np.concatenate(N), np.concatenate(L), np.concatenate(Pal))


def _reach(shape: Shape) -> float:
    """Radius of a sphere about the FCL frame centre enclosing the shape."""
    from app.model.hand.geometry import CapsuleShape

    if isinstance(shape, CapsuleShape):
        return shape.length / 2 + shape.radius
    return float(np.linalg.norm(shape.hi_link - shape.lo_link)) / 2


def merge(a: ContactSet, b: ContactSet) -> ContactSet:
    """Union of two contact sets."""
    if len(a) == 0:
        return b
    if len(b) == 0:
        return a
    return ContactSet(
        np.concatenate([a.p_object, b.p_object]),
        np.concatenate([a.n_object, b.n_object]),
        np.concatenate([a.link, b.link]),
        np.concatenate([a.palmar, b.palmar]),
    )
