"""Reference closing with fixed joint steps, as older simulators do (benchmarks, tests).

Sequential mode only: each stage advances one joint by ``step_rad`` until a moving link is
within the stop tolerance of an obstacle (or would penetrate), or the limit. It costs one
round of distance queries per step; the engine in ``app.sim.closing`` must agree with it to
within one step.
"""

from __future__ import annotations

import fcl
import numpy as np

from app.model.hand.chains import FingerChain
from app.sim.closing import ClosingStats, Obstacles, fcl_transform, pair_distance
from app.sim.closing_settings import ClosingSettings


def close_finger_naive(
    chain: FingerChain,
    bodies: list[fcl.CollisionObject],
    T_object_palm: np.ndarray,
    obstacles: Obstacles,
    settings: ClosingSettings,
    stats: ClosingStats,
    step_rad: float = 0.01,
) -> np.ndarray:
    """Sequential closing of one finger with fixed steps; returns its q (3,)."""
    q = chain.q_lower.copy()
    tol = settings.stop_tol_mm
    n_obs = len(obstacles.objs)
    mask = obstacles.mask if obstacles.mask is not None else np.ones((3, n_obs), bool)
    is_obj = obstacles.is_object

    def touching(qq: np.ndarray, first: int) -> list[int]:
        T_links = T_object_palm @ chain.link_poses(qq)
        hit = []
        for k in range(first, 3):
            bodies[k].setTransform(fcl_transform(T_links[k] @ chain.T_link_fcl[k]))
            for p in np.flatnonzero(mask[k]):
                stats.queries += 1
                if pair_distance(bodies[k], obstacles.objs[p]) <= tol:
                    hit.append(k)
                    break
        return hit

    k = 0
    while k < 3:
        links: list[int] = []
        while True:
            stats.steps += 1
            links = touching(q, k)
            if links or q[k] >= chain.q_upper[k]:
                break
            q[k] = min(q[k] + step_rad, chain.q_upper[k])
        k = max(links) + 1 if links else k + 1
    del is_obj
    return q
