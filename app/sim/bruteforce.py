"""Brute-force grasp hypotheses (METHOD §3b): OpenRAVE-style approach rays from a box grid.

Construction, per object (object frame, mm):

1. The mesh's axis-aligned bounding box, grown by ``box_margin_mm`` on every side.
2. On each of its six faces (order ``+x, −x, +y, −y, +z, −z`` = face 0..5) a square grid of
   spacing ``d = grid_spacing_mm``. Our decision: the grid is symmetric about the face
   centre and contains it — the points are ``centre + a·e_u + b·e_v`` with ``a = k·d`` for
   every integer ``k`` with ``|k·d| ≤`` the face's half-width along ``e_u`` (likewise ``b``),
   where ``(e_u, e_v)`` are the two other coordinate axes in increasing order (x before y
   before z). ``i`` and ``j`` number the points along ``e_u`` and ``e_v`` from 0, in
   increasing coordinate.
3. Each grid point casts a ray inward, along minus the face normal, against the object's
   triangle mesh (our own vectorised Möller–Trumbore test, ``first_hits``: exact on the mesh
   FCL collides with, and ~100× faster than trimesh's rtree-based intersector without
   embree; the SDF is only used by the tests to check the hits). The first hit is the
   grasp target; a ray that misses the object is dropped. Triangles the ray grazes
   (``|n̂ · d| < GRAZING_COS``, e.g. a grid line lying in a planar face of the drill) are
   skipped: such a hit has no meaningful approach normal.
4. The surface normal at a hit is the hit triangle's face normal, flipped if needed so that
   it points outward (against the ray). Approach direction = −normal; cone angle α = 0, so
   one approach ray per hit.
5. Every hit is combined with every standoff ``δ ∈ standoffs_mm`` (METHOD: {0, 25} mm) and
   roll ``θ ∈ rolls_rad`` (METHOD: {0, π/2, π, 3π/2, 2π}; 2π duplicates 0 and is dropped
   with ``drop_duplicate_roll``). Ordering: ray-major, then standoff, then roll.

Hand placement (our decisions): the hand vector is the palm normal, ``n = (0, 0, 1)`` in the
palm frame (OpenRAVE approaches along the manipulator's direction, the palm normal of a
hand), and the reference point is the benchmark's P (``Hand.approach_point_palm``,
(10, 70, 0) mm): the line through P along n is the approach ray through the hit. At roll 0,
palm +y is the object's +z projected off the approach line, or the object's +x when the
approach is within ~18° of ±z (``|a_z| > 0.95``), then the roll turns the hand about the
approach (right-hand rule about the approach direction, as in ``app.sim.hypotheses``). All
fingers close (``ALL_FINGERS``).

Every hit has its own target point, so ``Hypotheses.target_object`` (one point for the
anthropomorphic cone) holds the first hit only; ``BruteForceHypotheses.approach_line(i)``
returns the same set with ``target_object`` = hit ``i``, which is what ``simulate_base``
takes. Ids: ``'<object>/bf/f<face>/i<ii>j<jj>/d<standoff>/t<roll>'``.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
import trimesh

from app.model.contact_set import LONG_FINGERS
from app.model.objects import GraspObject
from app.sim.hypotheses import Hypotheses, palm_orientation

#: Fingers closing in the brute-force set: all of them.
ALL_FINGERS: tuple[str, ...] = ("thumb",) + LONG_FINGERS
#: Brute-force hand vector (palm frame): the palm normal.
BF_HAND_VECTOR_PALM = np.array([0.0, 0.0, 1.0])
#: Roll-0 palm +y hint is object +z unless the approach has |a_z| above this; then +x.
HINT_SWITCH_COS = 0.95
#: A ray whose angle to a triangle's plane is below ~5.7° (|n̂ · d| < 0.1) grazes it: the
#: triangle is skipped (a grid line lying in a planar face of the object would otherwise
#: "hit" it anywhere along the face, with an ill-defined normal).
GRAZING_COS = 0.1
#: Face normals of the grown box, in face order.
FACE_NORMALS = np.array(
    [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], dtype=float
)


@dataclass(frozen=True)
class BruteForceSettings:
    """Parameters of the brute-force hypothesis set (METHOD §3b defaults)."""

    grid_spacing_mm: float = 20.0
    """Spacing d of the grid on each face of the grown box, mm."""
    box_margin_mm: float = 10.0
    """The bounding box is grown by this on every side before the grid is laid, mm."""
    standoffs_mm: tuple[float, ...] = (0.0, 25.0)
    """Back-off distances after first contact, mm."""
    rolls_rad: tuple[float, ...] = (0.0, np.pi / 2, np.pi, 3 * np.pi / 2, 2 * np.pi)
    """Rolls about the approach ray, rad (the published list, 2π included)."""
    drop_duplicate_roll: bool = False
    """Drop rolls equal to an earlier one modulo 2π (the published 2π)."""

    def rolls(self) -> tuple[float, ...]:
        """The rolls used, rad (duplicates modulo 2π removed when asked)."""
        if not self.drop_duplicate_roll:
            return self.rolls_rad
        out: list[float] = []
        for r in self.rolls_rad:
            if not any(abs(np.angle(np.exp(1j * (r - o)))) < 1e-9 for o in out):
                out.append(r)
        return tuple(out)


@dataclass(frozen=True)
class BoxRays:
    """The inward rays of the grown-box grid that hit the object (R of them)."""

    origin_object: np.ndarray
    """(R, 3) grid points on the grown box, mm."""
    hit_object: np.ndarray
    """(R, 3) first hit on the object mesh, mm."""
    normal_object: np.ndarray
    """(R, 3) outward unit surface normal at the hit."""
    face: np.ndarray
    """(R,) int face index 0..5 (``+x, −x, +y, −y, +z, −z``)."""
    ij: np.ndarray
    """(R, 2) int grid indices on the face."""
    n_cast: int
    """Rays cast (hits and misses)."""


def face_grid(
    lo: np.ndarray, hi: np.ndarray, face: int, spacing: float
) -> tuple[np.ndarray, np.ndarray]:
    """Grid points of one face of the box [lo, hi] and their (i, j) indices.

    Returns:
        (points (P, 3), ij (P, 2)), points on the face plane, ``i`` along the first in-plane
        axis, both in increasing coordinate.
    """
    axis = face // 2
    u, v = (a for a in range(3) if a != axis)
    centre = 0.5 * (lo + hi)
    half = 0.5 * (hi - lo)

    def ticks(a: int) -> np.ndarray:
        k = int(np.floor(half[a] / spacing + 1e-9))
        return np.arange(-k, k + 1) * spacing

    tu, tv = ticks(u), ticks(v)
    ii, jj = np.meshgrid(np.arange(len(tu)), np.arange(len(tv)), indexing="ij")
    ii, jj = ii.ravel(), jj.ravel()
    pts = np.tile(centre, (len(ii), 1))
    pts[:, u] += tu[ii]
    pts[:, v] += tv[jj]
    pts[:, axis] = hi[axis] if FACE_NORMALS[face, axis] > 0 else lo[axis]
    return pts, np.stack([ii, jj], axis=1)


def cast_box_rays(mesh: trimesh.Trimesh, settings: BruteForceSettings | None = None) -> BoxRays:
    """Cast the inward grid rays of the grown bounding box onto ``mesh`` (a trimesh.Trimesh)."""
    s = settings or BruteForceSettings()
    bounds = np.asarray(mesh.bounds, float)
    lo, hi = bounds[0] - s.box_margin_mm, bounds[1] + s.box_margin_mm
    origins, faces, ijs = [], [], []
    for f in range(6):
        pts, ij = face_grid(lo, hi, f, s.grid_spacing_mm)
        origins.append(pts)
        faces.append(np.full(len(pts), f))
        ijs.append(ij)
    origin = np.concatenate(origins)
    face = np.concatenate(faces)
    ij = np.concatenate(ijs)
    direction = -FACE_NORMALS[face]
    tris = np.asarray(mesh.vertices, float)[np.asarray(mesh.faces)]
    tri_of, t_hit = first_hits(origin, direction, tris, GRAZING_COS)
    hit = origin + np.where(np.isfinite(t_hit), t_hit, 0.0)[:, None] * direction
    keep = np.nonzero(tri_of >= 0)[0]
    n = np.asarray(mesh.face_normals, float)[tri_of[keep]]
    flip = np.sum(n * direction[keep], axis=1) > 0
    n[flip] *= -1.0
    return BoxRays(origin[keep], hit[keep], n, face[keep], ij[keep], len(origin))


def first_hits(
    origin: np.ndarray,
    direction: np.ndarray,
    tris: np.ndarray,
    min_cos: float = 0.0,
    chunk: int = 16,
) -> tuple[np.ndarray, np.ndarray]:
    """First triangle hit by each ray (Möller–Trumbore, vectorised over rays × triangles).

    Args:
        origin: (R, 3) ray origins.
        direction: (R, 3) unit ray directions.
        tris: (T, 3, 3) triangle corners.
        min_cos: triangles with ``|n̂ · d| < min_cos`` (the ray grazes them) are ignored.
        chunk: rays per vectorised block (memory ~ chunk · T · 100 bytes).

    Returns:
        (tri (R,) int index of the first triangle hit, -1 for a miss; t (R,) distance along
        the ray, inf for a miss).
    """
    a = tris[:, 0]
    e1, e2 = tris[:, 1] - a, tris[:, 2] - a  # (T, 3)
    nrm = np.cross(e1, e2)
    nrm /= np.maximum(np.linalg.norm(nrm, axis=1, keepdims=True), 1e-300)
    tri = np.full(len(origin), -1)
    t_hit = np.full(len(origin), np.inf)
    for s0 in range(0, len(origin), chunk):
        o, d = origin[s0 : s0 + chunk, None, :], direction[s0 : s0 + chunk, None, :]
        pvec = np.cross(d, e2)  # (C, T, 3)
        det = np.sum(e1 * pvec, axis=-1)
        ok = np.abs(det) > 1e-12
        inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
        tvec = o - a
        u = np.sum(tvec * pvec, axis=-1) * inv
        qvec = np.cross(tvec, e1)
        v = np.sum(d * qvec, axis=-1) * inv
        t = np.sum(e2 * qvec, axis=-1) * inv
        eps = 1e-9
        ok &= (u >= -eps) & (v >= -eps) & (u + v <= 1 + eps) & (t > 0)
        ok &= np.abs(np.sum(d * nrm, axis=-1)) >= min_cos
        t = np.where(ok, t, np.inf)
        k = np.argmin(t, axis=1)
        tk = t[np.arange(len(k)), k]
        hit = np.isfinite(tk)
        tri[s0 : s0 + chunk] = np.where(hit, k, -1)
        t_hit[s0 : s0 + chunk] = tk
    return tri, t_hit


def roll0_hint(approach_object: np.ndarray) -> np.ndarray:
    """Palm +y hint at roll 0 (object frame): +z, or +x for approaches near ±z."""
    a = approach_object / np.linalg.norm(approach_object)
    return np.array([1.0, 0.0, 0.0]) if abs(a[2]) > HINT_SWITCH_COS else np.array([0.0, 0.0, 1.0])


@dataclass(frozen=True)
class BruteForceHypotheses(Hypotheses):
    """Brute-force hypotheses: a ``Hypotheses`` whose rays each have their own target."""

    hit_object: np.ndarray
    """(R, 3) the hit (target) of every approach ray, mm; ``ray_index`` indexes it."""
    face: np.ndarray
    """(R,) box face of every ray."""
    ij: np.ndarray
    """(R, 2) grid indices of every ray on its face."""
    n_cast: int
    """Rays cast, hits and misses (misses are dropped)."""

    def approach_line(self, i: int) -> BruteForceHypotheses:
        """The same set with ``target_object`` = the hit of hypothesis ``i`` (for
        ``simulate_base``, whose approach line is ``target_object + s · ray_object[i]``)."""
        return dataclasses.replace(self, target_object=self.hit_object[self.ray_index[i]])


def brute_force_hypotheses(
    obj: GraspObject, settings: BruteForceSettings | None = None
) -> BruteForceHypotheses:
    """All brute-force hypotheses of a ``GraspObject``: hits × standoffs × rolls."""
    s = settings or BruteForceSettings()
    key = obj.spec.key
    rays = cast_box_rays(obj.mesh, s)
    rolls = np.asarray(s.rolls(), float)
    standoffs = np.asarray(s.standoffs_mm, float)
    n_r = len(rays.hit_object)
    ri, di, ti = np.meshgrid(
        np.arange(n_r), np.arange(len(standoffs)), np.arange(len(rolls)), indexing="ij"
    )
    ri, di, ti = ri.ravel(), di.ravel(), ti.ravel()
    approach = -rays.normal_object
    R = np.stack(
        [
            palm_orientation(approach[r], BF_HAND_VECTOR_PALM, roll0_hint(approach[r]), rolls[t])
            for r, t in zip(ri, ti, strict=True)
        ]
    ).reshape(len(ri), 3, 3)
    ids = tuple(
        f"{key}/bf/f{rays.face[r]}/i{rays.ij[r, 0]:02d}j{rays.ij[r, 1]:02d}/d{d}/t{t}"
        for r, d, t in zip(ri, di, ti, strict=True)
    )
    target = rays.hit_object[0] if n_r else np.asarray(obj.centroid_object, float)
    return BruteForceHypotheses(
        object_key=key,
        ids=ids,
        ray_index=ri,
        standoff_index=di,
        roll_index=ti,
        ray_object=rays.normal_object[ri],
        target_object=np.asarray(target, float),
        standoff_mm=standoffs[di],
        roll_rad=rolls[ti],
        R_object_palm=R,
        hit_object=rays.hit_object,
        face=rays.face,
        ij=rays.ij,
        n_cast=rays.n_cast,
    )


#: Named hypothesis sets of the brute-force comparison (``app.sim.hypothesis_sets``).
BF_SETS: dict[str, BruteForceSettings] = {
    "brute_force": BruteForceSettings(),
    "brute_force_nodup": BruteForceSettings(drop_duplicate_roll=True),
}


def bf_store_suffix(settings: BruteForceSettings) -> str:
    """Suffix of the store's object key for a brute-force set.

    ``':bf'`` for the METHOD grid; the roll-duplicate flag only removes ids, so both named
    sets share it. Any other grid gets ``':bf-<hash>'``.
    """
    from app.hashing import stable_hash

    grid = dataclasses.replace(settings, drop_duplicate_roll=False)
    if grid == BruteForceSettings():
        return ":bf"
    return ":bf-" + stable_hash(dataclasses.asdict(grid))[:8]
