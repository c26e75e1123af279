"""Rebuild cost of the hand for a new thumb design (issue: < 50 ms). Prints figures.

Usage: .venv/bin/python benchmarks/bench_hand_rebuild.py
"""

from __future__ import annotations

import time

import numpy as np

from app.model.hand.model import build_hand
from app.sim.simulate import HandKit


def main() -> None:
    rng = np.random.default_rng(0)
    designs = rng.uniform([0, 0], [45, 90], size=(200, 2))
    build_hand(0, 45).visual_meshes()  # warm the shared visual meshes (design-independent)
    t = time.perf_counter()
    for c, m in designs:
        build_hand(float(c), float(m))
    hand_ms = (time.perf_counter() - t) / len(designs) * 1e3
    t = time.perf_counter()
    for c, m in designs[:50]:
        HandKit(build_hand(float(c), float(m)))
    kit_ms = (time.perf_counter() - t) / 50 * 1e3
    h = build_hand(10, 20)
    q = h.q_open
    t = time.perf_counter()
    for _ in range(2000):
        h.link_poses(q)
    fk_us = (time.perf_counter() - t) / 2000 * 1e6
    print(f"build_hand (Pinocchio model + data + shapes) : {hand_ms:8.3f} ms per design")
    print(f"HandKit (hand + FCL bodies + finger chains)   : {kit_ms:8.3f} ms per design")
    print(f"whole-hand forward kinematics (16 links)      : {fk_us:8.1f} us")
    print(f"target: rebuild < 50 ms -> {'met' if kit_ms < 50 else 'NOT met'}")


if __name__ == "__main__":
    main()
