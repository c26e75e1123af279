"""Contact patches of the compiled engine: ``app.sim.contacts.contacts_of_links`` in one
numba call per set of links.

Per link, the same steps as the numpy path: the bounding-sphere cull, the link's distance to
the object's convex pieces (exact GJK, ``app.sim.gjk``, in place of FCL: the pieces the
compiled closing engine stopped against), the exact coarse-to-fine screening of the link's
surface samples, the samples within tol (or the nearest one), farthest-point thinning in the
link frame, the object's normal by central differences and the palmar test; the signed
distance is ``app.sim.sdf_compiled`` (equal to the numpy closures to rounding). An imported
mesh (one ``MESH`` piece) takes the same steps on its distance field: the link's distance
from ``app.sim.mesh_distance`` (exact up to tol, as the numpy path's ``link_mesh_distance``)
and the signed distance from ``distance_field.point_sdf`` (the function the numpy path's
``MeshSdf`` calls). Objects without either (a stand-in without piece arrays) return None and
the caller uses the numpy path.
"""

from __future__ import annotations

import math
import warnings
from functools import lru_cache
from typing import Any

import numpy as np
from numba import errors, njit, types
from numba.extending import overload

from app.model.contact_set import ContactSet
from app.model.hand.geometry import Shape
from app.model.objects.distance_field import point_sdf, signed_bounds
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
from app.sim.mesh_distance import MESH, mesh_distance
from app.sim.sdf_compiled import object_program, sdf_point

# numba's pedantic SSA check flags the variables of ``sdf_point`` inlined through the
# ``object_sd`` overload (a known false alarm of nested inlining); the code is correct
warnings.filterwarnings(
    "ignore", message="variable '_object_sd_impl", category=errors.NumbaIRAssumptionWarning
)

LinkTables = tuple[
    np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
    np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
]  # fmt: skip

#: Cell size (mm) of the super-coarse samples that screen the coarse ones.
SUPER_CELL_MM = 12.0


def _piece_spheres(arr: Any) -> np.ndarray:
    """(P, 4) a bounding sphere (centre, radius) of each piece, object frame."""
    out = np.zeros((len(arr), 4))
    for p in range(len(arr)):
        v = arr.verts[arr.vstart[p] : arr.vstart[p + 1]]
        if len(v):
            c = 0.5 * (v.min(0) + v.max(0))
            r = float(np.linalg.norm(v - c, axis=1).max())
        else:
            c = np.zeros(3)
            typ, prm = arr.typ[p], arr.prm[p]
            if typ == gjk.BOX:
                r = float(np.linalg.norm(prm))
            elif typ == gjk.CYLINDER:
                r = float(np.hypot(prm[0], prm[1]))
            else:  # capsule, sphere
                r = float(prm[0] + prm[1])
        out[p, :3] = arr.R[p] @ c + arr.t[p]
        out[p, 3] = r + 1e-6
    return out


_SPHERES: dict[int, tuple[Any, np.ndarray]] = {}


def piece_spheres(arr: Any) -> np.ndarray:
    """``_piece_spheres`` cached per arrays object."""
    hit = _SPHERES.get(id(arr))
    if hit is not None and hit[0] is arr:
        return hit[1]
    if len(_SPHERES) >= 64:
        _SPHERES.clear()
    out = _piece_spheres(arr)
    _SPHERES[id(arr)] = (arr, out)
    return out


@lru_cache(maxsize=256)
def link_tables(shapes: tuple[Shape, ...], spacing: float) -> LinkTables:
    """The links' shapes, samples and coarse screening as flat arrays, ``contacts_kernel``'s
    order: (T_link_fcl (L, 4, 4), type (L,), prm (L, 3), reach (L,), samples (S, 3) link
    frames, sample offsets (L + 1,), coarse indices (C,) local to their link, coarse offsets
    (L + 1,), assignment (S,) local to the link's coarse samples, each sample's distance to
    its coarse sample (S,), the super-coarse sample of each coarse sample (C,) (local
    coarse index; super-coarse samples are coarse samples, one per ``SUPER_CELL_MM`` cell,
    assigned to themselves), the coarse sample's distance to it (C,), the largest distance
    of a sample to its coarse sample (C,))."""
    la = link_arrays(list(shapes), np.tile(np.eye(4), (len(shapes), 1, 1)))
    T_fcl = np.stack([s.T_link_fcl() for s in shapes])
    reach = np.array([_reach(s) for s in shapes])
    from scipy.spatial import cKDTree

    samp, soff, cidx, coff, assign, dist = [], [0], [], [0], [], []
    sup, dcs, cmax = [], [], []
    for s in shapes:
        p, _ = _samples(s, spacing)
        idx_c, asg, _ = _coarse(s, spacing)
        samp.append(p)
        soff.append(soff[-1] + len(p))
        cidx.append(idx_c)
        coff.append(coff[-1] + len(idx_c))
        assign.append(asg)
        dist.append(np.linalg.norm(p - p[idx_c][asg], axis=1))
        pc = p[idx_c]
        cell = np.floor(pc / SUPER_CELL_MM).astype(np.int64)
        _, first = np.unique(cell, axis=0, return_index=True)
        first = np.sort(first)
        d_s, a_s = cKDTree(pc[first]).query(pc)
        a_s = first[np.asarray(a_s)]
        a_s[first] = first  # a super-coarse sample screens itself (ties in the tree)
        sup.append(a_s.astype(np.int64))
        dcs.append(np.linalg.norm(pc - pc[a_s], axis=1))
        cm = np.zeros(len(idx_c))
        np.maximum.at(cm, asg, dist[-1])
        cmax.append(cm)
    return (
        np.ascontiguousarray(T_fcl), la.typ, la.prm, reach,
        np.ascontiguousarray(np.concatenate(samp)), np.array(soff, np.int64),
        np.concatenate(cidx).astype(np.int64), np.array(coff, np.int64),
        np.concatenate(assign).astype(np.int64), np.concatenate(dist),
        np.concatenate(sup), np.concatenate(dcs), np.concatenate(cmax),
    )  # fmt: skip


@njit(cache=True, inline="always")
def _posed_sample(
    T: np.ndarray, samp: np.ndarray, k: int | np.integer
) -> tuple[float, float, float]:
    """Link sample ``k`` (``samp`` rows, link frame) in the object frame (``T`` = T_object_link
    (4, 4))."""
    return (
        T[0, 0] * samp[k, 0] + T[0, 1] * samp[k, 1] + T[0, 2] * samp[k, 2] + T[0, 3],
        T[1, 0] * samp[k, 0] + T[1, 1] * samp[k, 1] + T[1, 2] * samp[k, 2] + T[1, 3],
        T[2, 0] * samp[k, 0] + T[2, 1] * samp[k, 1] + T[2, 2] * samp[k, 2] + T[2, 3],
    )


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


def object_sd(px: float, py: float, pz: float, src: Any) -> float:
    """The object's signed distance at one point, for compiled callers: ``src`` is an
    ``SdfProgram`` (analytic parts, ``sdf_point``) or a mesh's ``DistanceField.pack``
    (``point_sdf``). Numba picks the implementation by the type of ``src`` (one compiled
    specialisation of the caller per kind: the analytic kernels never unbox a mesh pack)."""
    raise NotImplementedError("compiled code only")


def object_mesh_distance(typ: int, prm: np.ndarray, R: np.ndarray, t: np.ndarray, src: Any,
                         exact_above: float) -> float:  # fmt: skip
    """``mesh_distance`` of a link to the mesh of ``src`` (a ``DistanceField.pack``); inf
    for an ``SdfProgram`` (an analytic object has no ``MESH`` piece)."""
    raise NotImplementedError("compiled code only")


def _is_mesh_pack(src: Any) -> bool:
    """Whether a numba type is a ``MeshPack`` (20 items, the spacing a float) rather than an
    ``SdfProgram`` (15 arrays)."""
    return isinstance(src, types.BaseTuple) and len(src) == 20


def mesh_select(T: np.ndarray, samp: np.ndarray, s0: int, s1: int, cidx: np.ndarray, c0: int,
                c1: int, assign: np.ndarray, sdist: np.ndarray, lip: float, tol: float,
                src: Any, sel: np.ndarray) -> int:  # fmt: skip
    """For an imported mesh (``src`` a ``DistanceField.pack``): the link's samples (rows
    ``s0:s1`` of ``samp``, posed at ``T``) whose signed distance is <= tol, written in sample
    order to ``sel``; their number. 0 for an ``SdfProgram`` (analytic objects keep the exact
    screening of ``contacts_kernel``), and 0 when no sample is within tol (the caller then
    takes those exact steps, which find the nearest sample).

    The same samples as that screening, found more cheaply: the field's node bounds
    (``signed_bounds``, ~50 ns) screen the coarse samples (a sample within tol has a coarse
    sample whose lower bound is <= tol + L·its distance to it) and then each sample; the
    exact value (``point_sdf``, 2–10 µs) is computed only when the bounds straddle tol."""
    raise NotImplementedError("compiled code only")


@njit(cache=True)
def _mesh_select(T: np.ndarray, samp: np.ndarray, s0: int, s1: int, cidx: np.ndarray, c0: int,
                 c1: int, assign: np.ndarray, sdist: np.ndarray, lip: float, tol: float,
                 pk: Any, sel: np.ndarray) -> int:  # fmt: skip
    """``mesh_select`` of a mesh pack."""
    lo_c = np.empty(c1 - c0)
    for c in range(c0, c1):
        k = s0 + cidx[c]
        x, y, z = _posed_sample(T, samp, k)
        lo_c[c - c0] = signed_bounds(pk, x, y, z)[0]
    n_sel = 0
    for k in range(s0, s1):
        if lo_c[assign[k]] - lip * sdist[k] > tol:
            continue
        x, y, z = _posed_sample(T, samp, k)
        lo, hi = signed_bounds(pk, x, y, z)
        if lo > tol:
            continue
        if hi <= tol or point_sdf(pk, x, y, z) <= tol:
            sel[n_sel] = k
            n_sel += 1
    return n_sel


@overload(mesh_select, jit_options={"cache": True})  # type: ignore[arg-type]
def _mesh_select_impl(T, samp, s0, s1, cidx, c0, c1, assign, sdist, lip, tol, src, sel):  # noqa: ANN001, ANN202, E501
    if _is_mesh_pack(src):
        return lambda T, samp, s0, s1, cidx, c0, c1, assign, sdist, lip, tol, src, sel: (
            _mesh_select(T, samp, s0, s1, cidx, c0, c1, assign, sdist, lip, tol, src, sel)
        )
    return lambda T, samp, s0, s1, cidx, c0, c1, assign, sdist, lip, tol, src, sel: 0


@overload(object_sd, inline="always", jit_options={"cache": True})  # type: ignore[arg-type]
def _object_sd_impl(px, py, pz, src):  # noqa: ANN001, ANN202 (numba types)
    if _is_mesh_pack(src):
        return lambda px, py, pz, src: point_sdf(src, px, py, pz)
    return lambda px, py, pz, src: sdf_point(px, py, pz, src)


@overload(object_mesh_distance, jit_options={"cache": True})  # type: ignore[arg-type]
def _object_mesh_distance_impl(typ, prm, R, t, src, exact_above):  # noqa: ANN001, ANN202
    if _is_mesh_pack(src):
        return lambda typ, prm, R, t, src, exact_above: mesh_distance(
            typ, prm, R, t, src, exact_above
        )
    return lambda typ, prm, R, t, src, exact_above: np.inf


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
    sdist: np.ndarray,
    sup: np.ndarray,
    dcs: np.ndarray,
    cmax: np.ndarray,
    otyp: np.ndarray,
    oprm: np.ndarray,
    oR: np.ndarray,
    ot: np.ndarray,
    vstart: np.ndarray,
    verts: np.ndarray,
    nbr_start: np.ndarray,
    nbr: np.ndarray,
    ospheres: np.ndarray,
    centroid: np.ndarray,
    r_obj: float,
    prog: Any,
    tol: float,
    max_pts: int,
    cos_lim: float,
    lip: float,
    h: float,
    tie: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, int, int]:
    """Contacts of links posed at ``T_links`` (L, 4, 4): (points (n, 3), contact normals
    (n, 3), link of each (n,), palmar (n,), n, distance queries) in rows ``[:n]``.

    Screening as the numpy path's, exact, with per-sample bounds: a sample at distance
    ``sdist`` from its coarse sample has a signed distance >= the coarse value - L·sdist (L
    the Lipschitz bound), so only samples whose bound is <= max(tol, the smallest coarse
    value) are evaluated; pieces whose bounding sphere is farther than tol are not queried.
    ``prog``: the object's ``SdfProgram``, or an imported mesh's ``DistanceField.pack``
    (its one piece is a ``MESH`` row, whose sphere must be infinite)."""
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
            ex, ey, ez = (
                Tb[0, 3] - ospheres[p, 0],
                Tb[1, 3] - ospheres[p, 1],
                Tb[2, 3] - ospheres[p, 2],
            )
            if math.sqrt(ex * ex + ey * ey + ez * ez) - reach[l] - ospheres[p, 3] > tol:
                continue
            if otyp[p] == MESH:  # exact when it may be <= tol, else a lower bound above
                d = object_mesh_distance(ltyp[l], lprm[l], Tb[:3, :3], Tb[:3, 3], prog, tol)
            else:
                d = gjk.shape_distance_nbr(
                    ltyp[l], lprm[l], Tb[:3, :3], Tb[:3, 3], otyp[p], oprm[p], oR[p], ot[p],
                    verts, nbr_start, nbr, 0, 0, vstart[p], vstart[p + 1],
                )  # fmt: skip
            queries += 1
            if d < best:
                best = d
        if best > tol:
            continue
        c0, c1 = coff[l], coff[l + 1]
        s0, s1 = soff[l], soff[l + 1]
        sel = np.empty(s1 - s0, np.int64)
        # an imported mesh: the samples within tol found from the field's bounds, exact
        # values only where they straddle tol (``mesh_select``); when there is none (a
        # grazing contact; always for analytic objects), the exact steps below
        n_sel = mesh_select(T, samp, s0, s1, cidx, c0, c1, assign, sdist, lip, tol, prog, sel)
        if n_sel == 0:
            # coarse samples, then the samples whose coarse sample may be within tol
            # (super-coarse samples first: a coarse sample whose bound from its super-coarse
            # sample keeps all its samples above tol gets that bound instead of its value)
            sd_c = np.empty(c1 - c0)
            exact = np.zeros(c1 - c0, np.bool_)
            for sweep in range(3):
                for c in range(c0, c1):
                    if exact[c - c0]:
                        continue
                    if sweep == 0 and sup[c] != c - c0:
                        continue
                    if sweep == 1:
                        lb = sd_c[sup[c]] - lip * dcs[c]
                        if lb - lip * cmax[c] > tol:
                            sd_c[c - c0] = lb
                            continue
                    k = s0 + cidx[c]
                    x, y, z = _posed_sample(T, samp, k)
                    sd_c[c - c0] = object_sd(x, y, z, prog)
                    exact[c - c0] = True
                if sweep == 1:
                    m_min = np.inf
                    for c in range(c1 - c0):
                        if exact[c] and sd_c[c] < m_min:
                            m_min = sd_c[c]
                    if m_min <= tol:
                        break  # else (a grazing contact): every coarse value, for the nearest
            m_min = np.inf
            for c in range(c1 - c0):
                if exact[c] and sd_c[c] < m_min:
                    m_min = sd_c[c]
            bound = max(tol, m_min)
            near, near_v = -1, np.inf
            for k in range(s0, s1):
                if sd_c[assign[k]] - lip * sdist[k] > bound:
                    continue
                x, y, z = _posed_sample(T, samp, k)
                v = object_sd(x, y, z, prog)
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
            q[0], q[1], q[2] = _posed_sample(T, samp, k)
            g = np.empty(3)
            for r in range(3):
                q[r] += h
                fp = object_sd(q[0], q[1], q[2], prog)
                q[r] -= h
                q[r] -= h
                fm = object_sd(q[0], q[1], q[2], prog)
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


_MESH_SPHERES: dict[int, tuple[Any, np.ndarray]] = {}


def _kernel_spheres(arr: Any) -> np.ndarray:
    """``piece_spheres`` with the ``MESH`` row made infinite (it has no vertices to bound)."""
    if arr.mesh is None:
        return piece_spheres(arr)
    hit = _MESH_SPHERES.get(id(arr))
    if hit is not None and hit[0] is arr:
        return hit[1]
    out = piece_spheres(arr).copy()
    out[arr.typ == MESH, 3] = np.inf
    if len(_MESH_SPHERES) >= 64:
        _MESH_SPHERES.clear()
    _MESH_SPHERES[id(arr)] = (arr, out)
    return out


def contacts_compiled(
    obj: Any,
    names: list[str],
    shapes: list[Shape],
    T_object_links: np.ndarray,
    settings: ContactSettings,
    palmar_angle_deg: float,
    counter: list[int] | None = None,
) -> ContactSet | None:
    """``contacts_of_links`` on the compiled path (analytic objects and imported meshes with
    their distance field), or None when the object has neither a compiled signed distance
    nor a mesh pack, or no piece arrays (the caller then uses the numpy path)."""
    arr = object_arrays(obj)
    if arr is None:
        return None
    prog = arr.mesh if arr.mesh is not None else object_program(obj)
    if prog is None:
        return None
    tables = link_tables(tuple(shapes), float(settings.sample_spacing_mm))
    P, N, link, pal, n, queries = contacts_kernel(
        np.ascontiguousarray(T_object_links, float), *tables,
        arr.typ, arr.prm, arr.R, arr.t, arr.vstart, arr.verts, arr.nbr_start, arr.nbr,
        _kernel_spheres(arr),
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
