"""Warm numba's on-disk cache of every compiled kernel: ``python -m app.quality.warm``.

``make setup`` (and ``make pytest``) run this once so that no process compiles at run time:
the compiled engine (``app.sim.warm``: closing, contacts, signed distances, GJK; about a
minute on a 2-core machine when cold) and the force-closure kernel
(``app.quality.force_closure_compiled``, about 30 s when cold). It prints how long each took.
"""

from __future__ import annotations

import time

from app.quality import force_closure_compiled
from app.sim import warm as sim_warm


def warm_force_closure() -> float:
    """Compile or load the force-closure kernels; seconds taken."""
    t0 = time.perf_counter()
    force_closure_compiled.warm()
    return time.perf_counter() - t0


def main() -> None:
    """Warm the cache and say how long it took."""
    dt = sim_warm.warm()
    print(f"compiled engine ready (numba cache warm): one hypothesis took {dt:.1f} s")
    dt = warm_force_closure()
    print(f"force-closure kernel ready (numba cache warm): {dt:.1f} s")


if __name__ == "__main__":
    main()
