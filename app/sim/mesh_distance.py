"""Distance from a hand link (capsule or box) to an imported mesh, for the compiled engine.

FCL answers a capsule against a 65k-triangle ``BVHModel`` in about 2 ms; the closing asks
dozens of such queries per hypothesis. Here the mesh's distance field
(``app.model.objects.distance_field``) does the screening, and GJK (``app.sim.gjk``) the
exact part:

1. **Bounds from the field.** The 8 grid nodes around a point bound its distance to the
   surface from both sides (``abs_bounds``: ``|node| ∓ node distance``). Taken at the
   capsule's axis points every 2 mm (less half a step and the radius) or at the box's centre
   (less its reach), they bound the link's distance. When the lower bound exceeds
   ``exact_above`` it is returned as it is: the closing only needs exact values near a stop
   (its conservative advancement takes lower bounds), and the callers pass a threshold above
   the stop tolerance.
2. **Candidates.** The upper bound U limits the search to the buckets within U of the link's
   core, screened in blocks of 4³ buckets, then bucket by bucket.
3. **Exact.** Each candidate triangle, screened by its bounding sphere against the best
   distance so far, is measured exactly: a capsule by the closed-form segment-triangle
   distance less its radius, a box by GJK (triangle = a 3-vertex convex shape). The minimum
   is the exact link-to-surface distance.

The surface is what FCL's BVH sees too: a link wholly inside the object is not "in
contact"; the closing never gets there from outside without crossing the surface.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from app.model.objects.distance_field import MeshPack, abs_bounds, closest_on_triangle
from app.sim import gjk

#: Obstacle type code of a mesh in ``ObstacleArrays.typ`` (after gjk's shape types).
MESH = 9


@njit(cache=True, inline="always")
def _point_core_distance(typ: int, prm: np.ndarray, R: np.ndarray, t: np.ndarray,
                         x: np.ndarray) -> float:  # fmt: skip
    """Distance from point x to the core of a capsule (its segment) or a box (the solid)."""
    return _xyz_core_distance(typ, prm, R, t, x[0], x[1], x[2])


@njit(cache=True, inline="always")
def _xyz_core_distance(typ: int, prm: np.ndarray, R: np.ndarray, t: np.ndarray, x0: float,
                       x1: float, x2: float) -> float:  # fmt: skip
    """``_point_core_distance`` of the point (x0, x1, x2) (scalars: no array is made)."""
    d0, d1, d2 = x0 - t[0], x1 - t[1], x2 - t[2]
    l0 = R[0, 0] * d0 + R[1, 0] * d1 + R[2, 0] * d2
    l1 = R[0, 1] * d0 + R[1, 1] * d1 + R[2, 1] * d2
    l2 = R[0, 2] * d0 + R[1, 2] * d1 + R[2, 2] * d2
    if typ == gjk.CAPSULE:
        z = min(max(l2, -prm[1]), prm[1])
        return math.sqrt(l0 * l0 + l1 * l1 + (l2 - z) * (l2 - z))
    e0 = max(abs(l0) - prm[0], 0.0)
    e1 = max(abs(l1) - prm[1], 0.0)
    e2 = max(abs(l2) - prm[2], 0.0)
    return math.sqrt(e0 * e0 + e1 * e1 + e2 * e2)


@njit(cache=True, inline="always")
def _seg_seg2(px1: float, py1: float, pz1: float, qx1: float, qy1: float, qz1: float,
              px2: float, py2: float, pz2: float, qx2: float, qy2: float, qz2: float
              ) -> float:  # fmt: skip
    """Squared distance between segments p1q1 and p2q2 (Ericson, Real-Time Collision
    Detection §5.1.9), on scalars."""
    d1x, d1y, d1z = qx1 - px1, qy1 - py1, qz1 - pz1
    d2x, d2y, d2z = qx2 - px2, qy2 - py2, qz2 - pz2
    rx, ry, rz = px1 - px2, py1 - py2, pz1 - pz2
    a = d1x * d1x + d1y * d1y + d1z * d1z
    e = d2x * d2x + d2y * d2y + d2z * d2z
    f = d2x * rx + d2y * ry + d2z * rz
    eps = 1e-18
    if a <= eps and e <= eps:
        return rx * rx + ry * ry + rz * rz
    if a <= eps:
        s = 0.0
        t = min(max(f / e, 0.0), 1.0)
    else:
        c = d1x * rx + d1y * ry + d1z * rz
        if e <= eps:
            t = 0.0
            s = min(max(-c / a, 0.0), 1.0)
        else:
            b = d1x * d2x + d1y * d2y + d1z * d2z
            den = a * e - b * b
            s = min(max((b * f - c * e) / den, 0.0), 1.0) if den > eps else 0.0
            t = (b * s + f) / e
            if t < 0.0:
                t = 0.0
                s = min(max(-c / a, 0.0), 1.0)
            elif t > 1.0:
                t = 1.0
                s = min(max((b - c) / a, 0.0), 1.0)
    wx = px1 + d1x * s - (px2 + d2x * t)
    wy = py1 + d1y * s - (py2 + d2y * t)
    wz = pz1 + d1z * s - (pz2 + d2z * t)
    return wx * wx + wy * wy + wz * wz


@njit(cache=True, inline="always")
def _cross_dot(ux: float, uy: float, uz: float, vx: float, vy: float, vz: float, nx: float,
               ny: float, nz: float) -> float:  # fmt: skip
    """(u × v) · n."""
    return (uy * vz - uz * vy) * nx + (uz * vx - ux * vz) * ny + (ux * vy - uy * vx) * nz


@njit(cache=True)
def segment_triangle_distance(
    s0: np.ndarray, s1: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray
) -> float:
    """Exact distance between segment s0s1 and triangle abc (0 when they meet): the segment
    crossing the triangle, else the least of its ends against the triangle and the segment
    against the triangle's three edges. Scalar arithmetic throughout (no array is made: this
    is the inner loop of a mesh query)."""
    ax, ay, az = a[0], a[1], a[2]
    bx, by, bz = b[0], b[1], b[2]
    cx, cy, cz = c[0], c[1], c[2]
    ux, uy, uz = bx - ax, by - ay, bz - az
    vx, vy, vz = cx - ax, cy - ay, cz - az
    nx, ny, nz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
    e0 = nx * (s0[0] - ax) + ny * (s0[1] - ay) + nz * (s0[2] - az)
    e1 = nx * (s1[0] - ax) + ny * (s1[1] - ay) + nz * (s1[2] - az)
    if (e0 <= 0.0 <= e1 or e1 <= 0.0 <= e0) and e0 != e1:
        w = e0 / (e0 - e1)
        xx = s0[0] + (s1[0] - s0[0]) * w
        xy = s0[1] + (s1[1] - s0[1]) * w
        xz = s0[2] + (s1[2] - s0[2]) * w
        # inside the triangle: the three edge tests agree in sign with n
        if (
            _cross_dot(ux, uy, uz, xx - ax, xy - ay, xz - az, nx, ny, nz) >= 0.0
            and _cross_dot(cx - bx, cy - by, cz - bz, xx - bx, xy - by, xz - bz, nx, ny, nz) >= 0.0
            and _cross_dot(ax - cx, ay - cy, az - cz, xx - cx, xy - cy, xz - cz, nx, ny, nz) >= 0.0
        ):
            return 0.0
    qx, qy, qz, _ = closest_on_triangle(s0[0], s0[1], s0[2], a, b, c)
    best = (s0[0] - qx) ** 2 + (s0[1] - qy) ** 2 + (s0[2] - qz) ** 2
    qx, qy, qz, _ = closest_on_triangle(s1[0], s1[1], s1[2], a, b, c)
    best = min(best, (s1[0] - qx) ** 2 + (s1[1] - qy) ** 2 + (s1[2] - qz) ** 2)
    p0, p1, p2, r0, r1, r2 = s0[0], s0[1], s0[2], s1[0], s1[1], s1[2]
    best = min(best, _seg_seg2(p0, p1, p2, r0, r1, r2, ax, ay, az, bx, by, bz))
    best = min(best, _seg_seg2(p0, p1, p2, r0, r1, r2, bx, by, bz, cx, cy, cz))
    best = min(best, _seg_seg2(p0, p1, p2, r0, r1, r2, cx, cy, cz, ax, ay, az))
    return math.sqrt(best)


#: Spacing (mm) of the capsule axis points whose field bounds screen a query.
AXIS_STEP_MM = 2.0

#: Buckets per block edge (blocks are screened before their buckets).
BLOCK = 4


@njit(cache=True)
def _bucket_triangles(
    typ: int, prm: np.ndarray, R: np.ndarray, t: np.ndarray, b: int, b_start: np.ndarray,
    b_ids: np.ndarray, V: np.ndarray, F: np.ndarray, tri_c: np.ndarray, tri_r: np.ndarray,
    stamp: np.ndarray, qid: int, margin: float, best: float, tverts: np.ndarray,
    s0: np.ndarray, s1: np.ndarray, eye: np.ndarray, zero: np.ndarray,
) -> float:  # fmt: skip
    """min(best, the link's exact distance to each triangle of bucket b not yet seen);
    ``s0``, ``s1``: a capsule's segment ends; ``eye``, ``zero``: a triangle's GJK frame."""
    for e in range(b_start[b], b_start[b + 1]):
        f = b_ids[e]
        if stamp[f] == qid:
            continue
        stamp[f] = qid
        if _point_core_distance(typ, prm, R, t, tri_c[f]) - tri_r[f] - margin > best:
            continue
        if typ == gjk.CAPSULE:  # closed form: segment against triangle, less the radius
            d = segment_triangle_distance(s0, s1, V[F[f, 0]], V[F[f, 1]], V[F[f, 2]]) - margin
        else:
            for i in range(3):
                for j in range(3):
                    tverts[i, j] = V[F[f, i], j]
            d = gjk.shape_distance(typ, prm, R, t, gjk.POINTS, zero, eye, zero, tverts,
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
    # rigorous bounds from the field's nodes at points of the link: the capsule's axis
    # every <= AXIS_STEP_MM (a point of the axis is within half a step of one of them), or
    # the box's centre (the box is within `reach` of it)
    lower = np.inf
    upper = np.inf
    if typ == gjk.CAPSULE:
        n_pts = max(2, int(math.ceil(2 * prm[1] / AXIS_STEP_MM)) + 1)
        half_step = prm[1] / (n_pts - 1)
        for k in range(n_pts):
            z = -prm[1] + 2 * prm[1] * k / (n_pts - 1)
            lo_k, hi_k = abs_bounds(pk, t[0] + R[0, 2] * z, t[1] + R[1, 2] * z, t[2] + R[2, 2] * z)
            lower = min(lower, lo_k)
            upper = min(upper, hi_k)
        lower -= half_step + margin
        upper -= margin
    else:
        lo_c, hi_c = abs_bounds(pk, t[0], t[1], t[2])
        lower = lo_c - reach
        upper = hi_c
    if lower > exact_above:
        return lower
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
    eye = np.eye(3)
    zero = np.zeros(3)
    s0 = np.empty(3)
    s1 = np.empty(3)
    for i in range(3):
        s0[i] = t[i] - R[i, 2] * prm[1]
        s1[i] = t[i] + R[i, 2] * prm[1]
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
                                                     tverts, s0, s1, eye, zero)  # fmt: skip
    return best
