"""Exact distance between convex shapes by GJK, compiled with numba (the compiled engine).

Shapes are described by flat numbers so that whole closing problems fit in arrays:

- ``type`` (int): ``POINTS`` (convex hull of vertices: an ``fcl.Convex`` piece), ``BOX``
  (``prm`` = half extents), ``CYLINDER`` (``prm[0]`` = radius, ``prm[1]`` = half length, axis
  z of the shape frame), ``CAPSULE`` (``prm[0]`` = radius, ``prm[1]`` = half length, axis z),
  ``SPHERE`` (``prm[0]`` = radius); FCL's conventions (centred in their frame).
- a pose (R (3, 3), t (3,)) placing the shape frame in the world;
- for ``POINTS``, rows ``verts[v0:v1]`` of a shared (V, 3) array (shape frame).

Capsules and spheres are run as their core (segment, point) and their radius subtracted
afterwards, so every support function is exact and the only curved core is the cylinder.
GJK keeps a simplex of at most four Minkowski-difference points; the point of its hull
nearest the origin is found by enumerating its (at most 15) faces, solving each face's
affine projection and keeping the smallest candidate whose barycentric weights are all
non-negative (slower than Johnson's recursion in theory, but without its sign-of-determinant
pitfalls on near-degenerate simplices). The iteration ends when the duality gap
|v|² − v·w is below ``EPS_REL`` · |v|² plus a roundoff floor, so the returned distance is
within about 1e-9 mm of the true one (tests compare it with FCL on random poses).
Intersecting cores return the (non-positive) value ``-margins``: a touching indicator,
not a penetration depth (the closing never needs the depth, only the sign).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

POINTS = 0
BOX = 1
CYLINDER = 2
CAPSULE = 3
SPHERE = 4

#: Relative duality-gap tolerance of GJK on |v|² (distance error ~ EPS_REL/2 · distance).
EPS_REL = 1e-12
#: Absolute floor of the duality gap (mm²): roundoff of coordinates ~100 mm.
EPS_ABS = 1e-18
#: Iteration cap (curved cylinder cores converge linearly; polytopes in a few steps).
MAX_ITERS = 128


#: A ``POINTS`` shape with at least this many vertices and a neighbour table is searched by
#: climbing its hull's edges (``_support_local``) instead of scanning every vertex.
CLIMB_MIN_VERTS = 256
#: The climb of a query's first support starts at the best of about this many vertices.
CLIMB_SEEDS = 32


@njit(cache=True, inline="always")
def _support_local(
    typ: int, prm: np.ndarray, verts: np.ndarray, nbr_start: np.ndarray, nbr: np.ndarray,
    v0: int, v1: int, d: np.ndarray, out: np.ndarray, hint: np.ndarray, h: int,
) -> None:  # fmt: skip
    """Support point of a shape's core in its own frame along direction ``d`` -> ``out``.

    A ``POINTS`` shape whose vertices have a neighbour table (``nbr[nbr_start[i]:
    nbr_start[i + 1]]``: the vertices joined to vertex i by a hull edge; ``hull_neighbours``)
    is searched by steepest ascent along the edges from ``hint[h]`` (the last support found
    in this query; for its first, the best of ``CLIMB_SEEDS`` evenly spread hull vertices),
    which ends at a global maximum: a vertex of a convex polytope that no
    edge-neighbour beats maximises any linear function over the polytope (the simplex
    method's optimality). Otherwise every vertex is scanned."""
    if typ == POINTS:
        ib = -1
        best = -1e300
        if v1 - v0 >= CLIMB_MIN_VERTS and nbr_start.shape[0] > v1 and nbr_start[v1] > nbr_start[v0]:
            ib = hint[h]
            if ib < v0 or ib >= v1 or nbr_start[ib] == nbr_start[ib + 1]:
                # a query's first support: start at the best hull vertex of a sample
                ib = -1
                for i in range(v0, v1, max(1, (v1 - v0) // CLIMB_SEEDS)):
                    sv = verts[i, 0] * d[0] + verts[i, 1] * d[1] + verts[i, 2] * d[2]
                    if sv > best and nbr_start[i + 1] > nbr_start[i]:
                        best = sv
                        ib = i
            if ib >= 0:
                best = verts[ib, 0] * d[0] + verts[ib, 1] * d[1] + verts[ib, 2] * d[2]
                while True:
                    nxt = ib
                    for e in range(nbr_start[ib], nbr_start[ib + 1]):
                        j = nbr[e]
                        sj = verts[j, 0] * d[0] + verts[j, 1] * d[1] + verts[j, 2] * d[2]
                        if sj > best:
                            best = sj
                            nxt = j
                    if nxt == ib:
                        break
                    ib = nxt
                hint[h] = ib
        if ib < 0:  # no table, or no hull vertex in the sample: scan every vertex
            best = -1e300
            ib = v0
            for i in range(v0, v1):
                sv = verts[i, 0] * d[0] + verts[i, 1] * d[1] + verts[i, 2] * d[2]
                if sv > best:
                    best = sv
                    ib = i
        out[0] = verts[ib, 0]
        out[1] = verts[ib, 1]
        out[2] = verts[ib, 2]
    elif typ == BOX:
        for j in range(3):
            out[j] = prm[j] if d[j] >= 0.0 else -prm[j]
    elif typ == CYLINDER:
        n = math.sqrt(d[0] * d[0] + d[1] * d[1])
        if n > 0.0:
            out[0] = prm[0] * d[0] / n
            out[1] = prm[0] * d[1] / n
        else:
            out[0] = 0.0
            out[1] = 0.0
        out[2] = prm[1] if d[2] >= 0.0 else -prm[1]
    elif typ == CAPSULE:
        out[0] = 0.0
        out[1] = 0.0
        out[2] = prm[1] if d[2] >= 0.0 else -prm[1]
    else:  # SPHERE core: its centre
        out[0] = 0.0
        out[1] = 0.0
        out[2] = 0.0


def hull_neighbours(verts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(nbr_start (V + 1,), nbr) of a point set (V, 3): the vertices joined to vertex i by an
    edge of the convex hull (triangulated) are ``nbr[nbr_start[i]:nbr_start[i + 1]]``; a
    point that is not a hull vertex (inside, or on a face) has none. Raises scipy's
    ``QhullError`` on a flat or degenerate set (the caller then scans every vertex)."""
    from scipy.spatial import ConvexHull

    hull = ConvexHull(np.asarray(verts, float))
    t = hull.simplices  # (F, 3)
    e = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
    e = np.unique(np.concatenate([e, e[:, ::-1]]), axis=0)  # both directions, sorted by source
    nbr_start = np.searchsorted(e[:, 0], np.arange(len(verts) + 1)).astype(np.int64)
    return nbr_start, np.ascontiguousarray(e[:, 1], np.int64)


@njit(cache=True, inline="always")
def margin(typ: int, prm: np.ndarray) -> float:
    """The radius swept around a shape's core (capsule, sphere), else 0."""
    if typ == CAPSULE or typ == SPHERE:
        return prm[0]
    return 0.0


@njit(cache=True)
def _closest_on_simplex(
    S: np.ndarray, n: int, v: np.ndarray, keep: np.ndarray, wk: np.ndarray, idx: np.ndarray
) -> int:
    """Point of conv(S[:n]) nearest the origin -> ``v``; the face used -> ``keep`` (its point
    indices, returned count). Returns 0 if no face qualifies (cannot happen for n >= 1).
    ``wk`` (9, 3) and ``idx`` (4,) are scratch."""
    best = 1e300
    nbest = 0
    e = wk[0:3]
    G = wk[3:6]
    b = wk[6]
    mu = wk[7]
    c = wk[8]
    for mask in range(1, 1 << n):
        m = 0
        for i in range(n):
            if mask & (1 << i):
                idx[m] = i
                m += 1
        p0 = S[idx[0]]
        ok = True
        if m == 1:
            c[0], c[1], c[2] = p0[0], p0[1], p0[2]
        else:
            k = m - 1
            for i in range(k):
                for j in range(3):
                    e[i, j] = S[idx[i + 1], j] - p0[j]
            for i in range(k):
                b[i] = -(e[i, 0] * p0[0] + e[i, 1] * p0[1] + e[i, 2] * p0[2])
                for j in range(i, k):
                    g = e[i, 0] * e[j, 0] + e[i, 1] * e[j, 1] + e[i, 2] * e[j, 2]
                    G[i, j] = g
                    G[j, i] = g
            if k == 1:
                if G[0, 0] <= 1e-30:
                    ok = False
                else:
                    mu[0] = b[0] / G[0, 0]
            elif k == 2:
                det = G[0, 0] * G[1, 1] - G[0, 1] * G[1, 0]
                if det <= 1e-14 * G[0, 0] * G[1, 1] or det <= 1e-300:
                    ok = False
                else:
                    mu[0] = (b[0] * G[1, 1] - G[0, 1] * b[1]) / det
                    mu[1] = (G[0, 0] * b[1] - G[1, 0] * b[0]) / det
            else:
                c00 = G[1, 1] * G[2, 2] - G[1, 2] * G[2, 1]
                c01 = G[1, 2] * G[2, 0] - G[1, 0] * G[2, 2]
                c02 = G[1, 0] * G[2, 1] - G[1, 1] * G[2, 0]
                det = G[0, 0] * c00 + G[0, 1] * c01 + G[0, 2] * c02
                if det <= 1e-14 * G[0, 0] * G[1, 1] * G[2, 2] or det <= 1e-300:
                    ok = False
                else:
                    c10 = G[0, 2] * G[2, 1] - G[0, 1] * G[2, 2]
                    c11 = G[0, 0] * G[2, 2] - G[0, 2] * G[2, 0]
                    c12 = G[0, 1] * G[2, 0] - G[0, 0] * G[2, 1]
                    c20 = G[0, 1] * G[1, 2] - G[0, 2] * G[1, 1]
                    c21 = G[0, 2] * G[1, 0] - G[0, 0] * G[1, 2]
                    c22 = G[0, 0] * G[1, 1] - G[0, 1] * G[1, 0]
                    mu[0] = (c00 * b[0] + c10 * b[1] + c20 * b[2]) / det
                    mu[1] = (c01 * b[0] + c11 * b[1] + c21 * b[2]) / det
                    mu[2] = (c02 * b[0] + c12 * b[1] + c22 * b[2]) / det
            if ok:
                lam0 = 1.0
                for i in range(k):
                    lam0 -= mu[i]
                    if mu[i] < 0.0:
                        ok = False
                if lam0 < 0.0:
                    ok = False
            if ok:
                for j in range(3):
                    s = p0[j]
                    for i in range(k):
                        s += mu[i] * e[i, j]
                    c[j] = s
        if ok:
            nn = c[0] * c[0] + c[1] * c[1] + c[2] * c[2]
            if nn < best:
                best = nn
                v[0], v[1], v[2] = c[0], c[1], c[2]
                for i in range(m):
                    keep[i] = idx[i]
                nbest = m
    return nbest


#: An empty neighbour table: every ``POINTS`` shape is scanned.
NO_NEIGHBOURS = np.zeros(1, np.int64)


@njit(cache=True)
def core_distance(
    ta: int,
    pa: np.ndarray,
    Ra: np.ndarray,
    tra: np.ndarray,
    tb: int,
    pb: np.ndarray,
    Rb: np.ndarray,
    trb: np.ndarray,
    verts: np.ndarray,
    va0: int,
    va1: int,
    vb0: int,
    vb1: int,
) -> float:
    """Distance between the cores of shapes a and b (0 when they intersect); every vertex
    of a ``POINTS`` shape is scanned (``core_distance_nbr``)."""
    return core_distance_nbr(ta, pa, Ra, tra, tb, pb, Rb, trb, verts, NO_NEIGHBOURS,
                             NO_NEIGHBOURS, va0, va1, vb0, vb1)  # fmt: skip


@njit(cache=True)
def core_distance_nbr(
    ta: int,
    pa: np.ndarray,
    Ra: np.ndarray,
    tra: np.ndarray,
    tb: int,
    pb: np.ndarray,
    Rb: np.ndarray,
    trb: np.ndarray,
    verts: np.ndarray,
    nbr_start: np.ndarray,
    nbr: np.ndarray,
    va0: int,
    va1: int,
    vb0: int,
    vb1: int,
) -> float:
    """Distance between the cores of shapes a and b (0 when they intersect), with the
    vertices' hull-edge neighbours (``_support_local``; ``nbr_start`` covers every row of
    ``verts`` or is ``NO_NEIGHBOURS``).

    The computation runs in b's frame (a is moved there once)."""
    # a's pose in b's frame: R = Rb^T Ra, t = Rb^T (ta - tb)
    R = np.empty((3, 3))
    t = np.empty(3)
    for i in range(3):
        s = 0.0
        for j in range(3):
            s += Rb[j, i] * (tra[j] - trb[j])
            acc = 0.0
            for k in range(3):
                acc += Rb[k, i] * Ra[k, j]
            R[i, j] = acc
        t[i] = s
    S = np.empty((4, 3))
    S2 = np.empty((4, 3))
    keep = np.empty(4, np.int64)
    v = np.empty(3)
    d = np.empty(3)
    dl = np.empty(3)
    sa = np.empty(3)
    sb = np.empty(3)
    w = np.empty(3)
    vn = np.empty(3)
    wk = np.empty((9, 3))
    idx = np.empty(4, np.int64)
    hint = np.full(2, -1, np.int64)  # the last support vertex of a and of b (none yet)

    def minkowski(dir_: np.ndarray) -> None:  # w = s_a(dir) - s_b(-dir), b frame
        for i in range(3):
            dl[i] = R[0, i] * dir_[0] + R[1, i] * dir_[1] + R[2, i] * dir_[2]
        _support_local(ta, pa, verts, nbr_start, nbr, va0, va1, dl, sa, hint, 0)
        for i in range(3):
            d[i] = -dir_[i]
        _support_local(tb, pb, verts, nbr_start, nbr, vb0, vb1, d, sb, hint, 1)
        for i in range(3):
            w[i] = R[i, 0] * sa[0] + R[i, 1] * sa[1] + R[i, 2] * sa[2] + t[i] - sb[i]

    # initial direction: from b's origin towards a's
    init = np.empty(3)
    init[0], init[1], init[2] = -t[0], -t[1], -t[2]
    if init[0] * init[0] + init[1] * init[1] + init[2] * init[2] < 1e-24:
        init[0] = 1.0
    minkowski(init)
    S[0] = w
    n = 1
    v[0], v[1], v[2] = w[0], w[1], w[2]
    vv = v[0] * v[0] + v[1] * v[1] + v[2] * v[2]
    for _ in range(MAX_ITERS):
        if vv <= 1e-24:
            return 0.0
        for i in range(3):
            d[i] = -v[i]
        minkowski(d)  # w = support of the difference along -v
        vw = v[0] * w[0] + v[1] * w[1] + v[2] * w[2]
        if vv - vw <= EPS_REL * vv + EPS_ABS:
            break
        dup = False
        for i in range(n):
            if S[i, 0] == w[0] and S[i, 1] == w[1] and S[i, 2] == w[2]:
                dup = True
        if dup:
            break
        S[n] = w
        n += 1
        m = _closest_on_simplex(S, n, vn, keep, wk, idx)
        vvn = vn[0] * vn[0] + vn[1] * vn[1] + vn[2] * vn[2]
        if vvn >= vv:  # no progress: numerical floor reached
            break
        for i in range(m):
            S2[i] = S[keep[i]]
        for i in range(m):
            S[i] = S2[i]
        n = m
        v[0], v[1], v[2] = vn[0], vn[1], vn[2]
        vv = vvn
        if n == 4:  # origin inside the tetrahedron
            return 0.0
    return math.sqrt(vv)


#: Bisection steps of ``_segment_cylinder``: the bracket shrinks by 2**-60 of the segment.
SEGMENT_CYLINDER_ITERS = 60


@njit(cache=True, inline="always")
def _cylinder_gap(r: float, h: float, x: float, y: float, z: float) -> tuple[float, float, float]:
    """The vector from a solid cylinder's nearest point (radius r, half length h, axis z) to
    the point (x, y, z); zero inside."""
    rho = math.sqrt(x * x + y * y)
    k = 1.0 - r / rho if rho > r else 0.0
    gz = z - h if z > h else (z + h if z < -h else 0.0)
    return x * k, y * k, gz


@njit(cache=True)
def _segment_cylinder(
    r: float, h: float, ax: float, ay: float, az: float, bx: float, by: float, bz: float
) -> float:
    """Distance from the segment a–b to a solid cylinder (radius r, half length h, axis z;
    the points in its frame), 0 when they meet. The distance of p(t) = a + t (b − a) to a
    convex set is convex in t and differentiable where positive, so the minimum is where the
    derivative's sign, sign(gap(p(t)) · (b − a)), changes: bisection to 2**-60 of the
    segment, the value then exact to rounding (the error is second order in t). GJK's
    iteration converges only linearly on the cylinder's curved side (up to ``MAX_ITERS``
    steps when a capsule lies along the wall); this is a few dozen flops per step, in
    scalars (no arrays: numba's small allocations would cost as much as the arithmetic)."""
    d0, d1, d2 = bx - ax, by - ay, bz - az
    g0, g1, g2 = _cylinder_gap(r, h, ax, ay, az)
    if g0 == 0.0 and g1 == 0.0 and g2 == 0.0:
        return 0.0
    if g0 * d0 + g1 * d1 + g2 * d2 >= 0.0:  # moving along the segment only goes away
        return math.sqrt(g0 * g0 + g1 * g1 + g2 * g2)
    g0, g1, g2 = _cylinder_gap(r, h, bx, by, bz)
    if g0 == 0.0 and g1 == 0.0 and g2 == 0.0:
        return 0.0
    if g0 * d0 + g1 * d1 + g2 * d2 <= 0.0:  # b is nearest
        return math.sqrt(g0 * g0 + g1 * g1 + g2 * g2)
    lo, hi = 0.0, 1.0
    best = np.inf
    for _ in range(SEGMENT_CYLINDER_ITERS):
        t = 0.5 * (lo + hi)
        g0, g1, g2 = _cylinder_gap(r, h, ax + t * d0, ay + t * d1, az + t * d2)
        dist2 = g0 * g0 + g1 * g1 + g2 * g2
        if dist2 == 0.0:
            return 0.0
        if dist2 < best:
            best = dist2
        if g0 * d0 + g1 * d1 + g2 * d2 < 0.0:
            lo = t
        else:
            hi = t
    return math.sqrt(best)


@njit(cache=True)
def _capsule_cylinder(
    ha: float, Ra: np.ndarray, tra: np.ndarray, pb: np.ndarray, Rb: np.ndarray, trb: np.ndarray
) -> float:
    """Distance between a capsule's or sphere's core (segment ±ha on its z axis; a point for
    ha = 0) and a cylinder's, in the cylinder's frame (``_segment_cylinder``)."""
    c0 = Rb[0, 0] * (tra[0] - trb[0]) + Rb[1, 0] * (tra[1] - trb[1]) + Rb[2, 0] * (tra[2] - trb[2])
    c1 = Rb[0, 1] * (tra[0] - trb[0]) + Rb[1, 1] * (tra[1] - trb[1]) + Rb[2, 1] * (tra[2] - trb[2])
    c2 = Rb[0, 2] * (tra[0] - trb[0]) + Rb[1, 2] * (tra[1] - trb[1]) + Rb[2, 2] * (tra[2] - trb[2])
    a0 = ha * (Rb[0, 0] * Ra[0, 2] + Rb[1, 0] * Ra[1, 2] + Rb[2, 0] * Ra[2, 2])
    a1 = ha * (Rb[0, 1] * Ra[0, 2] + Rb[1, 1] * Ra[1, 2] + Rb[2, 1] * Ra[2, 2])
    a2 = ha * (Rb[0, 2] * Ra[0, 2] + Rb[1, 2] * Ra[1, 2] + Rb[2, 2] * Ra[2, 2])
    return _segment_cylinder(pb[0], pb[1], c0 - a0, c1 - a1, c2 - a2, c0 + a0, c1 + a1, c2 + a2)


@njit(cache=True, inline="always")
def _point_segment2(
    px: float, py: float, pz: float, qx: float, qy: float, qz: float,
    dx: float, dy: float, dz: float, dd: float,
) -> float:  # fmt: skip
    """Squared distance from a point to the segment q + u d, u in [0, 1] (dd = d·d)."""
    u = 0.0
    if dd > 0.0:
        u = min(max(((px - qx) * dx + (py - qy) * dy + (pz - qz) * dz) / dd, 0.0), 1.0)
    x, y, z = px - qx - u * dx, py - qy - u * dy, pz - qz - u * dz
    return x * x + y * y + z * z


@njit(cache=True)
def _segment_segment(
    ha: float, Ra: np.ndarray, tra: np.ndarray, hb: float, Rb: np.ndarray, trb: np.ndarray
) -> float:
    """Distance between the segments ±ha and ±hb along the z axes of two frames (capsule
    cores; a point for a half length of 0), closed form, in scalars. The nearest pair is
    either interior to both (where the two lines' nearest points fall inside both segments)
    or has an end of one: the smallest of those five candidates, each an actual pair of
    points, so the result never falls below the true distance and (near-)parallel segments,
    whose interior solution is ill-conditioned, are exact through their ends."""
    u0, u1, u2 = 2.0 * ha * Ra[0, 2], 2.0 * ha * Ra[1, 2], 2.0 * ha * Ra[2, 2]  # d1
    w0, w1, w2 = 2.0 * hb * Rb[0, 2], 2.0 * hb * Rb[1, 2], 2.0 * hb * Rb[2, 2]  # d2
    p0, p1, p2 = tra[0] - 0.5 * u0, tra[1] - 0.5 * u1, tra[2] - 0.5 * u2
    q0, q1, q2 = trb[0] - 0.5 * w0, trb[1] - 0.5 * w1, trb[2] - 0.5 * w2
    a = u0 * u0 + u1 * u1 + u2 * u2
    e = w0 * w0 + w1 * w1 + w2 * w2
    best = _point_segment2(p0, p1, p2, q0, q1, q2, w0, w1, w2, e)
    best = min(best, _point_segment2(p0 + u0, p1 + u1, p2 + u2, q0, q1, q2, w0, w1, w2, e))
    best = min(best, _point_segment2(q0, q1, q2, p0, p1, p2, u0, u1, u2, a))
    best = min(best, _point_segment2(q0 + w0, q1 + w1, q2 + w2, p0, p1, p2, u0, u1, u2, a))
    b = u0 * w0 + u1 * w1 + u2 * w2
    den = a * e - b * b
    if den > 0.0:
        r0, r1, r2 = p0 - q0, p1 - q1, p2 - q2
        c = u0 * r0 + u1 * r1 + u2 * r2
        f = w0 * r0 + w1 * r1 + w2 * r2
        s = (b * f - c * e) / den
        t = (a * f - b * c) / den
        if 0.0 < s < 1.0 and 0.0 < t < 1.0:
            x = r0 + s * u0 - t * w0
            y = r1 + s * u1 - t * w1
            z = r2 + s * u2 - t * w2
            best = min(best, x * x + y * y + z * z)
    return math.sqrt(best)


@njit(cache=True)
def shape_distance(
    ta: int,
    pa: np.ndarray,
    Ra: np.ndarray,
    tra: np.ndarray,
    tb: int,
    pb: np.ndarray,
    Rb: np.ndarray,
    trb: np.ndarray,
    verts: np.ndarray,
    va0: int,
    va1: int,
    vb0: int,
    vb1: int,
) -> float:
    """Distance between shapes a and b, mm (cores' distance minus the margins): capsules and
    spheres against a cylinder or each other in closed form, the rest by GJK scanning every
    vertex (``shape_distance_nbr``)."""
    return shape_distance_nbr(ta, pa, Ra, tra, tb, pb, Rb, trb, verts, NO_NEIGHBOURS,
                              NO_NEIGHBOURS, va0, va1, vb0, vb1)  # fmt: skip


@njit(cache=True)
def shape_distance_nbr(
    ta: int,
    pa: np.ndarray,
    Ra: np.ndarray,
    tra: np.ndarray,
    tb: int,
    pb: np.ndarray,
    Rb: np.ndarray,
    trb: np.ndarray,
    verts: np.ndarray,
    nbr_start: np.ndarray,
    nbr: np.ndarray,
    va0: int,
    va1: int,
    vb0: int,
    vb1: int,
) -> float:
    """``shape_distance`` with the vertices' hull-edge neighbours (``core_distance_nbr``).
    Capsules and spheres against each other take the closed form (``_segment_segment``)."""
    if (ta == CAPSULE or ta == SPHERE) and (tb == CAPSULE or tb == SPHERE):
        dc = _segment_segment(pa[1] if ta == CAPSULE else 0.0, Ra, tra,
                              pb[1] if tb == CAPSULE else 0.0, Rb, trb)  # fmt: skip
    elif tb == CYLINDER and (ta == CAPSULE or ta == SPHERE):
        dc = _capsule_cylinder(pa[1] if ta == CAPSULE else 0.0, Ra, tra, pb, Rb, trb)
    elif ta == CYLINDER and (tb == CAPSULE or tb == SPHERE):
        dc = _capsule_cylinder(pb[1] if tb == CAPSULE else 0.0, Rb, trb, pa, Ra, tra)
    else:
        dc = core_distance_nbr(ta, pa, Ra, tra, tb, pb, Rb, trb, verts, nbr_start, nbr,
                               va0, va1, vb0, vb1)  # fmt: skip
    return dc - margin(ta, pa) - margin(tb, pb)


def describe_fcl_geometry(geom: object) -> tuple[int, np.ndarray] | None:
    """(type, prm (3,)) of an FCL primitive; None for Convex/BVH (vertices needed)."""
    import fcl

    prm = np.zeros(3)
    if isinstance(geom, fcl.Box):
        prm[:] = 0.5 * np.asarray(geom.side, float)
        return BOX, prm
    if isinstance(geom, fcl.Cylinder):
        prm[0], prm[1] = geom.radius, 0.5 * geom.lz
        return CYLINDER, prm
    if isinstance(geom, fcl.Capsule):
        prm[0], prm[1] = geom.radius, 0.5 * geom.lz
        return CAPSULE, prm
    if isinstance(geom, fcl.Sphere):
        prm[0] = geom.radius
        return SPHERE, prm
    return None
