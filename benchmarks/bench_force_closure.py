"""Why the benchmark decides FC by positive spanning and not by a qhull hull, and what the
compiled decision saves on real grasps. Prints figures.

Usage: .venv/bin/python benchmarks/bench_force_closure.py [--sample 10] [--reps 3]

Part 2 simulates every ``sample``-th hypothesis of the six objects at design 0/45 (compiled
engine, as ``bench_sweep.py``), keeps each approached grasp's contact set (what the judge
sees) and times, in CPU time per grasp (best of ``reps`` passes), the scipy path
(``primitive_wrenches`` + ``positively_spans``) against ``positively_spans_compiled``, with
the compiled path's fallback rate and the number of differing verdicts.
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

from app.model.contact_set import ContactSet
from app.model.objects import OBJECT_KEYS, load_object
from app.quality import force_closure as fcm
from app.quality.force_closure import (
    fc_and_epsilon,
    positively_spans,
    positively_spans_compiled,
    primitive_wrenches,
)
from app.quality.force_closure_lp import is_force_closure_lp
from app.quality.settings import SimSettings
from app.quality.warm import warm_force_closure
from app.sim.hypothesis_sets import cached_hypotheses
from app.sim.simulate import cached_kit, simulate_base, simulate_thumb


def contact_set(rng: np.random.Generator, k: int) -> np.ndarray:
    p = rng.normal(size=(k, 3))
    p /= np.linalg.norm(p, axis=1, keepdims=True)
    n = -p + rng.normal(scale=0.3, size=(k, 3))
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    return primitive_wrenches(30 * p, n, np.zeros(3), 30.0)


def timeit(f, W: np.ndarray, reps: int) -> float:
    t = time.perf_counter()
    for _ in range(reps):
        f(W)
    return (time.perf_counter() - t) / reps * 1e3


def synthetic() -> None:
    rng = np.random.default_rng(0)
    print(f"{'contacts':>8} {'wrenches':>8} {'qhull ms':>9} {'LP ms':>7} {'NNLS ms':>8}  agree")
    for k in (12, 24, 40):
        W = contact_set(rng, k)
        a = fc_and_epsilon(W)[0], is_force_closure_lp(W), positively_spans(W)
        print(
            f"{k:>8} {len(W):>8} {timeit(fc_and_epsilon, W, 2):>9.1f} "
            f"{timeit(is_force_closure_lp, W, 5):>7.1f} {timeit(positively_spans, W, 20):>8.2f}"
            f"  {a[0] == a[1] == a[2]}"
        )


Grasp = tuple[str, ContactSet, np.ndarray, float]


def real_grasps(sample: int) -> list[Grasp]:
    """(object, contacts, centroid, r) of every approached grasp of every ``sample``-th
    hypothesis of the six objects, design 0/45."""
    s = SimSettings()
    kit = cached_kit(0.0, 45.0, "ulnar")
    out: list[Grasp] = []
    for key in OBJECT_KEYS:
        obj, hy = load_object(key), cached_hypotheses(key)
        for i in range(0, len(hy), sample):
            g = simulate_thumb(kit, obj, simulate_base(kit, obj, hy, i, s), s)
            if g.approached and len(g.contacts):
                out.append((key, g.contacts, obj.centroid_object, float(obj.max_radius)))
    return out


def compare(grasps: list[Grasp], reps: int) -> None:
    mu, n_edges = SimSettings().fc.mu, SimSettings().fc.n_edges

    def scipy_path(g: Grasp) -> bool:
        return positively_spans(primitive_wrenches(g[1].p_object, g[1].n_object, g[2], g[3],
                                                   mu, n_edges))  # fmt: skip

    def compiled_path(g: Grasp) -> bool:
        return positively_spans_compiled(g[1].p_object, g[1].n_object, g[2], g[3], mu, n_edges)

    best = {}
    for name, f in (("scipy", scipy_path), ("compiled", compiled_path)):
        times = []
        for _ in range(reps):
            c0 = time.process_time()
            for g in grasps:
                f(g)
            times.append(time.process_time() - c0)
        best[name] = 1e3 * min(times) / len(grasps)
    before = dict(fcm.COMPILED_STATS)
    ref = [scipy_path(g) for g in grasps]
    got = [compiled_path(g) for g in grasps]
    fallbacks = fcm.COMPILED_STATS["fallbacks"] - before["fallbacks"]
    n_w = np.array([len(g[1]) * n_edges for g in grasps])
    print(f"real grasps (six objects, design 0/45)  : {len(grasps)}, {sum(ref)} FC, "
          f"wrenches per grasp median {int(np.median(n_w))}, max {n_w.max()}")  # fmt: skip
    print(f"scipy path (numpy wrenches + 7 nnls)   : {best['scipy']:8.3f} ms per grasp (CPU)")
    print(f"compiled (positively_spans_compiled)   : {best['compiled']:8.3f} ms per grasp (CPU), "
          f"{best['scipy'] / best['compiled']:.1f}x")  # fmt: skip
    print(f"fallbacks to the scipy path            : {fallbacks} of {len(grasps)} "
          f"({100 * fallbacks / len(grasps):.2f} %)")  # fmt: skip
    differ = sum(a != b for a, b in zip(ref, got, strict=True))
    print(f"differing verdicts                     : {differ}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--sample", type=int, default=10, help="every n-th hypothesis per object")
    ap.add_argument("--reps", type=int, default=3, help="timing passes (best is reported)")
    ap.add_argument("--no-synthetic", action="store_true", help="skip the qhull/LP/NNLS table")
    args = ap.parse_args()
    if not args.no_synthetic:
        synthetic()
    warm_force_closure()
    grasps = real_grasps(args.sample)
    print(f"load average before timing: {os.getloadavg()}")
    compare(grasps, args.reps)
    print(f"load average at end: {os.getloadavg()}")


if __name__ == "__main__":
    main()
