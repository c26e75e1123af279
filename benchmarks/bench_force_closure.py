"""Why the benchmark decides FC by positive spanning and not by a qhull hull. Prints figures.

Usage: .venv/bin/python benchmarks/bench_force_closure.py
"""

from __future__ import annotations

import time

import numpy as np

from app.quality.force_closure import fc_and_epsilon, positively_spans, primitive_wrenches
from app.quality.force_closure_lp import is_force_closure_lp


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


def main() -> None:
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


if __name__ == "__main__":
    main()
