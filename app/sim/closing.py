"""Collision-driven approach and finger closing (METHOD §4) by conservative advancement.

Objects are fixed (the world is the object frame). A closing *stage* moves a set of active
joints of one finger at fixed relative rates. Each step takes the largest advance that
provably cannot bring any moving link closer to an obstacle than half the stop tolerance:
a point of link k moves at most ``Σ_i |v_i| ρ_ki`` per unit of the stage parameter, where
ρ_ki is the largest distance from joint axis i to the link's capsule. Pair distances come
from FCL; a pair whose lower bound (last exact distance minus the motion since) stays above
``EXACT_BELOW_MM`` is not queried again. The stage ends when a moving link is within the
stop tolerance of the object (contact), of another finger or the palm (self-collision,
which stops the joint but is no object contact), or an active joint reaches its limit.
The last step is refined by false position (Illinois) to the first crossing of gap = stop
tolerance, ending once the gap lies within ``REFINE_BAND`` · tol below tol, so the stop is a
property of the geometry and the tolerance, not of any step size.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import fcl
import numpy as np

from app.model.hand.chains import FingerChain
from app.sim.closing_settings import (
    EXACT_BELOW_MM,
    REFINE_BAND,
    REFINE_ITERS,
    ClosingSettings,
)

if TYPE_CHECKING:
    from app.sim.closing_compiled import ObstacleArrays

__all__ = ["EXACT_BELOW_MM", "REFINE_BAND", "REFINE_ITERS"]

_LOWER = np.tri(3, dtype=bool)
_REQ = fcl.DistanceRequest(enable_nearest_points=True, enable_signed_distance=True)


def fcl_transform(T: np.ndarray) -> fcl.Transform:
    """FCL transform from a (4, 4) pose."""
    return fcl.Transform(T[:3, :3], T[:3, 3])


def pair_distance(a: fcl.CollisionObject, b: fcl.CollisionObject) -> float:
    """Signed distance between two posed FCL objects (negative when penetrating), mm."""
    return float(fcl.distance(a, b, _REQ, fcl.DistanceResult()))


def pair_nearest(
    a: fcl.CollisionObject, b: fcl.CollisionObject
) -> tuple[float, np.ndarray, np.ndarray]:
    """(distance, nearest point on a, nearest point on b), world frame."""
    r = fcl.DistanceResult()
    d = fcl.distance(a, b, _REQ, r)
    return float(d), np.array(r.nearest_points[0]), np.array(r.nearest_points[1])


@dataclass
class Obstacles:
    """Static obstacles of one closing problem, posed in the object frame."""

    objs: list[fcl.CollisionObject]
    """FCL objects: the object's pieces first, then any self-collision bodies."""
    n_object: int
    """The first ``n_object`` entries are the grasped object; the rest are hand links."""
    mask: np.ndarray | None = None
    """(3, P) bool: which (moving link, obstacle) pairs to check; None = all."""
    spheres: np.ndarray | None = None
    """(P, 4) optional bounding sphere (centre xyz, radius) of each obstacle, object frame,
    used to skip far pairs; rows with radius = inf are always queried."""
    arrays: ObstacleArrays | None = None
    """The same obstacles as flat arrays for the compiled engine (``settings.engine ==
    'compiled'``); None: FCL closes (also what an imported mesh gets)."""

    _kernel_args: tuple[np.ndarray, np.ndarray, np.ndarray] | None = field(
        default=None, repr=False, compare=False
    )

    @property
    def is_object(self) -> np.ndarray:
        """(P,) True for object pieces."""
        return np.arange(len(self.objs)) < self.n_object

    def kernel_args(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(is_object (P,), mask (3, P), spheres (P, 4)) as the compiled stage reads them,
        made once per obstacle set (a base's is closed against by every design)."""
        if self._kernel_args is None:
            P = len(self.objs) if self.arrays is None else len(self.arrays)
            m = np.ones((3, P), np.bool_) if self.mask is None else self.mask
            sph = np.full((P, 4), np.inf) if self.spheres is None else self.spheres
            self._kernel_args = (
                np.arange(P) < self.n_object,
                np.ascontiguousarray(m, np.bool_),
                np.ascontiguousarray(sph, float),
            )
        return self._kernel_args


@dataclass
class StageEvent:
    """Why a closing stage stopped."""

    kind: str
    """'contact' (object), 'self' (hand self-collision), 'limit', or 'max_steps'."""
    links: tuple[int, ...] = ()
    """Finger-local link indices (0..2) within the stop tolerance (contact/self)."""
    joints: tuple[int, ...] = ()
    """Finger-local joint indices at their upper limit ('limit')."""


@dataclass
class ClosingStats:
    """Counters of one closing, for the benchmarks."""

    queries: int = 0
    """FCL distance queries."""
    steps: int = 0
    """Conservative-advancement steps."""
    capped: int = 0
    """Stages stopped by ``max_steps``."""
    events: list[str] = field(default_factory=list)
    """Stage events in order, e.g. 'thumb:[0]:contact'."""
    stages: list[tuple[str, np.ndarray, np.ndarray, str]] | None = None
    """When a list: (finger, q_start (3,), q_end (3,), event kind) of every stage, for replay."""
    approach_s: tuple[float, float] | None = None
    """(start, first-contact) ray parameter of the approach, mm, when recorded."""


def _axis_rates(T_links: np.ndarray, chain: FingerChain, v: np.ndarray) -> np.ndarray:
    """(3,) bound on the speed (mm per unit stage parameter) of any point of each link.

    A point at distance ρ from joint axis i moves at most ρ·|v_i| per unit parameter; the
    distance from a line to a segment is largest at an end, plus the capsule radius.
    """
    ends = np.einsum("kij,kej->kei", T_links[:, :3, :3], chain.ends_link) + T_links[:, None, :3, 3]
    o = T_links[:, :3, 3]  # (3, 3) axis origins
    a = T_links[:, :3, 0]  # (3, 3) axis directions
    rel = ends[:, None, :, :] - o[None, :, None, :]  # (link k, axis i, end e, 3)
    along = np.einsum("kiej,ij->kie", rel, a)
    perp2 = (rel * rel).sum(-1) - along * along
    rho = np.sqrt(np.maximum(perp2, 0.0)).max(-1) + chain.radii[:, None]  # (k, i)
    rho = np.where(_LOWER, rho, 0.0)  # axis i moves link k only if i <= k
    return rho @ np.abs(v)


def advance_stage(
    chain: FingerChain,
    bodies: list[fcl.CollisionObject],
    T_object_palm: np.ndarray,
    q: np.ndarray,
    v: np.ndarray,
    obstacles: Obstacles,
    settings: ClosingSettings,
    stats: ClosingStats,
) -> tuple[np.ndarray, StageEvent]:
    """Close the finger's joints along rates ``v`` (3,) from ``q`` (3,) until an event.

    ``bodies`` are the finger's three FCL capsules (moved here). Returns the new q (3,).
    The bookkeeping runs on small Python lists: a stage touches a handful of pairs per
    step, and numpy's per-call overhead on such arrays cost more than the FCL queries.
    """
    q = q.astype(float).copy()
    tol = settings.stop_tol_mm
    first = int(np.flatnonzero(v > 0)[0])
    moving = list(range(first, 3))
    objs = obstacles.objs
    n_obs = len(objs)
    mask = obstacles.mask if obstacles.mask is not None else np.ones((3, n_obs), bool)
    is_obj = obstacles.is_object.tolist()
    lb_arr = np.full((3, n_obs), -np.inf)  # -inf: query exactly
    if obstacles.spheres is not None:
        T0 = T_object_palm @ chain.link_poses(q)
        c_link = np.einsum("kij,kj->ki", T0[:, :3, :3], chain.mid_link) + T0[:, :3, 3]
        sph = obstacles.spheres
        finite = np.isfinite(sph[:, 3])
        gap = np.linalg.norm(c_link[:, None, :] - sph[None, finite, :3], axis=-1)
        lb_arr[:, finite] = gap - chain.reach[:, None] - sph[None, finite, 3]
    lb_arr[~mask] = np.inf
    # per moving link: lower bounds of its distance to each obstacle (exact once queried)
    lb: dict[int, list[float]] = {k: lb_arr[k].tolist() for k in moving}
    T_fcl = chain.T_link_fcl
    inf = float("inf")

    def evaluate(qq: np.ndarray) -> tuple[list[int], list[int], float]:
        """Exact gaps at ``qq`` by lazy evaluation: (links within tol of the object, links
        within tol of the hand, smallest gap of a moving link).

        For each moving link, the pair with the smallest lower bound is queried until the
        smallest bound is an exact distance: that is the link's gap, and every other pair is
        at least its bound. Pairs with a bound <= tol are all queried (they may touch)."""
        T_links = T_object_palm @ chain.link_poses(qq)
        obj_hit: list[int] = []
        self_hit: list[int] = []
        g_min = inf
        for k in moving:
            row = lb[k]
            exact = [False] * n_obs
            posed = False
            while True:
                m = min(row)
                if m == inf:
                    break  # no pair to check
                p = row.index(m)
                if exact[p]:
                    p = next((j for j in range(n_obs) if row[j] <= tol and not exact[j]), -1)
                    if p < 0:
                        break
                if not posed:
                    bodies[k].setTransform(fcl_transform(T_links[k] @ T_fcl[k]))
                    posed = True
                row[p] = pair_distance(bodies[k], objs[p])
                stats.queries += 1
                exact[p] = True
            g = min(row)
            g_min = min(g_min, g)
            if g <= tol:
                hits = [j for j in range(n_obs) if exact[j] and row[j] <= tol]
                if any(is_obj[j] for j in hits):
                    obj_hit.append(k)
                else:
                    self_hit.append(k)
        return obj_hit, self_hit, g_min

    def snapshot() -> dict[int, list[float]]:
        return {k: list(r) for k, r in lb.items()}

    def set_bounds(base: dict[int, list[float]], rates: np.ndarray, t: float) -> None:
        for k in moving:
            d = float(rates[k]) * t
            lb[k] = [x - d for x in base[k]]

    safe: tuple[np.ndarray, float, dict[int, list[float]], np.ndarray, float] | None = None
    single = int((v > 0).sum()) == 1
    rates_fixed: np.ndarray | None = None
    for _ in range(settings.max_steps):
        stats.steps += 1
        touching_obj, touching_self, g = evaluate(q)
        if (touching_obj or touching_self) and safe is not None:
            # refine the stop to the first crossing of gap = tol between the last safe
            # configuration (gap g0 > tol) and q (gap <= tol): false position (Illinois),
            # ending when the gap is within REFINE_BAND of tol from below
            q0, g0, lb0, rates0, step = safe
            lo_t, lo_f, hi_t, hi_f = 0.0, g0 - tol, step, g - tol
            lb_hi = snapshot()
            side = 0
            for _ in range(REFINE_ITERS):
                if hi_f >= -REFINE_BAND * tol:
                    break
                t = hi_t - hi_f * (hi_t - lo_t) / (hi_f - lo_f)
                t = min(max(t, lo_t + 1e-3 * (hi_t - lo_t)), hi_t - 1e-3 * (hi_t - lo_t))
                set_bounds(lb0, rates0, t)
                o, s_, gm = evaluate(q0 + v * t)
                if o or s_:
                    hi_t, hi_f = t, gm - tol
                    touching_obj, touching_self = o, s_
                    lb_hi = snapshot()
                    if side == -1:
                        lo_f *= 0.5
                    side = -1
                else:
                    lo_t, lo_f = t, gm - tol
                    if side == 1:
                        hi_f *= 0.5
                    side = 1
            q = np.minimum(q0 + v * hi_t, np.where(v > 0, chain.q_upper, q0))
            lb.update(lb_hi)
        if touching_obj:
            return q, StageEvent("contact", tuple(sorted(set(touching_obj))))
        if touching_self:
            return q, StageEvent("self", tuple(sorted(set(touching_self))))
        room = np.where(v > 0, (chain.q_upper - q) / np.where(v > 0, v, 1.0), np.inf)
        at_limit = tuple(int(i) for i in np.flatnonzero((v > 0) & (room <= 1e-12)))
        if at_limit:
            return q, StageEvent("limit", joints=at_limit)
        if rates_fixed is None:
            rates = _axis_rates(T_object_palm @ chain.link_poses(q), chain, v)
            if single:  # one active joint: the links it moves are rigid relative to its axis
                rates_fixed = rates
        else:
            rates = rates_fixed
        gaps = np.array([min(lb[k]) for k in moving])
        with np.errstate(divide="ignore"):
            steps = (gaps - 0.5 * tol) / rates[first:]
        step = min(float(steps.min()), float(room.min()))
        safe = (q, g, snapshot(), rates, step)
        q = np.minimum(q + v * step, np.where(v > 0, chain.q_upper, q))
        set_bounds(safe[2], rates, step)
    stats.capped += 1
    return q, StageEvent("max_steps")


def _advance(
    chain: FingerChain,
    bodies: list[fcl.CollisionObject],
    T_object_palm: np.ndarray,
    q: np.ndarray,
    v: np.ndarray,
    obstacles: Obstacles,
    settings: ClosingSettings,
    stats: ClosingStats,
) -> tuple[np.ndarray, StageEvent]:
    """``advance_stage`` on the engine of ``settings`` (FCL when there are no arrays)."""
    if settings.engine != "compiled" or obstacles.arrays is None:
        return advance_stage(chain, bodies, T_object_palm, q, v, obstacles, settings, stats)
    from app.sim.closing_compiled import advance_stage_compiled

    counters = np.zeros(3, np.int64)
    q, kind, links, joints = advance_stage_compiled(
        chain,
        T_object_palm,
        q,
        v,
        obstacles.arrays,
        obstacles.kernel_args(),
        settings.stop_tol_mm,
        settings.max_steps,
        counters,
    )
    stats.queries += int(counters[0])
    stats.steps += int(counters[1])
    stats.capped += int(counters[2])
    return q, StageEvent(kind, links, joints)


#: Joint rate vectors of the sequential stages (never written).
_UNIT = np.eye(3)

_EVENT_NAMES: dict[tuple[object, ...], str] = {}


def _event_name(finger: str, v: np.ndarray, kind: str) -> str:
    """'thumb:[1]:contact': the finger, the joints a stage moved, why it stopped."""
    key = (finger, v[0] > 0, v[1] > 0, v[2] > 0, kind)
    name = _EVENT_NAMES.get(key)
    if name is None:
        name = f"{finger}:{[i for i in range(3) if key[1 + i]]}:{kind}"
        _EVENT_NAMES[key] = name
    return name


def close_finger(
    chain: FingerChain,
    bodies: list[fcl.CollisionObject],
    T_object_palm: np.ndarray,
    obstacles: Obstacles,
    settings: ClosingSettings,
    stats: ClosingStats,
    first_stage: dict[str, tuple[np.ndarray, StageEvent]] | None = None,
    first_stage_only: bool = False,
) -> np.ndarray:
    """Close one finger from its open posture by ``settings.mode``; returns its q (3,).

    ``first_stage``: a memo of the sequential mode's first stage (the proximal joint alone),
    keyed by finger, for callers whose first stage is the same across calls (the thumb's CMC
    stage across MCP design angles: ``app.sim.simulate``). Other modes ignore it.
    ``first_stage_only``: in sequential mode, run (and memoise) the first stage and stop.
    """
    q = chain.q_lower.copy()
    mode = settings.mode

    def run(v: np.ndarray) -> StageEvent:
        nonlocal q
        q0 = q
        memo = first_stage is not None and mode == "sequential" and v[0] > 0
        if memo and chain.finger in first_stage:  # type: ignore[operator]
            q, ev = first_stage[chain.finger]  # type: ignore[index]
            q = q.copy()
        else:
            q, ev = _advance(chain, bodies, T_object_palm, q, v, obstacles, settings, stats)
            if memo:
                first_stage[chain.finger] = (q.copy(), ev)  # type: ignore[index]
        stats.events.append(_event_name(chain.finger, v, ev.kind))
        if stats.stages is not None:
            stats.stages.append((chain.finger, q0.copy(), q.copy(), ev.kind))
        return ev

    def sequential(k: int) -> None:
        while k < 3:
            ev = run(_UNIT[k])
            k = max(ev.links) + 1 if ev.kind in ("contact", "self") else k + 1

    def together(active: list[int], rates: np.ndarray) -> int:
        """Close ``active`` joints together; returns the first joint left for afterwards."""
        nxt = max(active) + 1
        while active:
            v = np.zeros(3)
            v[active] = rates[active]
            if not (v > 0).any():
                break
            ev = run(v)
            if ev.kind in ("contact", "self"):
                j = max(ev.links)
                active = [i for i in active if i > j]
                nxt = max(nxt, j + 1)
            elif ev.kind == "limit":
                active = [i for i in active if i not in ev.joints]
            else:
                break
        return nxt

    if mode == "coupled_tendon":
        together([0, 1, 2], np.asarray(settings.tendon_ratios, float))
    elif mode == "independent_thumb" and chain.finger == "thumb":
        rates = np.array([settings.thumb_rates[0], settings.thumb_rates[1], 0.0])
        sequential(together([0, 1], rates))
    elif first_stage_only:
        run(_UNIT[0])
    else:
        sequential(0)
    return q


def approach(
    bodies: list[fcl.CollisionObject],
    T_palm_bodies: np.ndarray,
    R_object_palm: np.ndarray,
    ray_object: np.ndarray,
    target_object: np.ndarray,
    approach_point_palm: np.ndarray,
    object_pieces: list[fcl.CollisionObject],
    start_mm: float,
    settings: ClosingSettings,
    stats: ClosingStats,
    arrays: tuple[ObstacleArrays, ObstacleArrays] | None = None,
    floor_mm: float | None = None,
) -> float | None:
    """Slide the hand along the ray toward the object until first contact.

    The hand is placed with P on the line ``target + s · ray`` and orientation R; s falls
    from ``start_mm``. ``bodies`` (with FCL-frame poses ``T_palm_bodies`` (B, 4, 4)) are the
    links that take part. Returns s at first contact (gap ≤ stop tolerance), or None if the
    hand passes the target by ``start_mm`` without touching. ``arrays``: (bodies, pieces) as
    flat arrays for the compiled engine (used when ``settings.engine == 'compiled'``).
    ``floor_mm``: give up (None) once s falls below it (default ``-start_mm``); the steps
    before are the same, so a contact above the floor is found exactly as without it.
    """
    tol = settings.stop_tol_mm
    floor = -start_mm if floor_mm is None else max(-start_mm, floor_mm)
    if settings.engine == "compiled" and arrays is not None:
        from app.sim.closing_compiled import approach_compiled

        counters = np.zeros(3, np.int64)
        s_c, status = approach_compiled(
            arrays[0],
            T_palm_bodies,
            R_object_palm,
            ray_object,
            target_object,
            approach_point_palm,
            arrays[1],
            start_mm,
            tol,
            settings.max_steps,
            counters,
            floor,
        )
        stats.queries += int(counters[0])
        stats.steps += int(counters[1])
        stats.capped += int(counters[2])
        if status == 1:
            return None
        if status == 0 and stats.stages is not None:
            stats.approach_s = (start_mm, s_c)
        return s_c
    s = start_mm
    B, P = len(bodies), len(object_pieces)
    lb = np.full((B, P), -np.inf)
    offset = R_object_palm @ approach_point_palm
    for _ in range(settings.max_steps):
        stats.steps += 1
        T = np.eye(4)
        T[:3, :3] = R_object_palm
        T[:3, 3] = target_object + s * ray_object - offset
        for b in range(B):
            idx = np.flatnonzero(lb[b] < EXACT_BELOW_MM)
            if len(idx) == 0:
                continue
            bodies[b].setTransform(fcl_transform(T @ T_palm_bodies[b]))
            for p in idx:
                lb[b, p] = pair_distance(bodies[b], object_pieces[p])
                stats.queries += 1
        gap = float(lb.min())
        if gap <= tol:
            if stats.stages is not None:
                stats.approach_s = (start_mm, s)
            return s
        step = gap - 0.5 * tol  # pure translation: every point moves at unit speed
        s -= step
        lb -= step
        if s < floor:
            return None
    stats.capped += 1
    return s
