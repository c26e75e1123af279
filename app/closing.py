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
The last step is refined by bisection to the first crossing of gap = stop tolerance, so
the stop is a property of the geometry and the tolerance, not of any step size.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import fcl
import numpy as np

from app.closing_settings import ClosingSettings
from app.hand.chains import FingerChain

#: Pairs whose distance lower bound is below this are queried exactly each step (mm).
EXACT_BELOW_MM = 12.0
#: Bisection steps refining a stage's stop to the first crossing of gap = stop tolerance.
BISECT_ITERS = 5

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

    @property
    def is_object(self) -> np.ndarray:
        """(P,) True for object pieces."""
        return np.arange(len(self.objs)) < self.n_object


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
    rho = np.where(np.tri(3, dtype=bool), rho, 0.0)  # axis i moves link k only if i <= k
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
    """
    q = q.astype(float).copy()
    tol = settings.stop_tol_mm
    first = int(np.flatnonzero(v > 0)[0])
    moving = range(first, 3)
    n_obs = len(obstacles.objs)
    mask = obstacles.mask if obstacles.mask is not None else np.ones((3, n_obs), bool)
    is_obj = obstacles.is_object
    lb = np.full((3, n_obs), -np.inf)  # -inf: query exactly
    if obstacles.spheres is not None:
        T0 = T_object_palm @ chain.link_poses(q)
        c_link = np.einsum("kij,kj->ki", T0[:, :3, :3], chain.mid_link) + T0[:, :3, 3]
        sph = obstacles.spheres
        finite = np.isfinite(sph[:, 3])
        gap = np.linalg.norm(c_link[:, None, :] - sph[None, finite, :3], axis=-1)
        lb[:, finite] = gap - chain.reach[:, None] - sph[None, finite, 3]
    lb[~mask] = np.inf

    def evaluate(qq: np.ndarray, full: bool) -> tuple[list[int], list[int]]:
        """Exact gaps at ``qq`` by lazy evaluation; links within tol (object, self).

        For each moving link, the pair with the smallest lower bound is queried until the
        smallest bound is an exact distance: that is the link's gap, and every other pair is
        at least its bound. Pairs with a bound <= tol are all queried (they may touch).
        ``full=False`` keeps the bounds of the previous configuration (bisection probes,
        which stay between two configurations already bounded)."""
        T_links = T_object_palm @ chain.link_poses(qq)
        exact = np.zeros_like(lb, dtype=bool)
        obj_hit: list[int] = []
        self_hit: list[int] = []
        for k in moving:
            posed = False
            row = lb[k]
            while True:
                p = int(np.argmin(row))
                if not np.isfinite(row[p]) and row[p] > 0:
                    break  # no pair to check
                if exact[k, p]:
                    cand = np.flatnonzero((row <= tol) & ~exact[k])
                    if len(cand) == 0:
                        break
                    p = int(cand[0])
                if not posed:
                    bodies[k].setTransform(fcl_transform(T_links[k] @ chain.T_link_fcl[k]))
                    posed = True
                d = pair_distance(bodies[k], obstacles.objs[p])
                stats.queries += 1
                row[p] = d
                exact[k, p] = True
            hit = np.flatnonzero(exact[k] & (row <= tol))
            if len(hit):
                if is_obj[hit].any():
                    obj_hit.append(k)
                else:
                    self_hit.append(k)
        del full
        return obj_hit, self_hit

    q_safe: np.ndarray | None = None  # last q where every gap exceeded tol
    lb_safe = lb.copy()
    rates_safe = np.zeros(3)
    for _ in range(settings.max_steps):
        stats.steps += 1
        touching_obj, touching_self = evaluate(q, True)
        if (touching_obj or touching_self) and q_safe is not None:
            # refine the stop to the first crossing of gap = tol between q_safe and q
            lo, hi = q_safe, q
            lb_hi = lb.copy()
            for _ in range(BISECT_ITERS):
                mid = 0.5 * (lo + hi)
                # bounds at mid: from the safe side, minus the motion from q_safe to mid
                frac = float(np.max((mid - q_safe) / np.where(v > 0, v, 1.0)))
                lb[:] = lb_safe - rates_safe[:, None] * frac
                o, s_ = evaluate(mid, False)
                if o or s_:
                    hi, touching_obj, touching_self = mid, o, s_
                    lb_hi = lb.copy()
                else:
                    lo = mid
            q = hi
            lb[:] = lb_hi
        if touching_obj:
            return q, StageEvent("contact", tuple(sorted(set(touching_obj))))
        if touching_self:
            return q, StageEvent("self", tuple(sorted(set(touching_self))))
        room = np.where(v > 0, (chain.q_upper - q) / np.where(v > 0, v, 1.0), np.inf)
        at_limit = tuple(int(i) for i in np.flatnonzero((v > 0) & (room <= 1e-12)))
        if at_limit:
            return q, StageEvent("limit", joints=at_limit)
        T_links = T_object_palm @ chain.link_poses(q)
        rates = _axis_rates(T_links, chain, v)
        gaps = lb[list(moving)].min(axis=1)
        with np.errstate(divide="ignore"):
            steps = (gaps - 0.5 * tol) / rates[first:]
        step = min(float(steps.min()), float(room.min()))
        q_safe, lb_safe, rates_safe = q, lb.copy(), rates
        q = np.minimum(q + v * step, np.where(v > 0, chain.q_upper, q))
        lb -= rates[:, None] * step
    stats.capped += 1
    return q, StageEvent("max_steps")


def close_finger(
    chain: FingerChain,
    bodies: list[fcl.CollisionObject],
    T_object_palm: np.ndarray,
    obstacles: Obstacles,
    settings: ClosingSettings,
    stats: ClosingStats,
) -> np.ndarray:
    """Close one finger from its open posture by ``settings.mode``; returns its q (3,)."""
    q = chain.q_lower.copy()
    mode = settings.mode

    def run(v: np.ndarray) -> StageEvent:
        nonlocal q
        q0 = q
        q, ev = advance_stage(chain, bodies, T_object_palm, q, v, obstacles, settings, stats)
        stats.events.append(f"{chain.finger}:{np.flatnonzero(v > 0).tolist()}:{ev.kind}")
        if stats.stages is not None:
            stats.stages.append((chain.finger, q0.copy(), q.copy(), ev.kind))
        return ev

    def sequential(k: int) -> None:
        while k < 3:
            ev = run(np.eye(3)[k])
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
) -> float | None:
    """Slide the hand along the ray toward the object until first contact.

    The hand is placed with P on the line ``target + s · ray`` and orientation R; s falls
    from ``start_mm``. ``bodies`` (with FCL-frame poses ``T_palm_bodies`` (B, 4, 4)) are the
    links that take part. Returns s at first contact (gap ≤ stop tolerance), or None if the
    hand passes the target by ``start_mm`` without touching.
    """
    tol = settings.stop_tol_mm
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
        if s < -start_mm:
            return None
    stats.capped += 1
    return s
