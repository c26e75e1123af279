"""The built-in objects' signed distances compiled with numba (the compiled contact path).

An object's ``sdf_parts`` (``app.model.objects.shapes.SdfPart``) are packed once into flat
arrays (an ``SdfProgram``); ``sdf_point`` evaluates the same formulas as the numpy closures
of ``shapes.py`` for one point: surfaces of revolution and the drill's handle read the same
``PolygonSdfTable`` grid (bilinear inside it, the exact 2-D polygon distance outside), the
washer the exact polygon distance, boxes and capsules their closed forms, and a union the
minimum over its parts with the same bounding-sphere skip. The values agree with the numpy
ones to rounding (``tests/test_contacts.py`` checks 1e-9 mm on random points of every
built-in object). Imported meshes have no parts: they keep the numpy path.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import njit

REVOLVED = 0
ANNULUS = 1
BOX = 2
PRISM = 3
CAPSULE_X = 4
_KINDS = {"revolved": REVOLVED, "annulus": ANNULUS, "box": BOX, "prism": PRISM}
_KINDS["capsule_x"] = CAPSULE_X

#: The packed program: (kind (Q,), R (Q, 3, 3), t (Q, 3), prm (Q, 8), tab (Q,), poly (Q,),
#: tab_lo (T, 2), tab_h (T,), tab_n (T, 2), tab_off (T + 1,), tab_data (G,), poly_off (P + 1,),
#: poly_v (V, 2), poly_real (V,), bounds (Q, 4)).
SdfProgram = tuple[
    np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
    np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
    np.ndarray,
]  # fmt: skip


def pack(parts: Any, bounds: np.ndarray | None) -> SdfProgram:
    """Flat arrays of an object's ``sdf_parts`` (and a union's bounding spheres)."""
    q = len(parts)
    kind = np.zeros(q, np.int64)
    R = np.zeros((q, 3, 3))
    t = np.zeros((q, 3))
    prm = np.zeros((q, 8))
    tab = np.full(q, -1, np.int64)
    poly = np.full(q, -1, np.int64)
    tab_lo, tab_h, tab_n, tab_data = [], [], [], []
    tab_off = [0]
    poly_v, poly_real = [], []
    poly_off = [0]
    for i, part in enumerate(parts):
        kind[i] = _KINDS[part.kind]
        T = np.asarray(part.T, float)
        R[i], t[i] = T[:3, :3], T[:3, 3]
        prm[i, : len(part.params)] = part.params
        if part.table is not None:
            grid = part.table.grid()
            tab[i] = len(tab_h)
            tab_lo.append(np.asarray(part.table.lo, float))
            tab_h.append(float(part.table.h))
            tab_n.append(np.asarray(part.table.shape, np.int64))
            tab_data.append(np.ascontiguousarray(grid, float).ravel())
            tab_off.append(tab_off[-1] + grid.size)
            verts, real = part.table.verts, part.table.real
        else:
            verts, real = part.poly, part.real
        if verts is not None:
            poly[i] = len(poly_off) - 1
            poly_v.append(np.asarray(verts, float))
            poly_real.append(np.asarray(real, np.bool_))
            poly_off.append(poly_off[-1] + len(verts))
    b = np.zeros((q, 4))
    b[:, 3] = np.inf  # one part: never skipped
    if bounds is not None:
        b[:] = bounds
    return (
        kind, R, t, prm, tab, poly,
        np.array(tab_lo, float).reshape(-1, 2), np.array(tab_h, float),
        np.array(tab_n, np.int64).reshape(-1, 2), np.array(tab_off, np.int64),
        np.concatenate(tab_data) if tab_data else np.zeros(0),
        np.array(poly_off, np.int64),
        np.concatenate(poly_v) if poly_v else np.zeros((0, 2)),
        np.concatenate(poly_real) if poly_real else np.zeros(0, np.bool_),
        b,
    )  # fmt: skip


_CACHE: dict[int, tuple[Any, SdfProgram | None]] = {}


def object_program(target: Any) -> SdfProgram | None:
    """The object's packed signed distance (cached per object), or None (imported meshes,
    stand-ins without ``sdf_parts``)."""
    hit = _CACHE.get(id(target))
    if hit is not None and hit[0] is target:
        return hit[1]
    parts = getattr(target, "sdf_parts", None)
    prog = None if parts is None else pack(parts, getattr(target, "sdf_bounds", None))
    if len(_CACHE) >= 64:
        _CACHE.clear()
    _CACHE[id(target)] = (target, prog)
    return prog


@njit(cache=True)
def poly_sdf_2d(x: float, y: float, pv: np.ndarray, real: np.ndarray, o0: int, o1: int) -> float:
    """``shapes.polygon_sdf_2d`` of one point against polygon ``pv[o0:o1]``."""
    m = o1 - o0
    best = np.inf
    count = 0
    for i in range(m):
        ax, ay = pv[o0 + i, 0], pv[o0 + i, 1]
        j = o0 + (i + 1) % m
        bx, by = pv[j, 0], pv[j, 1]
        abx, aby = bx - ax, by - ay
        ab2 = max(abx * abx + aby * aby, 1e-300)
        aqx, aqy = x - ax, y - ay
        tt = (aqx * abx + aqy * aby) / ab2
        tt = min(max(tt, 0.0), 1.0)
        dx, dy = aqx - tt * abx, aqy - tt * aby
        d2 = dx * dx + dy * dy
        if real[o0 + i] and d2 < best:
            best = d2
        if (ay > y) != (by > y):
            xc = ax + (y - ay) * abx / aby
            if x < xc:
                count += 1
    dist = math.sqrt(best)
    return -dist if count % 2 == 1 else dist


@njit(cache=True, inline="always")
def _table(x: float, y: float, k: int, pi: int, prog: SdfProgram) -> float:
    """``PolygonSdfTable.__call__`` of one point (table ``k``, its polygon ``pi``)."""
    tab_lo, tab_h, tab_n, tab_off, tab_data = prog[6], prog[7], prog[8], prog[9], prog[10]
    poly_off, poly_v, poly_real = prog[11], prog[12], prog[13]
    h = tab_h[k]
    u0 = (x - tab_lo[k, 0]) / h
    u1 = (y - tab_lo[k, 1]) / h
    f0, f1 = math.floor(u0), math.floor(u1)
    n0, n1 = tab_n[k, 0], tab_n[k, 1]
    if not (f0 >= 0 and f1 >= 0 and f0 < n0 - 1 and f1 < n1 - 1):
        return poly_sdf_2d(x, y, poly_v, poly_real, poly_off[pi], poly_off[pi + 1])
    a, b = int(f0), int(f1)
    fx, fy = u0 - a, u1 - b
    base = tab_off[k]
    g00 = tab_data[base + a * n1 + b]
    g10 = tab_data[base + (a + 1) * n1 + b]
    g01 = tab_data[base + a * n1 + b + 1]
    g11 = tab_data[base + (a + 1) * n1 + b + 1]
    return g00 * (1 - fx) * (1 - fy) + g10 * fx * (1 - fy) + g01 * (1 - fx) * fy + g11 * fx * fy


@njit(cache=True, inline="always")
def part_sdf(i: int, px: float, py: float, pz: float, prog: SdfProgram) -> float:
    """Signed distance of one part at one point (object frame)."""
    kind, R, t, prm, tab, poly = prog[0], prog[1], prog[2], prog[3], prog[4], prog[5]
    k = kind[i]
    if k == REVOLVED or k == PRISM:  # (p - t) @ R: into the local frame
        dx, dy, dz = px - t[i, 0], py - t[i, 1], pz - t[i, 2]
        lx = dx * R[i, 0, 0] + dy * R[i, 1, 0] + dz * R[i, 2, 0]
        ly = dx * R[i, 0, 1] + dy * R[i, 1, 1] + dz * R[i, 2, 1]
        lz = dx * R[i, 0, 2] + dy * R[i, 1, 2] + dz * R[i, 2, 2]
        if k == REVOLVED:
            return _table(math.hypot(lx, ly), lz, tab[i], poly[i], prog)
        d2 = _table(lx, ly, tab[i], poly[i], prog)
        dzz = abs(lz - prm[i, 0]) - prm[i, 1]
        outside = math.hypot(max(d2, 0.0), max(dzz, 0.0))
        return outside + min(max(d2, dzz), 0.0)
    if k == ANNULUS:
        pi = poly[i]
        o0, o1 = int(prog[11][pi]), int(prog[11][pi + 1])
        return poly_sdf_2d(math.hypot(px, py), pz, prog[12], prog[13], o0, o1)
    if k == BOX:
        qx = abs(px - prm[i, 0]) - prm[i, 3]
        qy = abs(py - prm[i, 1]) - prm[i, 4]
        qz = abs(pz - prm[i, 2]) - prm[i, 5]
        ox, oy, oz = max(qx, 0.0), max(qy, 0.0), max(qz, 0.0)
        return math.sqrt(ox * ox + oy * oy + oz * oz) + min(max(qx, max(qy, qz)), 0.0)
    # CAPSULE_X: x0, length, y, z, radius
    s = min(max(px - prm[i, 0], 0.0), prm[i, 1])
    dx = (px - prm[i, 0]) - s
    dy, dz = py - prm[i, 2], pz - prm[i, 3]
    return math.sqrt(dx * dx + dy * dy + dz * dz) - prm[i, 4]


@njit(cache=True, inline="always")
def sdf_point(px: float, py: float, pz: float, prog: SdfProgram) -> float:
    """The object's signed distance at one point (``shapes.union`` semantics)."""
    n = len(prog[0])
    if n == 1:
        return part_sdf(0, px, py, pz, prog)
    bounds = prog[14]
    lb = np.empty(n)
    for j in range(n):
        ex, ey, ez = px - bounds[j, 0], py - bounds[j, 1], pz - bounds[j, 2]
        lb[j] = math.sqrt(ex * ex + ey * ey + ez * ez) - bounds[j, 3]
    best = np.inf
    for _ in range(n):  # parts by increasing bound; the rest cannot lower the minimum
        j = 0
        for m in range(1, n):
            if lb[m] < lb[j]:
                j = m
        if not lb[j] < best:
            break
        lb[j] = np.inf
        v = part_sdf(j, px, py, pz, prog)
        if v < best:
            best = v
    return best


@njit(cache=True)
def sdf_many(p: np.ndarray, prog: SdfProgram) -> np.ndarray:
    """``sdf_point`` of every row of ``p`` (N, 3)."""
    out = np.empty(len(p))
    for i in range(len(p)):
        out[i] = sdf_point(p[i, 0], p[i, 1], p[i, 2], prog)
    return out
