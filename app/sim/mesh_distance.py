"""Distance from a hand link (capsule or box) to an imported mesh, for the compiled engine.

FCL answers a capsule against a 65k-triangle ``BVHModel`` in about 2 ms; the closing asks
dozens of such queries per hypothesis. Here the mesh's distance field
(``app.model.objects.distance_field``) does the screening, and GJK (``app.sim.gjk``) the
exact part:

1. **Lower bound.** The link lies within ``reach`` of its centre c, so its distance to the
   surface is at least ``sdf(c) - reach`` (less the field's error where sdf(c) is
   interpolated, ~1.25 h; outside the grid the distance to the mesh's box). When that
   exceeds ``exact_above`` the bound is returned as it is: the closing only needs exact
   values near a stop (its conservative advancement takes lower bounds), and the callers
   pass a threshold above the stop tolerance.
2. **Upper bound.** Points of the link (the capsule's centre and axis points less its
   radius, the box's centre and corners) whose distance is exact bound the distance from
   above: ``U = min sdf(x) - margin``; the centre's interpolated value plus its error, or the
   farthest corner of the mesh's box, when none is exact.
3. **Exact.** The triangles in the buckets within ``U`` of the link's core, each screened by
   its bounding sphere against the best distance so far, go to GJK (triangle = a 3-vertex
   convex shape): the minimum is the exact link-to-surface distance (to GJK's ~1e-9 mm).

The surface is what FCL's BVH sees too: a link wholly inside the object is not "in
contact"; the closing never gets there from outside without crossing the surface.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from app.model.objects.distance_field import EXACT, INTERPOLATED, MeshPack, point_sdf_kind
from app.sim import gjk

#: Obstacle type code of a mesh in ``ObstacleArrays.typ`` (after gjk's shape types).
MESH = 9


@njit(cache=True)
def _point_core_distance(typ: int, prm: np.ndarray, R: np.ndarray, t: np.ndarray,
                         x: np.ndarray) -> float:  # fmt: skip
    """Distance from point x to the core of a capsule (its segment) or a box (the solid)."""
    lx = np.empty(3)
    for i in range(3):
        lx[i] = R[0, i] * (x[0] - t[0]) + R[1, i] * (x[1] - t[1]) + R[2, i] * (x[2] - t[2])
    if typ == gjk.CAPSULE:
        z = min(max(lx[2], -prm[1]), prm[1])
        return math.sqrt(lx[0] * lx[0] + lx[1] * lx[1] + (lx[2] - z) * (lx[2] - z))
    s = 0.0
    for i in range(3):
        d = abs(lx[i]) - prm[i]
        if d > 0:
            s += d * d
    return math.sqrt(s)


#: Buckets per block edge (blocks are screened before their buckets).
BLOCK = 4


@njit(cache=True)
def _bucket_triangles(
    typ: int, prm: np.ndarray, R: np.ndarray, t: np.ndarray, b: int, b_start: np.ndarray,
    b_ids: np.ndarray, V: np.ndarray, F: np.ndarray, tri_c: np.ndarray, tri_r: np.ndarray,
    stamp: np.ndarray, qid: int, margin: float, best: float, tverts: np.ndarray,
) -> float:  # fmt: skip
    """min(best, the link's exact distance to each triangle of bucket b not yet seen)."""
    eye = np.eye(3)
    zero = np.zeros(3)
    tri_prm = np.zeros(3)
    for e in range(b_start[b], b_start[b + 1]):
        f = b_ids[e]
        if stamp[f] == qid:
            continue
        stamp[f] = qid
        if _point_core_distance(typ, prm, R, t, tri_c[f]) - tri_r[f] - margin > best:
            continue
        for i in range(3):
            for j in range(3):
                tverts[i, j] = V[F[f, i], j]
        d = gjk.shape_distance(typ, prm, R, t, gjk.POINTS, tri_prm, eye, zero, tverts,
                               0, 0, 0, 3)  # fmt: skip
        if d < best:
            best = d
    return best


@njit(cache=True)
def mesh_distance(
    typ: int, prm: np.ndarray, R: np.ndarray, t: np.ndarray, pk: MeshPack, exact_above: float
) -> float:
    """Distance (mm) from a link (``gjk.CAPSULE`` or ``gjk.BOX`` posed at R, t; object frame)
    to the mesh of ``pk``: exact when it may be below ``exact_above``, else a lower bound."""
    (_o, h, _v, _band, _lo, _hi, V, F, _nf, _ne, _nv, b_origin, b_size, b_shape,
     b_start, b_ids, tri_c, tri_r, stamp, ctr) = pk  # fmt: skip
    if typ == gjk.CAPSULE:
        margin = prm[0]
        reach = prm[1] + prm[0]
    else:
        margin = 0.0
        reach = math.sqrt(prm[0] * prm[0] + prm[1] * prm[1] + prm[2] * prm[2])
    d_c, kind_c = point_sdf_kind(pk, t[0], t[1], t[2])
    slack = 1.5 * h  # interpolated (far) values err by at most ~1.25 h
    # distances to the surface (as FCL's BVH measures them): |sdf|, inside or out
    a_c = abs(d_c)
    if kind_c == EXACT:
        if a_c - reach > exact_above:
            return a_c - reach
    elif kind_c == INTERPOLATED:
        if a_c - slack - reach > exact_above:
            return a_c - slack - reach
    elif d_c - reach > exact_above:  # outside the grid: d_c bounds from below
        return d_c - reach
    # an upper bound: exact distances of points of the link (less the capsule's radius:
    # the points are on its axis), or, failing those, one from the centre's bound
    if kind_c == EXACT:
        upper = a_c - margin
    elif kind_c == INTERPOLATED:
        upper = a_c + slack - margin
    else:  # outside the grid: the farthest corner of the mesh's box is a surface bound
        far2 = 0.0
        for a in range(3):
            e = max(abs(t[a] - _lo[a]), abs(t[a] - _hi[a]))
            far2 += e * e
        upper = math.sqrt(far2) - margin
    x = np.empty(3)
    n_pts = 5 if typ == gjk.CAPSULE else 8
    for k in range(n_pts):
        if typ == gjk.CAPSULE:
            z = -prm[1] + 2 * prm[1] * k / 4
            for i in range(3):
                x[i] = t[i] + R[i, 2] * z
        else:
            for i in range(3):
                x[i] = t[i]
                for j in range(3):
                    sg = 1.0 if (k >> j) & 1 else -1.0
                    x[i] += R[i, j] * sg * prm[j]
        d, kind = point_sdf_kind(pk, x[0], x[1], x[2])
        if kind == EXACT:
            upper = min(upper, abs(d) - margin)
    # exact: triangles of the buckets within `upper` (+ the margin) of the core
    r = max(upper + margin, 0.0) + 1e-6
    lo_b = np.empty(3, np.int64)
    hi_b = np.empty(3, np.int64)
    for a in range(3):
        ext = abs(R[a, 0]) * (prm[0] if typ != gjk.CAPSULE else 0.0)
        ext += abs(R[a, 1]) * (prm[1] if typ != gjk.CAPSULE else 0.0)
        ext += abs(R[a, 2]) * prm[2 if typ != gjk.CAPSULE else 1]
        lo_b[a] = max(int(math.floor((t[a] - ext - r - b_origin[a]) / b_size)), 0)
        hi_b[a] = min(int(math.floor((t[a] + ext + r - b_origin[a]) / b_size)), b_shape[a] - 1)
    nby, nbz = b_shape[1], b_shape[2]
    half_diag = 0.8660254037844387 * b_size
    ctr[0] += 1
    qid = ctr[0]
    best = upper
    bc = np.empty(3)
    bq = np.empty(3)
    tverts = np.empty((3, 3))
    # blocks of BLOCK³ buckets first: a block farther from the core than best is skipped
    blk_half_diag = 0.8660254037844387 * BLOCK * b_size
    for si in range(lo_b[0] // BLOCK, hi_b[0] // BLOCK + 1):
        bc[0] = b_origin[0] + (si + 0.5) * BLOCK * b_size
        for sj in range(lo_b[1] // BLOCK, hi_b[1] // BLOCK + 1):
            bc[1] = b_origin[1] + (sj + 0.5) * BLOCK * b_size
            for sk in range(lo_b[2] // BLOCK, hi_b[2] // BLOCK + 1):
                bc[2] = b_origin[2] + (sk + 0.5) * BLOCK * b_size
                if _point_core_distance(typ, prm, R, t, bc) - blk_half_diag - margin > best:
                    continue
                for bi in range(max(lo_b[0], si * BLOCK), min(hi_b[0], si * BLOCK + BLOCK - 1) + 1):
                    for bj in range(max(lo_b[1], sj * BLOCK),
                                    min(hi_b[1], sj * BLOCK + BLOCK - 1) + 1):  # fmt: skip
                        for bk in range(max(lo_b[2], sk * BLOCK),
                                        min(hi_b[2], sk * BLOCK + BLOCK - 1) + 1):  # fmt: skip
                            b = (bi * nby + bj) * nbz + bk
                            if b_start[b] == b_start[b + 1]:
                                continue
                            bq[0] = b_origin[0] + (bi + 0.5) * b_size
                            bq[1] = b_origin[1] + (bj + 0.5) * b_size
                            bq[2] = b_origin[2] + (bk + 0.5) * b_size
                            dq = _point_core_distance(typ, prm, R, t, bq)
                            if dq - half_diag - margin > best:
                                continue
                            best = _bucket_triangles(typ, prm, R, t, b, b_start, b_ids, V, F,
                                                     tri_c, tri_r, stamp, qid, margin, best,
                                                     tverts)  # fmt: skip
    return best
