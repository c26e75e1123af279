"""Contact patches after closing (METHOD §5).

A link is in contact when its FCL distance to the object is within ``contact_tol_mm``.
Its patch: all points sampled on the link surface (about 1 mm apart) whose signed distance
to the object is within the tolerance, wherever they lie on the link (no disc about a
nearest point, which jumps along a link lying parallel to a flat face), or the link's
sample nearest the object when sampling misses a grazing contact; thinned to at most
``max_points_per_link`` by farthest-point sampling in the link frame, which keeps the
patch's extent (what resists torsion about the line between two fingers). A link touching
in two places keeps points of both: a patch is a contact set, force closure uses every
point. n_contact = minus the object's outward normal at the point, i.e. from the link toward
the object. Palmar: angle(n_contact, link n_palmar) < threshold.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import lru_cache

import fcl
import numpy as np

from app.model.contact_set import ContactSet
from app.model.hand.geometry import Shape
from app.model.target import GraspTarget
from app.sim.closing import fcl_transform, pair_distance


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
    tol: float,
    spacing: float,
) -> tuple[np.ndarray, int]:
    """(indices of the shape's surface samples whose signed distance to the object, with the
    link posed at ``T_object_link``, is <= ``tol``, in sample order; the index of the sample
    with the smallest signed distance).

    Exact screening: the SDF is evaluated on coarse samples first; a sample whose coarse
    sample lies farther than ``tol + L·δ`` from the object (δ the largest sample-to-coarse
    distance, L the SDF's Lipschitz bound) cannot be within ``tol``, so only the others are
    posed and evaluated. The nearest sample (the fallback of a grazing contact) is exact too:
    coarse samples are samples, so the nearest one's coarse sample is within L·δ of the
    smallest coarse value."""
    p_link, _ = _samples(shape, spacing)
    idx_c, assign, delta = _coarse(shape, spacing)
    R, t = T_object_link[:3, :3], T_object_link[:3, 3]
    sd_c = obj.sdf(p_link[idx_c] @ R.T + t)
    m = float(sd_c.min())
    bound = max(tol, m) + SDF_LIPSCHITZ * delta
    idx = np.flatnonzero((sd_c <= bound)[assign])
    sd = obj.sdf(p_link[idx] @ R.T + t)
    return idx[sd <= tol], int(idx[np.argmin(sd)])


#: Squared distances (mm²) within this of the largest count as tied in farthest-point
#: sampling (the lowest index wins), so that rounding never decides between the equidistant
#: samples of a band (and the compiled path picks the same points).
FPS_TIE_MM2 = 1e-6


def _argmax_tie(d: np.ndarray) -> int:
    return int(np.flatnonzero(d >= d.max() - FPS_TIE_MM2)[0])


def farthest_points(p: np.ndarray, m: int) -> np.ndarray:
    """Indices of up to ``m`` points of ``p`` (K, 3) spread by farthest-point sampling
    (deterministic: the first is the point farthest from the mean; near-ties go to the lowest
    index, ``FPS_TIE_MM2``)."""
    if len(p) <= m:
        return np.arange(len(p))
    centre = p.mean(0)
    idx = [_argmax_tie(((p - centre) ** 2).sum(1))]
    d = ((p - p[idx[0]]) ** 2).sum(1)
    for _ in range(m - 1):
        i = _argmax_tie(d)
        idx.append(i)
        d = np.minimum(d, ((p - p[i]) ** 2).sum(1))
    return np.array(idx)


def link_patch(
    obj: GraspTarget,
    shape: Shape,
    T_object_link: np.ndarray,
    settings: ContactSettings,
) -> tuple[np.ndarray, np.ndarray]:
    """Patch points (K, 3) and contact normals (K, 3) of one touching link, object frame.

    The patch is every surface sample of the link within ``contact_tol_mm`` of the object
    (a link may touch in separate places: all of them are its contact set), thinned by
    farthest-point sampling; it does not depend on where a distance query's nearest point
    lands. When sampling misses a grazing contact (the link is within tol, no sample is),
    the link's sample nearest the object stands for it."""
    p_link, _ = _samples(shape, settings.sample_spacing_mm)
    R, t = T_object_link[:3, :3], T_object_link[:3, 3]
    idx, nearest = near_surface(
        obj, shape, T_object_link, settings.contact_tol_mm, settings.sample_spacing_mm
    )
    if len(idx) == 0:
        idx = np.array([nearest])
    # thinning in the link frame: distances between samples are then the same numbers
    # whatever the pose, so a band of equidistant samples (a link parallel to a face) keeps
    # the same points under any tiny motion instead of breaking its ties differently
    idx = idx[farthest_points(p_link[idx], settings.max_points_per_link)]
    p = p_link[idx] @ R.T + t
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
    link_distance: Callable[[Shape, np.ndarray], float] | None = None,
) -> ContactSet:
    """Contacts of the given links (poses (L, 4, 4) in the object frame) with the object.

    ``link_distance(shape, T_object_fcl)``: the in-contact test's distance (exact at least up
    to the tolerance) in place of FCL's (the compiled engine on an imported mesh)."""
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
        if link_distance is not None:
            best = link_distance(shape, Tb)
            if counter is not None:
                counter[0] += 1
        else:
            body.setTransform(fcl_transform(Tb))
            best = np.inf
            for piece in pieces:
                best = min(best, pair_distance(body, piece))
                if counter is not None:
                    counter[0] += 1
        if best > settings.contact_tol_mm:
            continue
        p, n = link_patch(obj, shape, T, settings)
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
