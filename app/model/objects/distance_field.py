"""A signed distance field of a triangle mesh, built once and cached on disk (imported scans).

The exact signed distance of a mesh (closest point on 65k triangles, plus an inside test by
ray casting) costs trimesh about 1 ms per point in Python, which made a scan's contact
patches ~100 s per hypothesis. This field samples the exact signed distance on a regular
grid once per mesh, and answers queries by trilinear interpolation in compiled code.

How it is built (``build_field``):

- **Narrow band, exact.** Every grid node within ``band_mm`` of the surface gets its exact
  distance to the nearest triangle (a compiled loop over the triangles, each visiting the
  nodes of its bounding box grown by the band). Its sign is the side of the nearest
  feature's angle-weighted pseudo-normal (face, edge or vertex; Bærentzen & Aanæs 2005),
  which is exact for a watertight, consistently wound mesh; the importer guarantees that.
- **Far field, a lower bound.** Nodes farther than the band get the sign of their nearest
  band node and the magnitude ``e + band - h·√3/2`` (``e`` their Euclidean distance to the
  nearest band node, ``h`` the spacing): within ``h·√3/2`` of the true distance at the
  nodes, either side (the true distance lies in [e + band - h·√3, e + band]: a node just
  beyond the band can be valued up to h·√3/2 above it, e.g. 6.134 for 6.092 mm; the node
  bounds of ``signed_bounds`` widen a far node's value by h·√3/2 both ways, ``abs_bounds``
  only upwards, see its caveat);
  between nodes the interpolation adds up to about h/4 (the tests bound the far error by
  1.25 h). Only the contact screening reads these values, with a margin of several mm.
- **Outside the grid** (padded by ``PAD_MM`` = 25 mm and two cells, so every point within
  25 mm of the surface is inside it), the distance to the mesh's bounding box, a lower bound.

Queries (``DistanceField.__call__``): the smallest ``|node value| + node distance`` over the
8 nodes around a point (a far node's value raised by its error bound ``h·√3/2``) bounds the
point's distance from above; when that bound is within ``EXACT_WITHIN_MM`` (8 mm: beyond the
contact screening), the triangles of the buckets within it (a 2 mm grid of triangle lists)
are searched for the exact nearest one: the answer is the exact signed distance, to rounding
(tests compare it with trimesh at 1e-9 mm). Elsewhere the trilinear interpolation of the
nodes is returned (deeper or farther than 8 mm, or outside the grid: the distance to the
mesh's box). Plain interpolation would err by up to about h/2 next to sharp rims and thin
walls (0.5 mm measured on a 3 mm annulus), half the contact tolerance, which is why the near
field is answered exactly.

Cache: ``$XDG_CACHE_HOME/handbench/fields/<hash>.npz`` (``~/.cache/...``), keyed by the mesh's
vertices and faces, the spacing, the band and ``FIELD_VERSION``; written atomically, so
workers that build the same field at once do not corrupt it. An unwritable cache folder only
costs the rebuild.
"""

from __future__ import annotations

import hashlib
import math
import os
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import trimesh
from numba import njit

from app import cache_root

#: The arrays of ``DistanceField.pack`` (a tuple, so that compiled code takes it whole).
MeshPack = tuple[Any, ...]

#: Bump when the field's construction changes (old cached files are then ignored).
FIELD_VERSION = 4
#: Default grid spacing (mm): the contact tolerance is 1 mm.
SPACING_MM = 1.0
#: Default exact band (mm): the contact screening looks up to tol + 1.5·δ ≈ 5.5 mm.
BAND_MM = 6.0
#: Queries are answered exactly (nearest triangle) up to this distance from the surface.
EXACT_WITHIN_MM = 8.0
#: The grid extends this far beyond the mesh's box (mm): a hand link near the object has its
#: axis points inside it, where the nodes bound distances tightly (outside: the box's bounds).
PAD_MM = 25.0
#: Largest grid (nodes); larger objects get a coarser spacing (600 mm → ~3 mm).
MAX_NODES = 12_000_000


def _rw(a: np.ndarray) -> np.ndarray:
    """``a`` as a writable C-contiguous array (numba compiles one version per layout and
    read-only flag; every pack uses the same)."""
    if a.flags.writeable and a.flags.c_contiguous:
        return a
    return np.array(a, order="C")


def empty_pack() -> MeshPack:
    """A pack of the right types and no triangles (compiled kernels take one always)."""
    z3 = np.zeros(3)
    return (
        z3.copy(), 1.0, np.zeros((2, 2, 2), np.float32), 0.0, z3.copy(), z3.copy(),
        np.zeros((0, 3)), np.zeros((0, 3), np.int64), np.zeros((0, 3)), np.zeros((0, 3, 3)),
        np.zeros((0, 3)), z3.copy(), 1.0, np.ones(3, np.int64), np.zeros(2, np.int64),
        np.zeros(0, np.int64), np.zeros((0, 3)), np.zeros(0), np.zeros(0, np.int64),
        np.zeros(1, np.int64),
    )  # fmt: skip


@dataclass(frozen=True)
class DistanceField:
    """Signed distance samples on a regular grid, object frame, mm, and the mesh itself for
    exact answers near the surface."""

    origin_mm: np.ndarray
    """(3,) position of node (0, 0, 0)."""
    spacing_mm: float
    """Grid spacing h."""
    values_mm: np.ndarray
    """(nx, ny, nz) float32 signed distance at the nodes, negative inside."""
    band_mm: float
    """Nodes within this distance of the surface are exact; farther ones are lower bounds."""
    lo_mm: np.ndarray
    """(3,) lower corner of the mesh's bounding box (queries outside the grid)."""
    hi_mm: np.ndarray
    """(3,) upper corner of the mesh's bounding box."""
    mesh: MeshArrays
    """The triangles, their pseudo-normals and a bucket grid over them (exact queries)."""
    _pack_cache: list[MeshPack] = field(default_factory=list, repr=False, compare=False)

    def __call__(self, p: np.ndarray) -> np.ndarray:
        """Signed distance (N,) of points (N, 3), object frame: exact (to rounding) within
        ``EXACT_WITHIN_MM`` of the surface, else the interpolated field (module docstring)."""
        p = np.ascontiguousarray(np.asarray(p, dtype=np.float64).reshape(-1, 3))
        out = np.empty(len(p))
        _query(self.pack(), p, out)
        return out

    def pack(self) -> MeshPack:
        """Everything the compiled queries read, as one tuple (``point_sdf``; the closing
        engine's mesh distance). Holds this process's scratch arrays (not thread-safe)."""
        pk = self._pack_cache
        if not pk:
            m = self.mesh
            pk.append((
                _rw(self.origin_mm), float(self.spacing_mm), _rw(self.values_mm),
                float(self.band_mm), _rw(self.lo_mm), _rw(self.hi_mm), _rw(m.V), _rw(m.F),
                _rw(m.n_face), _rw(m.n_edge), _rw(m.n_vert), _rw(m.b_origin), float(m.b_size),
                _rw(m.b_shape), _rw(m.b_start), _rw(m.b_ids), _rw(m.tri_c), _rw(m.tri_r),
                np.zeros(len(m.F), np.int64), np.zeros(1, np.int64),
            ))  # fmt: skip
        return pk[0]

    def interpolated(self, p: np.ndarray) -> np.ndarray:
        """The grid's trilinear interpolation alone (N,), for tests and pictures."""
        p = np.ascontiguousarray(np.asarray(p, dtype=np.float64).reshape(-1, 3))
        out = np.empty(len(p))
        for k in range(len(p)):
            out[k] = _interp(p[k], self.origin_mm, self.spacing_mm, self.values_mm,
                             self.band_mm, self.lo_mm, self.hi_mm)[0]  # fmt: skip
        return out

    @property
    def nbytes(self) -> int:
        """Memory of the samples and the mesh arrays."""
        m = self.mesh
        arrays = (m.V, m.F, m.n_face, m.n_edge, m.n_vert, m.b_start, m.b_ids, m.tri_c, m.tri_r)
        return int(self.values_mm.nbytes + sum(a.nbytes for a in arrays))


@dataclass(frozen=True)
class MeshArrays:
    """A watertight mesh as flat arrays for the compiled queries."""

    V: np.ndarray
    """(V, 3) vertices, mm."""
    F: np.ndarray
    """(F, 3) int64 faces, counter-clockwise seen from outside."""
    n_face: np.ndarray
    """(F, 3) unit face normals."""
    n_edge: np.ndarray
    """(F, 3, 3) pseudo-normal of each face's edge k (corner k to k+1)."""
    n_vert: np.ndarray
    """(V, 3) angle-weighted vertex pseudo-normals."""
    b_origin: np.ndarray
    """(3,) lower corner of the bucket grid."""
    b_size: float
    """Bucket edge length, mm."""
    b_shape: np.ndarray
    """(3,) int64 buckets per axis."""
    b_start: np.ndarray
    """(B + 1,) int64 CSR offsets of each bucket's triangles in ``b_ids``."""
    b_ids: np.ndarray
    """int64 triangle ids, bucket by bucket (a triangle is in every bucket its box meets)."""
    tri_c: np.ndarray
    """(F, 3) centre of each triangle's bounding sphere (its vertices' mean)."""
    tri_r: np.ndarray
    """(F,) radius of that sphere."""


@njit(cache=True, inline="always")
def _interp(
    p: np.ndarray,
    origin: np.ndarray,
    h: float,
    v: np.ndarray,
    band: float,
    lo: np.ndarray,
    hi: np.ndarray,
) -> tuple[float, float, bool]:
    """(trilinear value, upper bound of |distance| from the 8 nodes, whether p is in the
    grid); outside the grid the distance to the mesh's box (a lower bound), inf, False."""
    nx, ny, nz = v.shape
    fx = (p[0] - origin[0]) / h
    fy = (p[1] - origin[1]) / h
    fz = (p[2] - origin[2]) / h
    if fx < 0 or fy < 0 or fz < 0 or fx > nx - 1 or fy > ny - 1 or fz > nz - 1:
        s = 0.0
        for a in range(3):
            d = max(lo[a] - p[a], 0.0, p[a] - hi[a])
            s += d * d
        return math.sqrt(s), np.inf, False
    i = min(int(fx), nx - 2)
    j = min(int(fy), ny - 2)
    m = min(int(fz), nz - 2)
    tx, ty, tz = fx - i, fy - j, fz - m
    c00 = v[i, j, m] * (1 - tx) + v[i + 1, j, m] * tx
    c10 = v[i, j + 1, m] * (1 - tx) + v[i + 1, j + 1, m] * tx
    c01 = v[i, j, m + 1] * (1 - tx) + v[i + 1, j, m + 1] * tx
    c11 = v[i, j + 1, m + 1] * (1 - tx) + v[i + 1, j + 1, m + 1] * tx
    c0 = c00 * (1 - ty) + c10 * ty
    c1 = c01 * (1 - ty) + c11 * ty
    upper = np.inf
    for di in range(2):
        for dj in range(2):
            for dm in range(2):
                ex = (tx - di) * h
                ey = (ty - dj) * h
                ez = (tz - dm) * h
                a = abs(v[i + di, j + dj, m + dm])
                if a > band:  # a far node's value is low by at most h·√3/2
                    a += h * 0.8660254037844387
                upper = min(upper, a + math.sqrt(ex * ex + ey * ey + ez * ez))
    return c0 * (1 - tz) + c1 * tz, upper, True


@njit(cache=True)
def abs_bounds(pk: MeshPack, px: float, py: float, pz: float) -> tuple[float, float]:
    """(lower, upper) bounds of the distance from a point to the surface, from the
    8 grid nodes around it alone (no triangle search): ``|node| ∓ node distance``, a far
    node's value being low by at most h·√3/2. Outside the grid: the distances to the mesh's
    box and to its farthest corner.

    Caveat (found by ``tests/test_distance_field.py``, not changed here because it moves
    outcomes): a far node's value can also be up to h·√3/2 *above* its distance (module
    docstring), so the lower bound can exceed the true distance by that much where a node
    just beyond the band is the best one (seen: 4.916 for 4.883 mm). ``signed_bounds``
    widens far nodes both ways; doing the same here changes the closing's steps (stops
    move within the stop band, 1.4–1.7 % of the drill scan's outcomes change)."""
    origin, h, v, band, lo, hi = pk[0], pk[1], pk[2], pk[3], pk[4], pk[5]
    nx, ny, nz = v.shape
    fx = (px - origin[0]) / h
    fy = (py - origin[1]) / h
    fz = (pz - origin[2]) / h
    if fx < 0 or fy < 0 or fz < 0 or fx > nx - 1 or fy > ny - 1 or fz > nz - 1:
        s_lo = 0.0
        s_hi = 0.0
        p = (px, py, pz)
        for a in range(3):
            d = max(lo[a] - p[a], 0.0, p[a] - hi[a])
            s_lo += d * d
            e = max(abs(p[a] - lo[a]), abs(p[a] - hi[a]))
            s_hi += e * e
        return math.sqrt(s_lo), math.sqrt(s_hi)
    i = min(int(fx), nx - 2)
    j = min(int(fy), ny - 2)
    m = min(int(fz), nz - 2)
    tx, ty, tz = fx - i, fy - j, fz - m
    lower = 0.0
    upper = np.inf
    for di in range(2):
        for dj in range(2):
            for dm in range(2):
                ex = (tx - di) * h
                ey = (ty - dj) * h
                ez = (tz - dm) * h
                dist = math.sqrt(ex * ex + ey * ey + ez * ez)
                a = abs(v[i + di, j + dj, m + dm])
                lower = max(lower, a - dist - 1e-4)  # float32 nodes
                if a > band:
                    a += h * 0.8660254037844387
                upper = min(upper, a + dist + 1e-4)
    return lower, upper


@njit(cache=True)
def signed_bounds(pk: MeshPack, px: float, py: float, pz: float) -> tuple[float, float]:
    """Rigorous (lower, upper) bounds of the signed distance of a point, from the 8 grid nodes
    around it alone: ``|node| ∓ node distance``, a far node's value widened by h·√3/2 both
    ways (module docstring; unlike ``abs_bounds``'s, the lower bound never exceeds). The
    sign is known when a node's ball of radius |value| (which no surface crosses) holds the
    point: that node's sign; else the bounds straddle 0. Outside the grid the point is outside
    the mesh's box: positive."""
    origin, h, v, band = pk[0], pk[1], pk[2], pk[3]
    nx, ny, nz = v.shape
    fx = (px - origin[0]) / h
    fy = (py - origin[1]) / h
    fz = (pz - origin[2]) / h
    if fx < 0 or fy < 0 or fz < 0 or fx > nx - 1 or fy > ny - 1 or fz > nz - 1:
        return abs_bounds(pk, px, py, pz)
    i = min(int(fx), nx - 2)
    j = min(int(fy), ny - 2)
    m = min(int(fz), nz - 2)
    tx, ty, tz = fx - i, fy - j, fz - m
    lower = 0.0
    sign = 0.0
    upper = np.inf
    for di in range(2):
        for dj in range(2):
            for dm in range(2):
                ex = (tx - di) * h
                ey = (ty - dj) * h
                ez = (tz - dm) * h
                dist = math.sqrt(ex * ex + ey * ey + ez * ez)
                val = v[i + di, j + dj, m + dm]
                a = abs(val)
                far = h * 0.8660254037844387 if a > band else 0.0  # within h·√3/2 either way
                lo_n = a - far - dist - 1e-4  # float32 nodes
                if lo_n > lower:
                    lower = lo_n
                    sign = 1.0 if val > 0 else -1.0
                upper = min(upper, a + far + dist + 1e-4)
    if sign > 0:
        return lower, upper
    if sign < 0:
        return -upper, -lower
    return -upper, upper


@njit(cache=True)
def point_sdf(pk: MeshPack, px: float, py: float, pz: float) -> float:
    """Signed distance of one point (``DistanceField.__call__``), for compiled callers."""
    return point_sdf_kind(pk, px, py, pz)[0]


#: ``point_sdf_kind`` kinds: the exact distance; the grid's interpolation (within ~1.25 h);
#: outside the grid, the distance to the mesh's box (a lower bound).
EXACT, INTERPOLATED, OUTSIDE = 0, 1, 2


@njit(cache=True)
def point_sdf_kind(pk: MeshPack, px: float, py: float, pz: float) -> tuple[float, int]:
    """(signed distance, how it was obtained: ``EXACT``, ``INTERPOLATED`` or ``OUTSIDE``)."""
    (origin, h, v, band, lo, hi, V, F, n_face, n_edge, n_vert, b_origin, b_size, b_shape,
     b_start, b_ids, _tc, _tr, stamp, ctr) = pk  # fmt: skip
    p = np.empty(3)
    p[0], p[1], p[2] = px, py, pz
    val, upper, inside_grid = _interp(p, origin, h, v, band, lo, hi)
    if not inside_grid:
        return val, OUTSIDE
    if upper > EXACT_WITHIN_MM:
        return val, INTERPOLATED
    r = upper + 1e-3  # the nodes are float32
    nby, nbz = b_shape[1], b_shape[2]
    lo_b = np.empty(3, np.int64)
    hi_b = np.empty(3, np.int64)
    ctr_b = np.empty(3, np.int64)
    for a in range(3):
        lo_b[a] = max(int(math.floor((p[a] - r - b_origin[a]) / b_size)), 0)
        hi_b[a] = min(int(math.floor((p[a] + r - b_origin[a]) / b_size)), b_shape[a] - 1)
        ctr_b[a] = int(math.floor((p[a] - b_origin[a]) / b_size))
    s_max = 0
    for a in range(3):
        s_max = max(s_max, ctr_b[a] - lo_b[a], hi_b[a] - ctr_b[a])
    ctr[0] += 1
    qid = ctr[0]
    best = r * r
    found = False
    s_best = 0.0
    # shells of buckets around p's, nearest first; shell s is at least (s - 1)·b_size away
    for sh in range(s_max + 1):
        if sh >= 2 and (sh - 1) * b_size > math.sqrt(best):
            break
        for bi in range(max(lo_b[0], ctr_b[0] - sh), min(hi_b[0], ctr_b[0] + sh) + 1):
            for bj in range(max(lo_b[1], ctr_b[1] - sh), min(hi_b[1], ctr_b[1] + sh) + 1):
                for bk in range(max(lo_b[2], ctr_b[2] - sh), min(hi_b[2], ctr_b[2] + sh) + 1):
                    cheb = max(abs(bi - ctr_b[0]), abs(bj - ctr_b[1]), abs(bk - ctr_b[2]))
                    if cheb != sh:
                        continue
                    b = (bi * nby + bj) * nbz + bk
                    for e in range(b_start[b], b_start[b + 1]):
                        f = b_ids[e]
                        if stamp[f] == qid:
                            continue
                        stamp[f] = qid
                        ex = px - _tc[f, 0]
                        ey = py - _tc[f, 1]
                        ez = pz - _tc[f, 2]
                        lb = math.sqrt(ex * ex + ey * ey + ez * ez) - _tr[f]
                        if lb > 0 and lb * lb > best:
                            continue
                        cx, cy, cz, feat = closest_on_triangle(px, py, pz, V[F[f, 0]],
                                                                V[F[f, 1]], V[F[f, 2]])  # fmt: skip
                        dx, dy, dz = px - cx, py - cy, pz - cz
                        d2 = dx * dx + dy * dy + dz * dz
                        if d2 < best or (not found and d2 <= best):
                            best = d2
                            found = True
                            if feat == 0:
                                n = n_face[f]
                            elif feat <= 3:
                                n = n_vert[F[f, feat - 1]]
                            else:
                                n = n_edge[f, feat - 4]
                            s_best = dx * n[0] + dy * n[1] + dz * n[2]
    if not found:  # cannot happen: the bound holds a triangle
        return val, INTERPOLATED
    d = math.sqrt(best)
    return (d if s_best > 0 else (-d if s_best < 0 else 0.0)), EXACT


@njit(cache=True)
def _query(pk: MeshPack, p: np.ndarray, out: np.ndarray) -> None:
    for k in range(p.shape[0]):
        out[k] = point_sdf(pk, p[k, 0], p[k, 1], p[k, 2])


@njit(cache=True, inline="always")
def _tri_box_overlap(
    c: np.ndarray, half: float, a: np.ndarray, b: np.ndarray, d: np.ndarray
) -> bool:
    """Whether triangle (a, b, d) meets the cube of centre c and half edge ``half``: the
    separating-axis test on the cube's 3 axes, the triangle's normal and the 9 edge-axis
    cross products (Akenine-Möller)."""
    v0 = a - c
    v1 = b - c
    v2 = d - c
    for ax in range(3):
        if min(v0[ax], v1[ax], v2[ax]) > half or max(v0[ax], v1[ax], v2[ax]) < -half:
            return False
    e0 = v1 - v0
    e1 = v2 - v1
    e2 = v0 - v2
    n = np.cross(e0, e1)
    r = half * (abs(n[0]) + abs(n[1]) + abs(n[2]))
    if abs(n @ v0) > r:
        return False
    for e in (e0, e1, e2):
        for ax in range(3):
            # axis = unit_ax × e
            u = np.zeros(3)
            if ax == 0:
                u[1], u[2] = -e[2], e[1]
            elif ax == 1:
                u[0], u[2] = e[2], -e[0]
            else:
                u[0], u[1] = -e[1], e[0]
            p0, p1, p2 = u @ v0, u @ v1, u @ v2
            rr = half * (abs(u[0]) + abs(u[1]) + abs(u[2]))
            if min(p0, p1, p2) > rr or max(p0, p1, p2) < -rr:
                return False
    return True


@njit(cache=True)
def _bucket_kernel(
    V: np.ndarray, F: np.ndarray, b_origin: np.ndarray, b_size: float, b_shape: np.ndarray,
    fill: bool, count: np.ndarray, b_start: np.ndarray, b_ids: np.ndarray,
) -> None:  # fmt: skip
    """Count (fill=False) or list (fill=True) the triangles of every bucket they meet (a long
    sliver is listed only where it passes, not in its whole bounding box)."""
    nby, nbz = b_shape[1], b_shape[2]
    centre = np.empty(3)
    lo_b = np.empty(3, np.int64)
    hi_b = np.empty(3, np.int64)
    for f in range(F.shape[0]):
        for a in range(3):
            lo = min(V[F[f, 0], a], V[F[f, 1], a], V[F[f, 2], a])
            hi = max(V[F[f, 0], a], V[F[f, 1], a], V[F[f, 2], a])
            lo_b[a] = max(int(math.floor((lo - b_origin[a]) / b_size)), 0)
            hi_b[a] = min(int(math.floor((hi - b_origin[a]) / b_size)), b_shape[a] - 1)
        a_, b_, c_ = V[F[f, 0]], V[F[f, 1]], V[F[f, 2]]
        n_box = (hi_b[0] - lo_b[0] + 1) * (hi_b[1] - lo_b[1] + 1) * (hi_b[2] - lo_b[2] + 1)
        exact = n_box > 8  # a large triangle: only the buckets it passes through
        for bi in range(lo_b[0], hi_b[0] + 1):
            for bj in range(lo_b[1], hi_b[1] + 1):
                for bk in range(lo_b[2], hi_b[2] + 1):
                    centre[0] = b_origin[0] + (bi + 0.5) * b_size
                    centre[1] = b_origin[1] + (bj + 0.5) * b_size
                    centre[2] = b_origin[2] + (bk + 0.5) * b_size
                    if exact and not _tri_box_overlap(
                        centre, 0.5 * b_size * (1 + 1e-6), a_, b_, c_
                    ):
                        continue
                    b = (bi * nby + bj) * nbz + bk
                    if fill:
                        b_ids[b_start[b] + count[b]] = f
                    count[b] += 1


#: Bucket edge (mm) of the triangle grid that exact queries search.
BUCKET_MM = 2.0


def mesh_arrays(mesh: trimesh.Trimesh, bucket_mm: float = BUCKET_MM) -> MeshArrays:
    """Flat arrays of a watertight mesh: triangles, pseudo-normals, triangle buckets."""
    V = np.ascontiguousarray(mesh.vertices, dtype=np.float64)
    F = np.ascontiguousarray(mesh.faces, dtype=np.int64)
    n_face = np.ascontiguousarray(mesh.face_normals, dtype=np.float64)
    n_edge, n_vert = _pseudo_normals(mesh)
    b_origin = np.asarray(mesh.bounds[0], dtype=float) - bucket_mm
    b_shape = (np.ceil((mesh.bounds[1] - b_origin) / bucket_mm) + 2).astype(np.int64)
    nb = int(np.prod(b_shape))
    count = np.zeros(nb, np.int64)
    b_start = np.zeros(nb + 1, np.int64)
    empty = np.zeros(0, np.int64)
    _bucket_kernel(V, F, b_origin, bucket_mm, b_shape, False, count, b_start, empty)
    b_start[1:] = np.cumsum(count)
    b_ids = np.empty(int(b_start[-1]), np.int64)
    count[:] = 0
    _bucket_kernel(V, F, b_origin, bucket_mm, b_shape, True, count, b_start, b_ids)
    tri = V[F]  # (F, 3, 3)
    tri_c = np.ascontiguousarray(tri.mean(axis=1))
    tri_r = np.sqrt(((tri - tri_c[:, None, :]) ** 2).sum(-1)).max(axis=1)
    return MeshArrays(V, F, n_face, np.ascontiguousarray(n_edge), np.ascontiguousarray(n_vert),
                      b_origin, float(bucket_mm), b_shape, b_start, b_ids, tri_c,
                      np.ascontiguousarray(tri_r))  # fmt: skip


@njit(cache=True, inline="always")
def closest_on_triangle(
    px: float, py: float, pz: float, a: np.ndarray, b: np.ndarray, c: np.ndarray
) -> tuple[float, float, float, int]:
    """Closest point of triangle abc to p and its feature: 0 face, 1/2/3 vertex a/b/c,
    4/5/6 edge ab/bc/ca (Ericson, Real-Time Collision Detection §5.1.5)."""
    abx, aby, abz = b[0] - a[0], b[1] - a[1], b[2] - a[2]
    acx, acy, acz = c[0] - a[0], c[1] - a[1], c[2] - a[2]
    apx, apy, apz = px - a[0], py - a[1], pz - a[2]
    d1 = abx * apx + aby * apy + abz * apz
    d2 = acx * apx + acy * apy + acz * apz
    if d1 <= 0 and d2 <= 0:
        return a[0], a[1], a[2], 1
    bpx, bpy, bpz = px - b[0], py - b[1], pz - b[2]
    d3 = abx * bpx + aby * bpy + abz * bpz
    d4 = acx * bpx + acy * bpy + acz * bpz
    if d3 >= 0 and d4 <= d3:
        return b[0], b[1], b[2], 2
    vc = d1 * d4 - d3 * d2
    if vc <= 0 and d1 >= 0 and d3 <= 0:
        t = d1 / (d1 - d3)
        return a[0] + t * abx, a[1] + t * aby, a[2] + t * abz, 4
    cpx, cpy, cpz = px - c[0], py - c[1], pz - c[2]
    d5 = abx * cpx + aby * cpy + abz * cpz
    d6 = acx * cpx + acy * cpy + acz * cpz
    if d6 >= 0 and d5 <= d6:
        return c[0], c[1], c[2], 3
    vb = d5 * d2 - d1 * d6
    if vb <= 0 and d2 >= 0 and d6 <= 0:
        t = d2 / (d2 - d6)
        return a[0] + t * acx, a[1] + t * acy, a[2] + t * acz, 6
    va = d3 * d6 - d5 * d4
    if va <= 0 and (d4 - d3) >= 0 and (d5 - d6) >= 0:
        t = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        return b[0] + t * (c[0] - b[0]), b[1] + t * (c[1] - b[1]), b[2] + t * (c[2] - b[2]), 5
    den = 1.0 / (va + vb + vc)
    v_ = vb * den
    w_ = vc * den
    return (
        a[0] + abx * v_ + acx * w_,
        a[1] + aby * v_ + acy * w_,
        a[2] + abz * v_ + acz * w_,
        0,
    )


@njit(cache=True)
def _band_kernel(
    V: np.ndarray,
    F: np.ndarray,
    n_face: np.ndarray,
    n_edge: np.ndarray,
    n_vert: np.ndarray,
    origin: np.ndarray,
    h: float,
    band: float,
    d2_best: np.ndarray,
    sign: np.ndarray,
) -> None:
    """Exact squared distance and pseudo-normal sign of every node within ``band`` (plus a
    cell) of each triangle: keeps each node's nearest triangle."""
    nx, ny, nz = d2_best.shape
    for f in range(F.shape[0]):
        a, b, c = V[F[f, 0]], V[F[f, 1]], V[F[f, 2]]
        lo_i = np.empty(3, np.int64)
        hi_i = np.empty(3, np.int64)
        dims = (nx, ny, nz)
        for ax in range(3):
            lo = min(a[ax], b[ax], c[ax]) - band
            hi = max(a[ax], b[ax], c[ax]) + band
            lo_i[ax] = max(int(math.floor((lo - origin[ax]) / h)), 0)
            hi_i[ax] = min(int(math.ceil((hi - origin[ax]) / h)), dims[ax] - 1)
        for i in range(lo_i[0], hi_i[0] + 1):
            px = origin[0] + i * h
            for j in range(lo_i[1], hi_i[1] + 1):
                py = origin[1] + j * h
                for k in range(lo_i[2], hi_i[2] + 1):
                    pz = origin[2] + k * h
                    cx, cy, cz, feat = closest_on_triangle(px, py, pz, a, b, c)
                    dx, dy, dz = px - cx, py - cy, pz - cz
                    d2 = dx * dx + dy * dy + dz * dz
                    if d2 < d2_best[i, j, k]:
                        d2_best[i, j, k] = d2
                        if feat == 0:
                            n = n_face[f]
                        elif feat <= 3:
                            n = n_vert[F[f, feat - 1]]
                        else:
                            n = n_edge[f, feat - 4]
                        s = dx * n[0] + dy * n[1] + dz * n[2]
                        sign[i, j, k] = 1 if s > 0 else (-1 if s < 0 else 0)


def _pseudo_normals(mesh: trimesh.Trimesh) -> tuple[np.ndarray, np.ndarray]:
    """Per-face-edge (F, 3, 3; edge k from corner k to k+1) and per-vertex (V, 3)
    angle-weighted pseudo-normals (unnormalised; only their direction's side matters)."""
    faces = np.asarray(mesh.faces, dtype=np.int64)
    n_face = np.asarray(mesh.face_normals, dtype=np.float64)
    # edges: sum of the two adjacent faces' normals (watertight: each edge has two)
    e = np.stack([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]], axis=1)  # (F, 3, 2)
    key = np.sort(e.reshape(-1, 2), axis=1)
    _, inv = np.unique(key, axis=0, return_inverse=True)
    inv = inv.reshape(-1)
    acc = np.zeros((int(inv.max()) + 1, 3))
    np.add.at(acc, inv, np.repeat(n_face, 3, axis=0))
    n_edge = acc[inv].reshape(-1, 3, 3)
    # vertices: angle-weighted sum of incident face normals
    angles = np.asarray(mesh.face_angles, dtype=np.float64)  # (F, 3)
    n_vert = np.zeros((len(mesh.vertices), 3))
    for corner in range(3):
        np.add.at(n_vert, faces[:, corner], n_face * angles[:, corner : corner + 1])
    return n_edge, n_vert


def spacing_for(mesh: trimesh.Trimesh, spacing_mm: float = SPACING_MM, band_mm: float = BAND_MM
                ) -> float:  # fmt: skip
    """The grid spacing: ``spacing_mm``, or coarser so that the grid stays under MAX_NODES."""
    pad = max(band_mm, PAD_MM) + 2 * spacing_mm
    ext = np.asarray(mesh.extents, dtype=float) + 2 * pad
    h = spacing_mm
    while float(np.prod(np.ceil(ext / h) + 1)) > MAX_NODES:
        h *= 1.25
    return h


def build_field(
    mesh: trimesh.Trimesh, spacing_mm: float = SPACING_MM, band_mm: float = BAND_MM
) -> DistanceField:
    """The signed distance field of a watertight mesh (module docstring)."""
    from scipy.ndimage import distance_transform_edt

    assert mesh.is_watertight, "the importer hands over watertight meshes only"
    h = spacing_for(mesh, spacing_mm, band_mm)
    band = max(band_mm, 2 * h)
    lo = np.asarray(mesh.bounds[0], dtype=float)
    hi = np.asarray(mesh.bounds[1], dtype=float)
    pad = max(band, PAD_MM) + 2 * h  # links near the object have their bounds in the grid
    origin = lo - pad
    shape = tuple(int(x) for x in np.ceil((hi + pad - origin) / h) + 1)
    m = mesh_arrays(mesh)
    d2 = np.full(shape, np.inf)
    sign = np.zeros(shape, dtype=np.int8)
    _band_kernel(m.V, m.F, m.n_face, m.n_edge, m.n_vert, origin, h, band, d2, sign)
    in_band = d2 <= band * band
    values = np.sqrt(np.where(in_band, d2, 0.0)) * sign
    res = distance_transform_edt(~in_band, sampling=h, return_indices=True)
    assert isinstance(res, tuple)
    e, idx = res[0], res[1]
    far = ~in_band
    far_sign = sign[idx[0][far], idx[1][far], idx[2][far]]
    far_sign = np.where(far_sign == 0, 1, far_sign)
    values[far] = far_sign * np.maximum(band, e[far] + band - h * math.sqrt(3) / 2)
    return DistanceField(origin, float(h), values.astype(np.float32), float(band), lo, hi, m)


def cache_dir() -> Path:
    """Where fields are cached: ``$XDG_CACHE_HOME/handbench/fields`` (``~/.cache/...``)."""
    return cache_root() / "fields"


def field_key(mesh: trimesh.Trimesh, spacing_mm: float, band_mm: float) -> str:
    """Cache key of a mesh's field: its vertices, faces, the spacing, band and version."""
    hsh = hashlib.sha256()
    hsh.update(np.ascontiguousarray(mesh.vertices, dtype=np.float64).tobytes())
    hsh.update(np.ascontiguousarray(mesh.faces, dtype=np.int64).tobytes())
    hsh.update(f"{spacing_mm}|{band_mm}|{FIELD_VERSION}".encode())
    return hsh.hexdigest()[:32]


def cached_field(
    mesh: trimesh.Trimesh, spacing_mm: float = SPACING_MM, band_mm: float = BAND_MM
) -> tuple[DistanceField, bool]:
    """The mesh's field from the disk cache, else built and saved; and whether it was built."""
    path = cache_dir() / f"{field_key(mesh, spacing_mm, band_mm)}.npz"
    try:
        with np.load(path) as z:
            f = DistanceField(
                z["origin"], float(z["spacing"]), z["values"], float(z["band"]), z["lo"], z["hi"],
                mesh_arrays(mesh),
            )  # fmt: skip
        return f, False
    except (OSError, KeyError, ValueError):
        pass
    f = build_field(mesh, spacing_mm, band_mm)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".npz.tmp")
        with os.fdopen(fd, "wb") as fh:
            np.savez(
                fh, origin=f.origin_mm, spacing=f.spacing_mm, values=f.values_mm,
                band=f.band_mm, lo=f.lo_mm, hi=f.hi_mm,
            )  # fmt: skip
        os.replace(tmp, path)
    except OSError:
        pass  # an unwritable cache only costs the rebuild next time
    return f, True
