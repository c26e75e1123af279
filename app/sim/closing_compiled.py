"""The compiled closing engine: ``advance_stage`` and ``approach`` of ``app.sim.closing``
ported to numba over flat arrays, with exact GJK distances (``app.sim.gjk``) in place of FCL.

Same algorithm, line for line: conservative advancement with a lower bound per (moving link,
obstacle) pair and lazy exact evaluation (the smallest bound queried until it is exact, all
bounds <= tol queried), the axis-rate bound (computed once per single-joint stage), the
false-position (Illinois) refinement of the stop to within ``REFINE_BAND`` · tol below tol
(at most ``REFINE_ITERS`` probes), ``max_steps``; the approach with ``EXACT_BELOW_MM``. Only
the distance differs: GJK here is exact to ~1e-9 mm, FCL's (libccd) to ~1e-4–1e-3 mm on
some poses (measured in ``tests/test_gjk.py``), so stops agree to that order.

Obstacles are the object's convex pieces (types and vertices kept by the model, see
``app.model.objects.shapes.Piece.vertices``) plus, for the thumb, the hand's palm box and
long-finger capsules. An imported mesh (FCL's ``fcl.BVHModel``) is one ``MESH`` row, whose
distances come from its distance field and GJK on nearby triangles
(``app.sim.mesh_distance``). Objects with a piece the arrays cannot describe (a Convex
without its vertices, a mesh without a field) have no arrays, and the caller falls back to
FCL.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import fcl
import numpy as np
from numba import njit

from app.model.hand.chains import FingerChain
from app.model.hand.geometry import BoxShape, CapsuleShape
from app.model.objects.distance_field import MeshPack, empty_pack
from app.sim import gjk
from app.sim.closing_settings import EXACT_BELOW_MM, REFINE_BAND, REFINE_ITERS
from app.sim.mesh_distance import MESH, mesh_distance

#: A mesh obstacle's distance is exact when it may be below tol + this (a lower bound above).
MESH_EXACT_MM = 2.0

_EMPTY_PACK: list[MeshPack] = []


def _pack(arrays: ObstacleArrays) -> MeshPack:
    """The mesh pack of ``arrays``, or an empty one of the same types."""
    if arrays.mesh is not None:
        return arrays.mesh
    if not _EMPTY_PACK:
        _EMPTY_PACK.append(empty_pack())
    return _EMPTY_PACK[0]


#: Event codes returned by the compiled stage (``StageEvent.kind`` in that order).
EVENT_KINDS = ("contact", "self", "limit", "max_steps")


@dataclass(frozen=True)
class ObstacleArrays:
    """Shapes of a closing problem's obstacles as flat arrays (object frame)."""

    typ: np.ndarray
    """(P,) int64 ``app.sim.gjk`` shape type."""
    prm: np.ndarray
    """(P, 3) shape parameters."""
    R: np.ndarray
    """(P, 3, 3) rotation of each shape frame."""
    t: np.ndarray
    """(P, 3) origin of each shape frame."""
    vstart: np.ndarray
    """(P + 1,) int64: vertices of shape p are ``verts[vstart[p]:vstart[p + 1]]``."""
    verts: np.ndarray
    """(V, 3) hull vertices of the ``POINTS`` shapes, shape frames."""
    mesh: Any = None
    """The imported mesh's ``DistanceField.pack`` when a row is ``MESH`` (at most one)."""
    nbr_start: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(1, np.int64))
    """(V + 1,) int64: the hull-edge neighbours of vertex i are ``nbr[nbr_start[i]:
    nbr_start[i + 1]]`` (``gjk.hull_neighbours``; large ``POINTS`` shapes only, others have
    none and are scanned)."""
    nbr: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0, np.int64))
    """(E,) int64 rows of ``verts``."""

    def __len__(self) -> int:
        return len(self.typ)

    def concat(self, other: ObstacleArrays) -> ObstacleArrays:
        """These shapes followed by ``other``'s."""
        return ObstacleArrays(
            np.concatenate([self.typ, other.typ]),
            np.concatenate([self.prm, other.prm]),
            np.concatenate([self.R, other.R]),
            np.concatenate([self.t, other.t]),
            np.concatenate([self.vstart[:-1], other.vstart + self.vstart[-1]]),
            np.concatenate([self.verts, other.verts]),
            self.mesh if self.mesh is not None else other.mesh,
            np.concatenate([self.nbr_start[:-1], other.nbr_start + self.nbr_start[-1]]),
            np.concatenate([self.nbr, other.nbr + len(self.verts)]),
        )


def _arrays(
    rows: list[tuple[int, np.ndarray, np.ndarray, np.ndarray, np.ndarray | None]],
) -> ObstacleArrays:
    n = len(rows)
    vstart = np.zeros(n + 1, np.int64)
    vs = []
    starts: list[np.ndarray] = []  # per vertex: its number of neighbours
    nbrs: list[np.ndarray] = []
    for i, r in enumerate(rows):
        k = 0 if r[4] is None else len(r[4])
        vstart[i + 1] = vstart[i] + k
        if r[4] is not None:
            v = np.asarray(r[4], float)
            vs.append(v)
            counts, ids = np.zeros(k, np.int64), np.zeros(0, np.int64)
            if k >= gjk.CLIMB_MIN_VERTS:
                try:
                    st, nb = gjk.hull_neighbours(v)
                except Exception:  # flat or degenerate (QhullError): scanned
                    st = None
                if st is not None and len(nb):
                    counts, ids = np.diff(st), nb + vstart[i]
            starts.append(counts)
            nbrs.append(ids)
    cnt = np.concatenate(starts) if starts else np.zeros(0, np.int64)
    return ObstacleArrays(
        np.array([r[0] for r in rows], np.int64),
        np.array([r[1] for r in rows], float).reshape(n, 3),
        np.array([r[2] for r in rows], float).reshape(n, 3, 3),
        np.array([r[3] for r in rows], float).reshape(n, 3),
        vstart,
        np.ascontiguousarray(np.concatenate(vs) if vs else np.zeros((0, 3))),
        None,
        np.concatenate([[0], np.cumsum(cnt)]).astype(np.int64),
        np.ascontiguousarray(np.concatenate(nbrs) if nbrs else np.zeros(0, np.int64), np.int64),
    )


def _pieces_arrays(target: Any) -> ObstacleArrays | None:
    # ``pieces`` (``GraspObject``, the tests' stand-ins) is not part of ``GraspTarget``: FCL
    # objects do not expose their geometry, so a target without it is left to FCL
    pieces = getattr(target, "pieces", None)
    if pieces is None:
        return None
    rows: list[tuple[int, np.ndarray, np.ndarray, np.ndarray, np.ndarray | None]] = []
    mesh = None
    for pc in pieces:
        verts = getattr(pc, "vertices", None)
        if isinstance(pc.geometry, fcl.BVHModel):
            # an imported mesh: its distance field, if the target has one, in the object frame
            pack_of = getattr(target, "mesh_pack", None)
            pack = pack_of() if callable(pack_of) else None
            ident = np.allclose(pc.R_object_piece, np.eye(3)) and not np.any(pc.t_object_piece)
            if pack is None or mesh is not None or not ident:
                return None
            mesh = pack
            rows.append((MESH, np.zeros(3), np.eye(3), np.zeros(3), None))
            continue
        if verts is not None:
            rows.append((gjk.POINTS, np.zeros(3), pc.R_object_piece, pc.t_object_piece, verts))
            continue
        d = gjk.describe_fcl_geometry(pc.geometry)
        if d is None:  # BVHModel (imported mesh), or a Convex without its vertices
            return None
        rows.append((d[0], d[1], pc.R_object_piece, pc.t_object_piece, None))
    arr = _arrays(rows)
    return arr if mesh is None else dataclasses.replace(arr, mesh=mesh)


#: id(target) -> (target, arrays): objects are long-lived (``load_object`` caches them); the
#: stored reference keeps an id from being reused while its entry exists.
_CACHE: dict[int, tuple[Any, ObstacleArrays | None]] = {}
_CACHE_MAX = 64


def object_arrays(target: Any) -> ObstacleArrays | None:
    """The object's collision pieces as arrays (cached per object), or None when a piece has
    no array description (imported meshes): the caller then uses FCL."""
    hit = _CACHE.get(id(target))
    if hit is not None and hit[0] is target:
        return hit[1]
    arr = _pieces_arrays(target)
    if len(_CACHE) >= _CACHE_MAX:
        _CACHE.clear()
    _CACHE[id(target)] = (target, arr)
    return arr


def link_arrays(shapes: Sequence[object], T_fcl: np.ndarray) -> ObstacleArrays:
    """Hand link shapes (capsules, the palm box) posed at ``T_fcl`` (L, 4, 4) (FCL frames)."""
    rows: list[tuple[int, np.ndarray, np.ndarray, np.ndarray, np.ndarray | None]] = []
    for s, T in zip(shapes, T_fcl, strict=True):
        if isinstance(s, CapsuleShape):
            rows.append(
                (gjk.CAPSULE, np.array([s.radius, 0.5 * s.length, 0.0]), T[:3, :3], T[:3, 3], None)
            )
        elif isinstance(s, BoxShape):
            rows.append((gjk.BOX, 0.5 * (s.hi_link - s.lo_link), T[:3, :3], T[:3, 3], None))
        else:
            raise TypeError(f"no array description of {type(s).__name__}")
    return _arrays(rows)


def link_mesh_distance(shape: object, T_object_fcl: np.ndarray, pk: MeshPack, tol: float) -> float:
    """A hand link's (``CapsuleShape`` or ``BoxShape`` posed at its FCL frame) distance to an
    imported mesh (``mesh_distance``): exact when it may be <= ``tol`` (the contact test),
    else a lower bound above it."""
    la = link_arrays([shape], T_object_fcl[None])
    return float(mesh_distance(la.typ[0], la.prm[0], la.R[0], la.t[0], pk, tol))


# ------------------------------------------------------------------- compiled kernels


@njit(cache=True)
def _link_poses(placements: np.ndarray, q: np.ndarray, T_op: np.ndarray) -> np.ndarray:
    """(3, 4, 4) T_object_link of a finger (``FingerChain.link_poses`` then T_object_palm @)."""
    loc = placements.copy()
    for k in range(3):
        c, s = np.cos(q[k]), np.sin(q[k])
        for i in range(3):
            y, z = placements[k, i, 1], placements[k, i, 2]
            loc[k, i, 1] = y * c + z * s
            loc[k, i, 2] = z * c - y * s
    out = np.empty((3, 4, 4))
    out[0] = T_op @ loc[0]
    out[1] = out[0] @ loc[1]
    out[2] = out[1] @ loc[2]
    return out


def thumb_link_poses(placements: np.ndarray, q: np.ndarray, T_op: np.ndarray) -> np.ndarray:
    """(3, 4, 4) T_object_link of a finger at q (3,) (``FingerChain.link_poses``, then
    T_object_palm @), compiled."""
    return _link_poses(placements, q, T_op)


@njit(cache=True)
def _axis_rates(
    T_links: np.ndarray, ends_link: np.ndarray, radii: np.ndarray, v: np.ndarray
) -> np.ndarray:
    """``app.sim.closing._axis_rates``."""
    rates = np.zeros(3)
    for k in range(3):
        for i in range(k + 1):
            rho = 0.0
            for e in range(2):
                rel = np.empty(3)
                for j in range(3):
                    p = T_links[k, j, 3]
                    for m in range(3):
                        p += T_links[k, j, m] * ends_link[k, e, m]
                    rel[j] = p - T_links[i, j, 3]
                along = (
                    rel[0] * T_links[i, 0, 0]
                    + rel[1] * T_links[i, 1, 0]
                    + rel[2] * T_links[i, 2, 0]
                )
                perp2 = rel[0] * rel[0] + rel[1] * rel[1] + rel[2] * rel[2] - along * along
                r = np.sqrt(max(perp2, 0.0))
                if r > rho:
                    rho = r
            rates[k] += (rho + radii[k]) * abs(v[i])
    return rates


@njit(cache=True)
def _evaluate(
    qq: np.ndarray,
    placements: np.ndarray,
    T_fcl: np.ndarray,
    cap_prm: np.ndarray,
    T_op: np.ndarray,
    first: int,
    lb: np.ndarray,
    tol: float,
    otyp: np.ndarray,
    oprm: np.ndarray,
    oR: np.ndarray,
    ot: np.ndarray,
    vstart: np.ndarray,
    verts: np.ndarray,
    nbr_start: np.ndarray,
    nbr: np.ndarray,
    is_obj: np.ndarray,
    obj_hit: np.ndarray,
    self_hit: np.ndarray,
    counters: np.ndarray,
    mesh: MeshPack,
) -> float:
    """``evaluate`` of ``app.sim.closing.advance_stage``: updates ``lb`` rows, sets the hit
    masks, returns the smallest gap of a moving link; ``counters[0]`` += queries."""
    T_links = _link_poses(placements, qq, T_op)
    n_obs = len(otyp)
    inf = np.inf
    g_min = inf
    obj_hit[:] = False
    self_hit[:] = False
    exact = np.zeros(n_obs, np.bool_)
    for k in range(first, 3):
        row = lb[k]
        exact[:] = False
        posed = False
        Tk = np.empty((4, 4))
        while True:
            m = inf
            p = -1
            for j in range(n_obs):
                if row[j] < m:
                    m = row[j]
                    p = j
            if m == inf:
                break
            if exact[p]:
                p = -1
                for j in range(n_obs):
                    if row[j] <= tol and not exact[j]:
                        p = j
                        break
                if p < 0:
                    break
            if not posed:
                Tk = T_links[k] @ T_fcl[k]
                posed = True
            if otyp[p] == MESH:
                row[p] = mesh_distance(
                    gjk.CAPSULE, cap_prm[k], Tk[:3, :3], Tk[:3, 3], mesh, tol + MESH_EXACT_MM
                )
            else:
                row[p] = gjk.shape_distance_nbr(
                    gjk.CAPSULE, cap_prm[k], Tk[:3, :3], Tk[:3, 3], otyp[p], oprm[p], oR[p],
                    ot[p], verts, nbr_start, nbr, 0, 0, vstart[p], vstart[p + 1],
                )  # fmt: skip
            counters[0] += 1
            exact[p] = True
        g = inf
        for j in range(n_obs):
            if row[j] < g:
                g = row[j]
        if g < g_min:
            g_min = g
        if g <= tol:
            hit_obj = False
            for j in range(n_obs):
                if exact[j] and row[j] <= tol and is_obj[j]:
                    hit_obj = True
            if hit_obj:
                obj_hit[k] = True
            else:
                self_hit[k] = True
    return g_min


@njit(cache=True)
def advance_stage_kernel(
    placements: np.ndarray,
    T_fcl: np.ndarray,
    cap_prm: np.ndarray,
    ends_link: np.ndarray,
    radii: np.ndarray,
    mid_link: np.ndarray,
    reach: np.ndarray,
    q_upper: np.ndarray,
    T_op: np.ndarray,
    q_in: np.ndarray,
    v: np.ndarray,
    otyp: np.ndarray,
    oprm: np.ndarray,
    oR: np.ndarray,
    ot: np.ndarray,
    vstart: np.ndarray,
    verts: np.ndarray,
    nbr_start: np.ndarray,
    nbr: np.ndarray,
    is_obj: np.ndarray,
    mask: np.ndarray,
    spheres: np.ndarray,
    tol: float,
    max_steps: int,
    refine_iters: int,
    refine_band: float,
    counters: np.ndarray,
    mesh: MeshPack,
) -> tuple[np.ndarray, int, np.ndarray, np.ndarray]:
    """One closing stage (``app.sim.closing.advance_stage``): (q, event code, links (3,) bool,
    joints at limit (3,) bool). ``counters`` += (queries, steps, capped)."""
    q = q_in.copy()
    first = 0
    n_active = 0
    for i in range(3):
        if v[i] > 0:
            n_active += 1
    for i in range(3):
        if v[i] > 0:
            first = i
            break
    n_obs = len(otyp)
    inf = np.inf
    lb = np.full((3, n_obs), -inf)
    has_sph = False
    for j in range(n_obs):
        if np.isfinite(spheres[j, 3]):
            has_sph = True
    if has_sph:
        T0 = _link_poses(placements, q, T_op)
        for k in range(3):
            c = np.empty(3)
            for i in range(3):
                c[i] = T0[k, i, 3]
                for j in range(3):
                    c[i] += T0[k, i, j] * mid_link[k, j]
            for j in range(n_obs):
                if np.isfinite(spheres[j, 3]):
                    dd = np.sqrt(
                        (c[0] - spheres[j, 0]) ** 2
                        + (c[1] - spheres[j, 1]) ** 2
                        + (c[2] - spheres[j, 2]) ** 2
                    )
                    lb[k, j] = dd - reach[k] - spheres[j, 3]
    for k in range(3):
        for j in range(n_obs):
            if not mask[k, j]:
                lb[k, j] = inf
    obj_hit = np.zeros(3, np.bool_)
    self_hit = np.zeros(3, np.bool_)
    o2 = np.zeros(3, np.bool_)
    s2 = np.zeros(3, np.bool_)
    no_joint = np.zeros(3, np.bool_)
    single = n_active == 1
    rates_fixed = np.zeros(3)
    have_fixed = False
    have_safe = False
    safe_q = q.copy()
    safe_g = 0.0
    safe_lb = lb.copy()
    safe_rates = np.zeros(3)
    safe_step = 0.0
    for _ in range(max_steps):
        counters[1] += 1
        g = _evaluate(
            q, placements, T_fcl, cap_prm, T_op, first, lb, tol,
            otyp, oprm, oR, ot, vstart, verts, nbr_start, nbr, is_obj, obj_hit, self_hit,
            counters, mesh,
        )  # fmt: skip
        if (obj_hit.any() or self_hit.any()) and have_safe:
            lo_t, lo_f, hi_t, hi_f = 0.0, safe_g - tol, safe_step, g - tol
            lb_hi = lb.copy()
            side = 0
            for _r in range(refine_iters):
                if hi_f >= -refine_band * tol:
                    break
                t = hi_t - hi_f * (hi_t - lo_t) / (hi_f - lo_f)
                t = min(max(t, lo_t + 1e-3 * (hi_t - lo_t)), hi_t - 1e-3 * (hi_t - lo_t))
                for k in range(first, 3):
                    d = safe_rates[k] * t
                    for j in range(n_obs):
                        lb[k, j] = safe_lb[k, j] - d
                gm = _evaluate(
                    safe_q + v * t, placements, T_fcl, cap_prm, T_op, first, lb, tol,
                    otyp, oprm, oR, ot, vstart, verts, nbr_start, nbr, is_obj, o2, s2,
                    counters, mesh,
                )  # fmt: skip
                if o2.any() or s2.any():
                    hi_t, hi_f = t, gm - tol
                    obj_hit[:] = o2
                    self_hit[:] = s2
                    lb_hi = lb.copy()
                    if side == -1:
                        lo_f *= 0.5
                    side = -1
                else:
                    lo_t, lo_f = t, gm - tol
                    if side == 1:
                        hi_f *= 0.5
                    side = 1
            cap = np.where(v > 0, q_upper, safe_q)
            q = np.minimum(safe_q + v * hi_t, cap)
            for k in range(first, 3):
                lb[k] = lb_hi[k]
        if obj_hit.any():
            return q, 0, obj_hit, no_joint
        if self_hit.any():
            return q, 1, self_hit, no_joint
        room = np.full(3, inf)
        at_limit = np.zeros(3, np.bool_)
        for i in range(3):
            if v[i] > 0:
                room[i] = (q_upper[i] - q[i]) / v[i]
                at_limit[i] = room[i] <= 1e-12
        if at_limit.any():
            return q, 2, no_joint, at_limit
        if not have_fixed:
            rates = _axis_rates(_link_poses(placements, q, T_op), ends_link, radii, v)
            if single:
                rates_fixed = rates
                have_fixed = True
        else:
            rates = rates_fixed
        step = inf
        for k in range(first, 3):
            gk = inf
            for j in range(n_obs):
                if lb[k, j] < gk:
                    gk = lb[k, j]
            sk = (gk - 0.5 * tol) / rates[k]
            if sk < step:
                step = sk
        for i in range(3):
            if room[i] < step:
                step = room[i]
        have_safe = True
        safe_q = q
        safe_g = g
        safe_lb = lb.copy()
        safe_rates = rates
        safe_step = step
        cap = np.where(v > 0, q_upper, q)
        q = np.minimum(q + v * step, cap)
        for k in range(first, 3):
            d = rates[k] * step
            for j in range(n_obs):
                lb[k, j] = safe_lb[k, j] - d
    counters[2] += 1
    return q, 3, no_joint, no_joint


@njit(cache=True)
def approach_kernel(
    btyp: np.ndarray,
    bprm: np.ndarray,
    T_palm_bodies: np.ndarray,
    R_op: np.ndarray,
    ray: np.ndarray,
    target: np.ndarray,
    offset: np.ndarray,
    otyp: np.ndarray,
    oprm: np.ndarray,
    oR: np.ndarray,
    ot: np.ndarray,
    vstart: np.ndarray,
    verts: np.ndarray,
    nbr_start: np.ndarray,
    nbr: np.ndarray,
    start_mm: float,
    tol: float,
    max_steps: int,
    exact_below: float,
    counters: np.ndarray,
    mesh: MeshPack,
    floor: float,
) -> tuple[float, int]:
    """``app.sim.closing.approach``: (s, status) with status 0 contact, 1 fell below
    ``floor`` without contact (passed the target), 2 capped by ``max_steps``."""
    s = start_mm
    B, P = len(btyp), len(otyp)
    lb = np.full((B, P), -np.inf)
    T = np.eye(4)
    T[:3, :3] = R_op
    for _ in range(max_steps):
        counters[1] += 1
        for j in range(3):
            T[j, 3] = target[j] + s * ray[j] - offset[j]
        for b in range(B):
            posed = False
            Tb = np.empty((4, 4))
            for p in range(P):
                if lb[b, p] < exact_below:
                    if not posed:
                        Tb = T @ T_palm_bodies[b]
                        posed = True
                    if otyp[p] == MESH:
                        lb[b, p] = mesh_distance(btyp[b], bprm[b], Tb[:3, :3], Tb[:3, 3], mesh,
                                                 tol + MESH_EXACT_MM)  # fmt: skip
                    else:
                        lb[b, p] = gjk.shape_distance_nbr(
                            btyp[b], bprm[b], Tb[:3, :3], Tb[:3, 3], otyp[p], oprm[p], oR[p],
                            ot[p], verts, nbr_start, nbr, 0, 0, vstart[p], vstart[p + 1],
                        )  # fmt: skip
                    counters[0] += 1
        gap = np.inf
        for b in range(B):
            for p in range(P):
                if lb[b, p] < gap:
                    gap = lb[b, p]
        if gap <= tol:
            return s, 0
        step = gap - 0.5 * tol
        s -= step
        for b in range(B):
            for p in range(P):
                lb[b, p] -= step
        if s < floor:
            return s, 1
    counters[2] += 1
    return s, 2


# ------------------------------------------------------------------- Python entry points


ChainArrays = tuple[
    np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray
]


def chain_arrays(chain: FingerChain) -> ChainArrays:
    """The finger's kinematic and capsule arrays in ``advance_stage_kernel``'s order."""
    cached = _CHAIN_CACHE.get(id(chain))
    if cached is not None and cached[0] is chain:
        return cached[1]
    cap_prm = np.zeros((3, 3))
    cap_prm[:, 0] = chain.radii
    cap_prm[:, 1] = [0.5 * s.length for s in chain.shapes]
    arrs: ChainArrays = (
        np.ascontiguousarray(chain.placements, float),
        np.ascontiguousarray(chain.T_link_fcl, float),
        cap_prm,
        np.ascontiguousarray(chain.ends_link, float),
        np.ascontiguousarray(chain.radii, float),
        np.ascontiguousarray(chain.mid_link, float),
        np.ascontiguousarray(chain.reach, float),
        np.ascontiguousarray(chain.q_upper, float),
    )
    if len(_CHAIN_CACHE) >= 5 * _CACHE_MAX:
        _CHAIN_CACHE.clear()
    _CHAIN_CACHE[id(chain)] = (chain, arrs)
    return arrs


_CHAIN_CACHE: dict[int, tuple[FingerChain, ChainArrays]] = {}


#: The indices set in a (3,) mask, by the mask's bits (1 << i for index i).
_INDEX_SETS = tuple(tuple(i for i in range(3) if m >> i & 1) for m in range(8))


def _mask_code(mask: np.ndarray) -> int:
    return int(mask[0]) | int(mask[1]) << 1 | int(mask[2]) << 2


def advance_stage_compiled(
    chain: FingerChain,
    T_object_palm: np.ndarray,
    q: np.ndarray,
    v: np.ndarray,
    arrays: ObstacleArrays,
    kernel_args: tuple[np.ndarray, np.ndarray, np.ndarray],
    tol: float,
    max_steps: int,
    counters: np.ndarray,
) -> tuple[np.ndarray, str, tuple[int, ...], tuple[int, ...]]:
    """``advance_stage`` on the compiled engine: (q, event kind, links, joints).
    ``kernel_args``: (is_object (P,), mask (3, P), spheres (P, 4)) of the obstacles in the
    kernel's layout (``Obstacles.kernel_args``, made once per obstacle set)."""
    is_obj, m, sph = kernel_args
    qn, code, links, joints = advance_stage_kernel(
        *chain_arrays(chain),
        np.ascontiguousarray(T_object_palm, float),
        np.asarray(q, float),
        np.asarray(v, float),
        arrays.typ, arrays.prm, arrays.R, arrays.t, arrays.vstart, arrays.verts,
        arrays.nbr_start, arrays.nbr,
        is_obj, m, sph, float(tol), int(max_steps), REFINE_ITERS, REFINE_BAND, counters,
        _pack(arrays),
    )  # fmt: skip
    return qn, EVENT_KINDS[code], _INDEX_SETS[_mask_code(links)], _INDEX_SETS[_mask_code(joints)]


def approach_compiled(
    body_arrays: ObstacleArrays,
    T_palm_bodies: np.ndarray,
    R_object_palm: np.ndarray,
    ray_object: np.ndarray,
    target_object: np.ndarray,
    approach_point_palm: np.ndarray,
    pieces: ObstacleArrays,
    start_mm: float,
    tol: float,
    max_steps: int,
    counters: np.ndarray,
    floor: float | None = None,
) -> tuple[float, int]:
    """``approach`` on the compiled engine: (s, status) as ``approach_kernel``; ``floor``
    defaults to ``-start_mm``."""
    offset = np.asarray(R_object_palm, float) @ np.asarray(approach_point_palm, float)
    return approach_kernel(
        body_arrays.typ, body_arrays.prm, np.ascontiguousarray(T_palm_bodies, float),
        np.ascontiguousarray(R_object_palm, float), np.asarray(ray_object, float),
        np.asarray(target_object, float), offset,
        pieces.typ, pieces.prm, pieces.R, pieces.t, pieces.vstart, pieces.verts,
        pieces.nbr_start, pieces.nbr,
        float(start_mm), float(tol), int(max_steps), EXACT_BELOW_MM, counters, _pack(pieces),
        float(-start_mm if floor is None else floor),
    )  # fmt: skip
