"""Geometry builders: watertight mesh, convex FCL pieces and signed distance of each object.

Every builder takes the ``[shape]`` table of a data file (mm) and returns a
:class:`Geometry` in the object frame. Three views of one solid are kept consistent:

- ``mesh``: one watertight triangle mesh (unions through manifold3d), vertices on the
  exact surface, faces within ~0.05 mm of it (polygon sections chosen from the radius);
- ``sdf``: the exact signed distance outside (negative inside) of the ideal solid:
  surfaces of revolution use the 2-D distance to the profile polygon in (r, z), unions of
  primitives take the minimum of exact primitive distances;
- ``pieces``: convex FCL geometries posed in the object frame whose union is the solid
  within ~0.15 mm (inscribed polygons), because capsule-vs-primitive/convex distance is
  about 5 µs while capsule-vs-BVH mesh is about 45 µs.
"""

from __future__ import annotations

import hashlib
import math
import os
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import fcl
import numpy as np
import trimesh
from scipy.interpolate import PchipInterpolator
from scipy.spatial import ConvexHull

from app import cache_root

SdfFn = Callable[[np.ndarray], np.ndarray]

#: Largest distance (mm) between a mesh face and the ideal surface (circle sagitta).
MESH_TOL_MM = 0.05
#: Largest distance (mm) between a convex FCL piece and the ideal surface.
PIECE_TOL_MM = 0.15


@dataclass(frozen=True)
class Piece:
    """One convex collision piece, posed in the object frame."""

    geometry: Any
    """An ``fcl.CollisionGeometry`` (Box, Cylinder, Capsule, Sphere, Convex or BVHModel)."""
    R_object_piece: np.ndarray
    """(3, 3) rotation of the piece frame in the object frame."""
    t_object_piece: np.ndarray
    """(3,) position of the piece frame origin in the object frame, mm."""
    label: str = ""
    """What part of the object this piece is (for debugging and pictures)."""
    vertices: np.ndarray | None = None
    """(K, 3) hull vertices of a Convex piece, piece frame (the compiled closing engine's
    support function; FCL's Convex does not expose them); None for primitives and meshes."""


@dataclass(frozen=True, eq=False)
class SdfPart:
    """What one primitive's signed distance computes, as numbers (the compiled contact
    kernels evaluate the same formula as the ``sdf`` closure: ``app.sim.sdf_compiled``).

    ``kind``: 'revolved' (``table`` of the (rho, z) polygon, local frame posed by ``T``),
    'annulus' (exact 2-D distance to ``poly`` in (rho, z), object frame), 'box'
    (``params`` = centre xyz, half extents xyz), 'prism' (``table`` of the section polygon,
    ``params`` = z centre, half height; local frame posed by ``T``), 'capsule_x'
    (``params`` = x0, length, y, z, radius)."""

    kind: str
    """Formula (see the class docstring)."""
    T: np.ndarray
    """(4, 4) pose of the local frame in the object frame (identity where unused)."""
    params: tuple[float, ...] = ()
    """Scalar parameters of the formula."""
    table: PolygonSdfTable | None = None
    """The tabulated 2-D distance ('revolved', 'prism')."""
    poly: np.ndarray | None = None
    """(M, 2) polygon of the exact 2-D distance ('annulus')."""
    real: np.ndarray | None = None
    """(M,) bool: which edges of ``poly`` count ('annulus')."""


@dataclass(frozen=True)
class Geometry:
    """Mesh, signed distance and collision pieces of one object, object frame, mm."""

    mesh: trimesh.Trimesh
    """Watertight triangle mesh."""
    sdf: SdfFn
    """(N, 3) points -> (N,) signed distance, negative inside."""
    pieces: tuple[Piece, ...]
    """Convex pieces whose union is the solid (one BVHModel for imported meshes)."""
    sdf_parts: tuple[SdfPart, ...] | None = None
    """The same signed distance as numbers: the minimum over these parts (None: an imported
    mesh, whose distance only the ``sdf`` closure computes)."""
    sdf_bounds: np.ndarray | None = None
    """(len(sdf_parts), 4) bounding sphere (centre, radius) of each part of a union: a part
    whose ``|p - c| - r`` is not below the best value so far is skipped (None: one part)."""


# --------------------------------------------------------------------------- helpers


def sections_for(radius_mm: float, tol_mm: float = MESH_TOL_MM, multiple: int = 8) -> int:
    """Polygon sections so that the sagitta r(1 - cos(pi/n)) stays below ``tol_mm``."""
    if radius_mm <= tol_mm:
        return multiple
    n = math.ceil(math.pi / math.acos(1.0 - tol_mm / radius_mm))
    return max(2 * multiple, multiple * math.ceil(n / multiple))


def pose(R: np.ndarray, t: np.ndarray) -> np.ndarray:
    """(4, 4) homogeneous pose from a rotation (3, 3) and a translation (3,)."""
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = t
    return T


def rot_y(angle_rad: float) -> np.ndarray:
    """(3, 3) rotation about +y."""
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


#: Rotation taking local +z to object +x (local x -> object -z, local y -> object y).
R_Z_TO_X = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])


def _as_points(p: np.ndarray) -> np.ndarray:
    p = np.asarray(p, dtype=float)
    if p.ndim != 2 or p.shape[1] != 3:
        raise ValueError(f"points must have shape (N, 3), got {p.shape}")
    return p


def polygon_sdf_2d(q: np.ndarray, verts: np.ndarray, real_edge: np.ndarray) -> np.ndarray:
    """Signed distance from 2-D points to a closed polygon, negative inside.

    q: (N, 2) points; verts: (M, 2) polygon (implicitly closed); real_edge: (M,) bool, edge i
    (verts[i] -> verts[i+1]) counts for the distance (edges on a revolution axis do not).
    The sign comes from the even-odd rule over all edges.
    """
    a = verts
    b = np.roll(verts, -1, axis=0)
    ab = b - a  # (M, 2)
    ab2 = np.maximum((ab * ab).sum(1), 1e-300)
    aq = q[:, None, :] - a[None, :, :]  # (N, M, 2)
    t = np.clip((aq * ab[None]).sum(2) / ab2[None], 0.0, 1.0)
    d = aq - t[..., None] * ab[None]
    dist2 = (d * d).sum(2)
    dist2 = np.where(real_edge[None, :], dist2, np.inf)
    dist = np.sqrt(dist2.min(axis=1))
    # even-odd crossing test along +x (here +r)
    y = q[:, 1:2]
    cond = (a[None, :, 1] > y) != (b[None, :, 1] > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        x_cross = a[None, :, 0] + (y - a[None, :, 1]) * ab[None, :, 0] / ab[None, :, 1]
    inside = (cond & (q[:, 0:1] < x_cross)).sum(1) % 2 == 1
    return np.where(inside, -dist, dist)


#: Bump when ``polygon_sdf_2d`` or the table's layout changes (cached tables are then unused).
TABLE_VERSION = 1


def _save_atomic(path: Path, values: np.ndarray) -> None:
    """Write ``values`` to ``path`` (.npy) through a temp file and a rename, so that processes
    building the same table at once never leave a torn file; an unwritable folder is fine."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".npy.tmp")
        with os.fdopen(fd, "wb") as fh:
            np.save(fh, values)
        os.replace(tmp, path)
    except OSError:
        pass


class PolygonSdfTable:
    """``polygon_sdf_2d`` tabulated on a regular grid, bilinearly interpolated.

    The exact 2-D distance costs O(N · M) for N points and M polygon edges, which made
    contact extraction dominate a simulation. The table is built lazily on first use over
    the polygon's box padded by ``pad`` (spacing ``h``); points outside it use the exact
    function. A signed distance is 1-Lipschitz, so interpolation errs by at most about
    h/2 near corners and far less on smooth parts (tests: |sdf| on mesh vertices < 0.3 mm).
    """

    def __init__(
        self, verts: np.ndarray, real_edge: np.ndarray, h: float = 0.2, pad: float = 40.0
    ) -> None:
        self.verts, self.real, self.h, self.pad = verts, real_edge, h, pad
        self._grid: np.ndarray | None = None

    def _build(self) -> np.ndarray:
        lo = self.verts.min(0) - self.pad
        hi = self.verts.max(0) + self.pad
        self.lo = lo
        self.shape = np.ceil((hi - lo) / self.h).astype(int) + 1
        gx = lo[0] + self.h * np.arange(self.shape[0])
        gy = lo[1] + self.h * np.arange(self.shape[1])
        X, Y = np.meshgrid(gx, gy, indexing="ij")
        q = np.column_stack([X.ravel(), Y.ravel()])
        vals = np.concatenate(
            [
                polygon_sdf_2d(q[i : i + 20000], self.verts, self.real)
                for i in range(0, len(q), 20000)
            ]
        )
        return vals.reshape(self.shape)

    def grid(self) -> np.ndarray:
        """The tabulated values (built on first use, or read from the disk cache:
        ``table_cache_path``); ``lo``/``shape`` are set with it."""
        if self._grid is None:
            path = self.table_cache_path()
            try:
                g = np.load(path, allow_pickle=False)
                self.lo = self.verts.min(0) - self.pad
                self.shape = (
                    np.ceil((self.verts.max(0) + self.pad - self.lo) / self.h).astype(int) + 1
                )
                if g.dtype != np.float64 or g.shape != tuple(self.shape):
                    raise ValueError("table of another shape")
            except (OSError, ValueError):
                g = self._build()
                _save_atomic(path, g)
            self._grid = g
            return g
        return self._grid

    def table_cache_path(self) -> Path:
        """``$XDG_CACHE_HOME/handbench/tables/<hash>.npy``: the table, keyed by the polygon,
        its real edges, the spacing, the padding and ``TABLE_VERSION`` (building the pear's
        table takes seconds in every new process; reading it, milliseconds). The values are
        stored as float64, so a read table equals a built one bit for bit."""
        h = hashlib.sha256()
        h.update(np.ascontiguousarray(self.verts, np.float64).tobytes())
        h.update(np.ascontiguousarray(self.real, np.bool_).tobytes())
        h.update(f"{self.h!r}|{self.pad!r}|{TABLE_VERSION}".encode())
        return cache_root() / "tables" / f"{h.hexdigest()[:32]}.npy"

    def __call__(self, q: np.ndarray) -> np.ndarray:
        g = self.grid()
        u = (q - self.lo) / self.h
        i = np.floor(u).astype(int)
        inside = (i >= 0).all(1) & (i[:, 0] < self.shape[0] - 1) & (i[:, 1] < self.shape[1] - 1)
        out = np.empty(len(q))
        if (~inside).any():
            out[~inside] = polygon_sdf_2d(q[~inside], self.verts, self.real)
        ii, ff = i[inside], u[inside] - i[inside]
        a, b = ii[:, 0], ii[:, 1]
        fx, fy = ff[:, 0], ff[:, 1]
        out[inside] = (
            g[a, b] * (1 - fx) * (1 - fy)
            + g[a + 1, b] * fx * (1 - fy)
            + g[a, b + 1] * (1 - fx) * fy
            + g[a + 1, b + 1] * fx * fy
        )
        return out


def _transform_sdf(local: SdfFn, T: np.ndarray) -> SdfFn:
    R, t = T[:3, :3].copy(), T[:3, 3].copy()

    def sdf(p: np.ndarray) -> np.ndarray:
        return local((_as_points(p) - t) @ R)

    return sdf


def _convex_fcl(points: np.ndarray) -> tuple[Any, np.ndarray]:
    """fcl.Convex hull of (K, 3) points (outward faces), and its vertices (V, 3)."""
    hull = ConvexHull(points)
    v = hull.points[hull.vertices]
    remap = np.full(len(hull.points), -1)
    remap[hull.vertices] = np.arange(len(hull.vertices))
    faces = remap[hull.simplices]
    # orient every face outward
    c = v.mean(0)
    tri = v[faces]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    flip = ((tri[:, 0] - c) * n).sum(1) < 0
    faces[flip] = faces[flip][:, ::-1]
    flat = np.hstack([np.full((len(faces), 1), 3), faces]).ravel().astype(np.int64)
    v = np.ascontiguousarray(v, dtype=float)
    return fcl.Convex(v, len(faces), flat), v


def _ring(r: float, z: float, n: int) -> np.ndarray:
    if r <= 1e-9:
        return np.array([[0.0, 0.0, z]])
    a = np.linspace(0.0, 2 * math.pi, n, endpoint=False)
    return np.column_stack([r * np.cos(a), r * np.sin(a), np.full(n, z)])


def _upper_hull_deviation(z: np.ndarray, r: np.ndarray) -> float:
    """Largest gap between the upper concave envelope of (z, r) samples and the samples."""
    hull: list[int] = []
    for i in range(len(z)):
        while len(hull) >= 2:
            i0, i1 = hull[-2], hull[-1]
            cross = (z[i1] - z[i0]) * (r[i] - r[i0]) - (r[i1] - r[i0]) * (z[i] - z[i0])
            if cross >= 0:  # i1 is below the chord i0-i: not on the upper hull
                hull.pop()
            else:
                break
        hull.append(i)
    env = np.interp(z, z[hull], r[hull])
    return float(np.max(env - r))


def _concave_runs(z: np.ndarray, r: np.ndarray, tol: float) -> list[tuple[int, int]]:
    """Split a profile r(z) into maximal runs [i, j] whose solid of revolution is convex."""
    runs = []
    i = 0
    n = len(z)
    while i < n - 1:
        j = i + 1
        while j + 1 < n and _upper_hull_deviation(z[i : j + 2], r[i : j + 2]) <= tol:
            j += 1
        runs.append((i, j))
        i = j
    return runs


# ------------------------------------------------------------- solids of revolution


def revolved_profile(
    z: np.ndarray,
    r: np.ndarray,
    T: np.ndarray,
    label: str,
    run_tol_mm: float = 0.02,
    with_pieces: bool = True,
) -> Geometry:
    """Solid {rho <= r(z), z0 <= z <= zN} about local +z (piecewise-linear profile), posed by T.

    z: (K,) strictly increasing, r: (K,) >= 0. Pieces: one convex hull (or fcl.Cylinder)
    per maximal run where r(z) is concave, i.e. where the solid is convex.
    """
    z = np.asarray(z, dtype=float)
    r = np.asarray(r, dtype=float)
    if np.any(np.diff(z) <= 0) or np.any(r < 0):
        raise ValueError(f"{label}: profile z must increase and r be >= 0")
    rmax = float(r.max())
    # closed polygon in (r, z): axis bottom -> profile -> axis top (axis edge is not surface)
    poly = [(0.0, z[0])] + list(zip(r, z, strict=True)) + [(0.0, z[-1])]
    pts = np.array(poly)
    keep = np.ones(len(pts), dtype=bool)
    keep[1:] = np.any(np.abs(np.diff(pts, axis=0)) > 1e-12, axis=1)
    pts = pts[keep]
    if np.allclose(pts[0], pts[-1]):
        pts = pts[:-1]
    real = pts[:, 0] > 1e-12
    real |= np.roll(pts[:, 0], -1) > 1e-12  # edge i is on the axis iff both ends have r = 0

    table = PolygonSdfTable(pts, real)

    def sdf_local(p: np.ndarray) -> np.ndarray:
        q = np.column_stack([np.hypot(p[:, 0], p[:, 1]), p[:, 2]])
        return table(q)

    line = np.column_stack([r, z])
    if r[0] > 0:
        line = np.vstack([[0.0, z[0]], line])
    if r[-1] > 0:
        line = np.vstack([line, [0.0, z[-1]]])
    mesh = trimesh.creation.revolve(line, sections=sections_for(rmax))
    mesh.apply_transform(T)

    n_piece = sections_for(rmax, PIECE_TOL_MM)
    R, t = T[:3, :3], T[:3, 3]
    pieces = []
    runs = _concave_runs(z, r, run_tol_mm) if with_pieces else []
    for k, (i, j) in enumerate(runs):
        verts: np.ndarray | None = None
        if j == i + 1 and abs(r[i] - r[j]) < 1e-9 and r[i] > 0:
            geom: Any = fcl.Cylinder(float(r[i]), float(z[j] - z[i]))
            t_loc = np.array([0.0, 0.0, 0.5 * (z[i] + z[j])])
        else:
            geom, verts = _convex_fcl(
                np.vstack([_ring(r[m], z[m], n_piece) for m in range(i, j + 1)])
            )
            t_loc = np.zeros(3)
        pieces.append(Piece(geom, R.copy(), R @ t_loc + t, f"{label}[{k}]", verts))
    part = SdfPart("revolved", np.array(T, float), table=table)
    return Geometry(mesh, _transform_sdf(sdf_local, T), tuple(pieces), (part,))


def _annulus(r_in: float, r_out: float, height: float, n_wedges: int, label: str) -> Geometry:
    """Flat ring r_in <= rho <= r_out, 0 <= z <= height; pieces: n_wedges convex wedges."""
    pts = np.array([[r_in, 0.0], [r_out, 0.0], [r_out, height], [r_in, height]])
    real = np.ones(4, dtype=bool)

    def sdf(p: np.ndarray) -> np.ndarray:
        p = _as_points(p)
        q = np.column_stack([np.hypot(p[:, 0], p[:, 1]), p[:, 2]])
        return polygon_sdf_2d(q, pts, real)

    n_mesh = n_wedges * math.ceil(sections_for(r_out) / n_wedges)
    mesh = trimesh.creation.revolve(np.vstack([pts, pts[:1]]), sections=n_mesh)
    per = max(1, math.ceil(sections_for(r_out, PIECE_TOL_MM) / n_wedges))
    pieces = []
    for w in range(n_wedges):
        a0 = 2 * math.pi * w / n_wedges
        a1 = 2 * math.pi * (w + 1) / n_wedges
        a_out = np.linspace(a0, a1, per + 1)
        xy = np.vstack(
            [
                r_in * np.column_stack([np.cos([a0, a1]), np.sin([a0, a1])]),
                r_out * np.column_stack([np.cos(a_out), np.sin(a_out)]),
            ]
        )
        v = np.vstack(
            [
                np.column_stack([xy, np.zeros(len(xy))]),
                np.column_stack([xy, np.full(len(xy), height)]),
            ]
        )
        geom, hull = _convex_fcl(v)
        pieces.append(Piece(geom, np.eye(3), np.zeros(3), f"{label}[{w}]", hull))
    part = SdfPart("annulus", np.eye(4), poly=pts, real=real)
    return Geometry(mesh, sdf, tuple(pieces), (part,))


# ------------------------------------------------------------------ primitives (drill)


def _box(center: np.ndarray, size: np.ndarray, label: str) -> Geometry:
    half = 0.5 * np.asarray(size, dtype=float)
    c = np.asarray(center, dtype=float)

    def sdf(p: np.ndarray) -> np.ndarray:
        q = np.abs(_as_points(p) - c) - half
        outside = np.linalg.norm(np.maximum(q, 0.0), axis=1)
        return outside + np.minimum(q.max(axis=1), 0.0)

    mesh = trimesh.creation.box(extents=2 * half, transform=pose(np.eye(3), c))
    part = SdfPart("box", np.eye(4), (*map(float, c), *map(float, half)))
    return Geometry(mesh, sdf, (Piece(fcl.Box(*(2 * half)), np.eye(3), c.copy(), label),), (part,))


def rounded_rect(width_x: float, width_y: float, corner_r: float, n_corner: int) -> np.ndarray:
    """(4 * n_corner, 2) counter-clockwise convex rounded rectangle centred at the origin."""
    hx, hy = 0.5 * width_x - corner_r, 0.5 * width_y - corner_r
    out = []
    for cx, cy, a0 in ((hx, hy, 0.0), (-hx, hy, 90.0), (-hx, -hy, 180.0), (hx, -hy, 270.0)):
        a = np.deg2rad(a0 + np.linspace(0.0, 90.0, n_corner))
        out.append(np.column_stack([cx + corner_r * np.cos(a), cy + corner_r * np.sin(a)]))
    return np.vstack(out)


def _prism(poly: np.ndarray, z0: float, z1: float, T: np.ndarray, label: str) -> Geometry:
    """Convex polygon (K, 2) extruded along local z from z0 to z1, posed by T."""
    k = len(poly)
    real = np.ones(k, dtype=bool)
    zc, hz = 0.5 * (z0 + z1), 0.5 * (z1 - z0)

    table = PolygonSdfTable(poly, real)

    def sdf_local(p: np.ndarray) -> np.ndarray:
        d2 = table(p[:, :2])
        dz = np.abs(p[:, 2] - zc) - hz
        outside = np.hypot(np.maximum(d2, 0.0), np.maximum(dz, 0.0))
        return outside + np.minimum(np.maximum(d2, dz), 0.0)

    v = np.vstack(
        [np.column_stack([poly, np.full(k, z0)]), np.column_stack([poly, np.full(k, z1)])]
    )
    i = np.arange(k)
    j = (i + 1) % k
    sides = np.vstack([np.column_stack([i, j, j + k]), np.column_stack([i, j + k, i + k])])
    fan = np.arange(1, k - 1)
    bottom = np.column_stack([np.zeros(k - 2, dtype=int), fan + 1, fan])
    top = np.column_stack([np.full(k - 2, k), fan + k, fan + 1 + k])
    mesh = trimesh.Trimesh(v, np.vstack([sides, bottom, top]), process=True)
    mesh.fix_normals()
    mesh.apply_transform(T)
    geom, hull = _convex_fcl(v)
    piece = Piece(geom, T[:3, :3].copy(), T[:3, 3].copy(), label, hull)
    part = SdfPart("prism", np.array(T, float), (zc, hz), table=table)
    return Geometry(mesh, _transform_sdf(sdf_local, T), (piece,), (part,))


def _capsule_x(x0: float, x1: float, radius: float, y: float, z: float, label: str) -> Geometry:
    """Capsule whose axis segment runs along object x from x0 to x1 at (y, z)."""
    n_arc = max(4, sections_for(radius) // 4)
    a = np.linspace(0.0, 0.5 * math.pi, n_arc + 1)
    length = x1 - x0
    # profile along local z: bottom hemisphere, cylinder, top hemisphere
    zb = -radius * np.cos(a)  # from -radius to 0
    rb = radius * np.sin(a)
    zt = length + radius * np.sin(a)
    rt = radius * np.cos(a)
    zz = np.concatenate([zb, zt])
    rr = np.concatenate([rb, rt])
    T = pose(R_Z_TO_X, np.array([x0, y, z]))
    rev = revolved_profile(zz, rr, T, label, with_pieces=False)
    c0 = np.array([x0, y, z])

    def sdf(p: np.ndarray) -> np.ndarray:
        p = _as_points(p)
        s = np.clip(p[:, 0] - x0, 0.0, length)
        d = p - c0
        d[:, 0] -= s
        return np.linalg.norm(d, axis=1) - radius

    center = np.array([0.5 * (x0 + x1), y, z])
    piece = Piece(fcl.Capsule(radius, length), R_Z_TO_X.copy(), center, label)
    part = SdfPart("capsule_x", np.eye(4), (x0, length, y, z, radius))
    return Geometry(rev.mesh, sdf, (piece,), (part,))


def union(parts: list[Geometry]) -> Geometry:
    """Union of parts: one watertight mesh (manifold3d), min of SDFs, all pieces."""
    if len(parts) == 1:
        return parts[0]
    mesh = trimesh.boolean.union([g.mesh for g in parts], engine="manifold")
    fns = [g.sdf for g in parts]
    # bounding sphere of each part: |p - c| - r <= sdf_part(p) everywhere (inside too), so a
    # part whose bound is not below the best value so far cannot lower the min: skip it
    centres = np.stack([g.mesh.bounds.mean(axis=0) for g in parts])
    radii = 1.0 + np.array(  # + 1 mm: curved surfaces bulge past their mesh vertices
        [
            np.linalg.norm(g.mesh.vertices - c, axis=1).max()
            for g, c in zip(parts, centres, strict=True)
        ]
    )

    def sdf(p: np.ndarray) -> np.ndarray:
        p = _as_points(p)
        lb = np.linalg.norm(p[None, :, :] - centres[:, None, :], axis=2) - radii[:, None]
        best = np.full(len(p), np.inf)
        for j in np.argsort(lb.mean(axis=1)):
            need = lb[j] < best
            if need.all():
                best = np.minimum(best, fns[j](p))
            elif need.any():
                best[need] = np.minimum(best[need], fns[j](p[need]))
        return best

    sdf_parts: tuple[SdfPart, ...] | None = None
    bounds: np.ndarray | None = None
    if all(g.sdf_parts is not None and len(g.sdf_parts) == 1 and g.sdf_bounds is None
           for g in parts):  # fmt: skip
        sdf_parts = tuple(sp for g in parts for sp in (g.sdf_parts or ()))
        bounds = np.column_stack([centres, radii])
    pieces = tuple(pc for g in parts for pc in g.pieces)
    return Geometry(mesh, sdf, pieces, sdf_parts, bounds)


# ------------------------------------------------------------------ object builders


def _f(shape: dict[str, Any], name: str) -> float:
    if name not in shape:
        raise KeyError(f"shape parameter '{name}' missing")
    v = float(shape[name])
    if not math.isfinite(v) or v <= 0:
        raise ValueError(f"shape parameter '{name}' must be a positive number, got {v}")
    return v


def build_marker(s: dict[str, Any]) -> Geometry:
    """Marker lying on the table along +x, tip (cap) end toward +x, centred on x = 0."""
    length = _f(s, "length_mm")
    rb = 0.5 * _f(s, "barrel_diameter_mm")
    rc = 0.5 * _f(s, "cap_diameter_mm")
    cap_len = _f(s, "cap_length_mm")
    taper = _f(s, "taper_length_mm")
    ch = _f(s, "end_chamfer_mm")
    z = [0.0, ch, length - cap_len, length - cap_len + taper, length - ch, length]
    r = [rb - ch, rb, rb, rc, rc, rc - ch]
    T = pose(R_Z_TO_X, np.array([-0.5 * length, 0.0, rb]))
    return revolved_profile(np.array(z), np.array(r), T, "marker")


def pear_profile(s: dict[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    """(z, r) samples of the pear profile: shape-preserving (PCHIP) through the control points."""
    cp = np.asarray(s["profile_zr_mm"], dtype=float)
    if cp.ndim != 2 or cp.shape[1] != 2 or np.any(np.diff(cp[:, 0]) <= 0):
        raise ValueError("profile_zr_mm must be [[z, r], ...] with z increasing")
    step = _f(s, "profile_step_mm")
    f = PchipInterpolator(cp[:, 0], cp[:, 1])
    zs = [cp[0, 0]]
    for a, b in zip(cp[:-1, 0], cp[1:, 0], strict=True):
        n = max(1, math.ceil((b - a) / step))
        zs.extend(np.linspace(a, b, n + 1)[1:])
    z = np.array(zs)
    r = np.maximum(f(z), 0.0)
    return z, r


def build_pear(s: dict[str, Any]) -> Geometry:
    """Pear standing on its base, axis +z, origin at the base centre."""
    z, r = pear_profile(s)
    return revolved_profile(z, r, np.eye(4), "pear")


def build_washer(s: dict[str, Any]) -> Geometry:
    """Washer lying flat, axis +z, origin at the centre of its bottom face."""
    r_out = 0.5 * _f(s, "outer_diameter_mm")
    r_in = 0.5 * _f(s, "inner_diameter_mm")
    if r_in >= r_out:
        raise ValueError("inner_diameter_mm must be smaller than outer_diameter_mm")
    return _annulus(r_in, r_out, _f(s, "thickness_mm"), int(s.get("n_wedges", 24)), "washer")


def build_cylinder(s: dict[str, Any]) -> Geometry:
    """Upright can, axis +z, origin at the centre of its bottom face."""
    r = 0.5 * _f(s, "diameter_mm")
    h = _f(s, "height_mm")
    return revolved_profile(np.array([0.0, h]), np.array([r, r]), np.eye(4), "can")


def build_drill(s: dict[str, Any]) -> Geometry:
    """Power drill standing on its battery, chuck toward +x; see objects/power_drill.toml."""
    bat = np.asarray(s["battery_size_mm"], dtype=float)  # x, y, z
    bat_x = float(s["battery_center_x_mm"])
    battery = _box(np.array([bat_x, 0.0, 0.5 * bat[2]]), bat, "battery")

    tilt = math.radians(float(s["handle_tilt_deg"]))
    hx, hy = _f(s, "handle_depth_mm"), _f(s, "handle_width_mm")
    hc = np.asarray(s["handle_center_xz_mm"], dtype=float)
    body_r = 0.5 * _f(s, "body_diameter_mm")
    body_z = float(s["body_axis_z_mm"])
    corner = _f(s, "handle_corner_radius_mm")
    poly = rounded_rect(hx, hy, corner, max(4, sections_for(corner, PIECE_TOL_MM) // 4 + 1))
    # handle axis: local z = (sin t, 0, cos t) (top leans toward the chuck); bottom end
    # buried 8 mm into the battery, top end at the body axis
    z_bot = (bat[2] - 8.0 - hc[1]) / math.cos(tilt)
    z_top = (body_z - hc[1]) / math.cos(tilt)
    handle = _prism(poly, z_bot, z_top, pose(rot_y(tilt), np.array([hc[0], 0.0, hc[1]])), "handle")

    body = _capsule_x(
        float(s["body_back_x_mm"]) + body_r,
        float(s["body_front_x_mm"]) - body_r,
        body_r,
        0.0,
        body_z,
        "body",
    )
    chuck_parts = []
    for i, (x0, x1, d) in enumerate(s["chuck_segments_x0_x1_d_mm"]):
        zz = np.array([float(x0), float(x1)])
        rr = np.full(2, 0.5 * float(d))
        T = pose(R_Z_TO_X, np.array([0.0, 0.0, body_z]))
        chuck_parts.append(revolved_profile(zz, rr, T, f"chuck{i}"))

    tr = np.asarray(s["trigger_size_mm"], dtype=float)  # protrusion x, width y, height z
    tz0, tz1 = float(s["trigger_z_mm"][0]), float(s["trigger_z_mm"][1])
    tzc = 0.5 * (tz0 + tz1)
    # handle front face at the trigger's mid-height, measured along x
    front_x = hc[0] + (tzc - hc[1]) * math.tan(tilt) + 0.5 * hx / math.cos(tilt)
    overlap = 8.0
    trigger = _box(
        np.array([front_x + 0.5 * (tr[0] - overlap), 0.0, tzc]),
        np.array([tr[0] + overlap, tr[1], tz1 - tz0]),
        "trigger",
    )
    return union([battery, handle, body, *chuck_parts, trigger])


def mesh_sdf(mesh: trimesh.Trimesh) -> SdfFn:
    """Exact signed distance to a watertight mesh by trimesh (slow: closest point + ray
    containment, ~1 ms per point); the reference ``tests/test_distance_field.py`` checks
    ``MeshSdf`` against."""

    def sdf(p: np.ndarray) -> np.ndarray:
        p = _as_points(p)
        _, dist, _ = trimesh.proximity.closest_point(mesh, p)
        inside = mesh.contains(p)
        return np.where(inside, -dist, dist)

    return sdf


class MeshSdf:
    """Signed distance of an imported mesh through its distance field (``distance_field``):
    exact near the surface, built on first use and cached on disk."""

    def __init__(self, mesh: trimesh.Trimesh) -> None:
        self._mesh = mesh
        self._field: Any = None
        self.built_s: float | None = None
        """Seconds the field took to build in this process (None: loaded from the cache)."""

    def field(self) -> Any:
        """The ``DistanceField`` (loaded or built on first call)."""
        if self._field is None:
            import time

            from app.model.objects.distance_field import cached_field

            t0 = time.perf_counter()
            self._field, built = cached_field(self._mesh)
            self.built_s = time.perf_counter() - t0 if built else None
        return self._field

    def __call__(self, p: np.ndarray) -> np.ndarray:
        return self.field()(_as_points(p))


def mesh_bvh(mesh: trimesh.Trimesh) -> Any:
    """One fcl.BVHModel of a mesh (queries ~45 µs instead of ~5 µs for convex pieces)."""
    m = fcl.BVHModel()
    m.beginModel(len(mesh.vertices), len(mesh.faces))
    m.addSubModel(np.asarray(mesh.vertices, dtype=float), np.asarray(mesh.faces, dtype=np.int64))
    m.endModel()
    return m


def build_mesh_file(s: dict[str, Any], base_dir: Path | None) -> Geometry:
    """An imported object saved as a mesh file (PLY/STL/OBJ) in mm, beside its TOML file."""
    path = Path(str(s["file"]))
    if not path.is_absolute() and base_dir is not None:
        path = base_dir / path
    loaded = trimesh.load(str(path), force="mesh", process=True)
    if not isinstance(loaded, trimesh.Trimesh):
        raise ValueError(f"{path}: not a triangle mesh")
    return from_mesh(loaded)


def from_mesh(mesh: trimesh.Trimesh) -> Geometry:
    """Geometry of an already validated watertight mesh in mm (object frame = mesh frame)."""
    piece = Piece(mesh_bvh(mesh), np.eye(3), np.zeros(3), "mesh")
    return Geometry(mesh, MeshSdf(mesh), (piece,))


BUILDERS: dict[str, Callable[[dict[str, Any]], Geometry]] = {
    "marker": build_marker,
    "pear": build_pear,
    "washer": build_washer,
    "cylinder": build_cylinder,
    "drill": build_drill,
}


def build(shape: dict[str, Any], base_dir: Path | None = None) -> Geometry:
    """Geometry from a ``[shape]`` table; ``kind`` picks the builder (or ``"mesh"``)."""
    kind = str(shape.get("kind"))
    if kind == "mesh":
        return build_mesh_file(shape, base_dir)
    if kind not in BUILDERS:
        raise ValueError(f"unknown shape kind {kind!r}; valid: {sorted(BUILDERS) + ['mesh']}")
    return BUILDERS[kind](shape)
