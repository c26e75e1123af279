"""Contact patches of the compiled engine: ``app.sim.contacts.contacts_of_links`` in one
numba call per set of links.

Per link, the same steps as the numpy path: the bounding-sphere cull, the link's distance to
the object's convex pieces (exact GJK, ``app.sim.gjk``, in place of FCL: the pieces the
compiled closing engine stopped against), the exact coarse-to-fine screening of the link's
surface samples, the samples within tol (or the nearest one), farthest-point thinning in the
link frame, the object's normal by central differences and the palmar test; the signed
distance is ``app.sim.sdf_compiled`` (equal to the numpy closures to rounding). Objects
without a compiled signed distance or without piece arrays (imported meshes) return None and
the caller uses the numpy path.
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import Any

import numpy as np
from numba import njit

from app.model.contact_set import ContactSet
from app.model.hand.geometry import Shape
from app.model.objects.model import NORMAL_STEP_MM
from app.sim import gjk
from app.sim.closing_compiled import link_arrays, object_arrays
from app.sim.contacts import (
    FPS_TIE_MM2,
    SDF_LIPSCHITZ,
    ContactSettings,
    _coarse,
    _reach,
    _samples,
)
from app.sim.sdf_compiled import SdfProgram, object_program, sdf_point

LinkTables = tuple[
    np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
    np.ndarray, np.ndarray, np.ndarray,
]  # fmt: skip


@lru_cache(maxsize=256)
def link_tables(shapes: tuple[Shape, ...], spacing: float) -> LinkTables:
    """The links' shapes, samples and coarse screening as flat arrays, ``contacts_kernel``'s
    order: (T_link_fcl (L, 4, 4), type (L,), prm (L, 3), reach (L,), samples (S, 3) link
    frames, sample offsets (L + 1,), coarse indices (C,) local to their link, coarse offsets
    (L + 1,), assignment (S,) local to the link's coarse samples, δ (L,))."""
    la = link_arrays(list(shapes), np.tile(np.eye(4), (len(shapes), 1, 1)))
    T_fcl = np.stack([s.T_link_fcl() for s in shapes])
    reach = np.array([_reach(s) for s in shapes])
    samp, soff, cidx, coff, assign, delta = [], [0], [], [0], [], []
    for s in shapes:
        p, _ = _samples(s, spacing)
        idx_c, asg, d = _coarse(s, spacing)
        samp.append(p)
        soff.append(soff[-1] + len(p))
        cidx.append(idx_c)
        coff.append(coff[-1] + len(idx_c))
        assign.append(asg)
        delta.append(d)
    return (
        np.ascontiguousarray(T_fcl), la.typ, la.prm, reach,
        np.ascontiguousarray(np.concatenate(samp)), np.array(soff, np.int64),
        np.concatenate(cidx).astype(np.int64), np.array(coff, np.int64),
        np.concatenate(assign).astype(np.int64), np.array(delta),
    )  # fmt: skip


@njit(cache=True)
def _argmax_tie(d: np.ndarray, n: int, tie: float) -> int:
    """First index of ``d[:n]`` within ``tie`` of its maximum (``contacts._argmax_tie``)."""
    m = -np.inf
    for i in range(n):
        if d[i] > m:
            m = d[i]
    for i in range(n):
        if d[i] >= m - tie:
            return i
    return 0


@njit(cache=True)
def contacts_kernel(
    T_links: np.ndarray,
    T_fcl: np.ndarray,
    ltyp: np.ndarray,
    lprm: np.ndarray,
    reach: np.ndarray,
    samp: np.ndarray,
    soff: np.ndarray,
    cidx: np.ndarray,
    coff: np.ndarray,
    assign: np.ndarray,
    delta: np.ndarray,
    otyp: np.ndarray,
    oprm: np.ndarray,
    oR: np.ndarray,
    ot: np.ndarray,
    vstart: np.ndarray,
    verts: np.ndarray,
    centroid: np.ndarray,
    r_obj: float,
    prog: SdfProgram,
    tol: float,
    max_pts: int,
    cos_lim: float,
    lip: float,
    h: float,
    tie: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, int, int]:
    """Contacts of links posed at ``T_links`` (L, 4, 4): (points (n, 3), contact normals
    (n, 3), link of each (n,), palmar (n,), n, distance queries) in rows ``[:n]``."""
    L = len(T_links)
    P = np.empty((L * max_pts, 3))
    N = np.empty((L * max_pts, 3))
    link = np.empty(L * max_pts, np.int64)
    pal = np.empty(L * max_pts, np.bool_)
    n_out = 0
    queries = 0
    n_obs = len(otyp)
    for l in range(L):  # noqa: E741
        T = T_links[l]
        Tb = T @ T_fcl[l]
        cx, cy, cz = Tb[0, 3] - centroid[0], Tb[1, 3] - centroid[1], Tb[2, 3] - centroid[2]
        if math.sqrt(cx * cx + cy * cy + cz * cz) > r_obj + reach[l] + tol:
            continue
        best = np.inf
        for p in range(n_obs):
            d = gjk.shape_distance(
                ltyp[l], lprm[l], Tb[:3, :3], Tb[:3, 3],
                otyp[p], oprm[p], oR[p], ot[p], verts, 0, 0, vstart[p], vstart[p + 1],
            )  # fmt: skip
            queries += 1
            if d < best:
                best = d
        if best > tol:
            continue
        # coarse samples, then the samples whose coarse sample may be within tol
        c0, c1 = coff[l], coff[l + 1]
        s0, s1 = soff[l], soff[l + 1]
        sd_c = np.empty(c1 - c0)
        m_min = np.inf
        for c in range(c0, c1):
            k = s0 + cidx[c]
            x = T[0, 0] * samp[k, 0] + T[0, 1] * samp[k, 1] + T[0, 2] * samp[k, 2] + T[0, 3]
            y = T[1, 0] * samp[k, 0] + T[1, 1] * samp[k, 1] + T[1, 2] * samp[k, 2] + T[1, 3]
            z = T[2, 0] * samp[k, 0] + T[2, 1] * samp[k, 1] + T[2, 2] * samp[k, 2] + T[2, 3]
            v = sdf_point(x, y, z, prog)
            sd_c[c - c0] = v
            if v < m_min:
                m_min = v
        bound = max(tol, m_min) + lip * delta[l]
        sel = np.empty(s1 - s0, np.int64)
        n_sel = 0
        near, near_v = -1, np.inf
        for k in range(s0, s1):
            if sd_c[assign[k]] > bound:
                continue
            x = T[0, 0] * samp[k, 0] + T[0, 1] * samp[k, 1] + T[0, 2] * samp[k, 2] + T[0, 3]
            y = T[1, 0] * samp[k, 0] + T[1, 1] * samp[k, 1] + T[1, 2] * samp[k, 2] + T[1, 3]
            z = T[2, 0] * samp[k, 0] + T[2, 1] * samp[k, 1] + T[2, 2] * samp[k, 2] + T[2, 3]
            v = sdf_point(x, y, z, prog)
            if v <= tol:
                sel[n_sel] = k
                n_sel += 1
            if v < near_v:
                near, near_v = k, v
        if n_sel == 0:
            sel[0] = near
            n_sel = 1
        # farthest-point thinning in the link frame
        chosen = np.empty(min(n_sel, max_pts), np.int64)
        if n_sel <= max_pts:
            for i in range(n_sel):
                chosen[i] = sel[i]
        else:
            mx, my, mz = 0.0, 0.0, 0.0
            for i in range(n_sel):
                mx += samp[sel[i], 0]
                my += samp[sel[i], 1]
                mz += samp[sel[i], 2]
            mx, my, mz = mx / n_sel, my / n_sel, mz / n_sel
            d = np.empty(n_sel)
            for i in range(n_sel):
                a = samp[sel[i]]
                d[i] = (a[0] - mx) ** 2 + (a[1] - my) ** 2 + (a[2] - mz) ** 2
            j = _argmax_tie(d, n_sel, tie)
            chosen[0] = sel[j]
            b = samp[sel[j]]
            for i in range(n_sel):
                a = samp[sel[i]]
                d[i] = (a[0] - b[0]) ** 2 + (a[1] - b[1]) ** 2 + (a[2] - b[2]) ** 2
            for m in range(1, max_pts):
                j = _argmax_tie(d, n_sel, tie)
                chosen[m] = sel[j]
                b = samp[sel[j]]
                for i in range(n_sel):
                    a = samp[sel[i]]
                    e = (a[0] - b[0]) ** 2 + (a[1] - b[1]) ** 2 + (a[2] - b[2]) ** 2
                    if e < d[i]:
                        d[i] = e
        for k in chosen:
            q = np.empty(3)
            for r in range(3):
                q[r] = T[r, 0] * samp[k, 0] + T[r, 1] * samp[k, 1] + T[r, 2] * samp[k, 2]
                q[r] += T[r, 3]
            g = np.empty(3)
            for r in range(3):
                q[r] += h
                fp = sdf_point(q[0], q[1], q[2], prog)
                q[r] -= h
                q[r] -= h
                fm = sdf_point(q[0], q[1], q[2], prog)
                q[r] += h
                g[r] = (fp - fm) / (2 * h)
            nrm = math.sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2])
            if nrm <= 1e-12:
                nrm = 1.0
            for r in range(3):
                P[n_out, r] = q[r]
                N[n_out, r] = -(g[r] / nrm)
            link[n_out] = l
            c = N[n_out, 0] * T[0, 2] + N[n_out, 1] * T[1, 2] + N[n_out, 2] * T[2, 2]
            pal[n_out] = c > cos_lim
            n_out += 1
    return P, N, link, pal, n_out, queries


def contacts_compiled(
    obj: Any,
    names: list[str],
    shapes: list[Shape],
    T_object_links: np.ndarray,
    settings: ContactSettings,
    palmar_angle_deg: float,
    counter: list[int] | None = None,
) -> ContactSet | None:
    """``contacts_of_links`` on the compiled path, or None when the object has no compiled
    signed distance or piece arrays (the caller then uses the numpy path)."""
    prog = object_program(obj)
    arr = object_arrays(obj)
    if prog is None or arr is None:
        return None
    tables = link_tables(tuple(shapes), float(settings.sample_spacing_mm))
    P, N, link, pal, n, queries = contacts_kernel(
        np.ascontiguousarray(T_object_links, float), *tables,
        arr.typ, arr.prm, arr.R, arr.t, arr.vstart, arr.verts,
        np.asarray(obj.centroid_object, float), float(obj.max_radius), prog,
        float(settings.contact_tol_mm), int(settings.max_points_per_link),
        float(np.cos(np.deg2rad(palmar_angle_deg))), SDF_LIPSCHITZ, NORMAL_STEP_MM,
        FPS_TIE_MM2,
    )  # fmt: skip
    if counter is not None:
        counter[0] += int(queries)
    if n == 0:
        return ContactSet()
    names_arr = np.array(names, dtype=object)
    return ContactSet(P[:n].copy(), N[:n].copy(), names_arr[link[:n]], pal[:n].copy())
