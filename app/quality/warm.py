"""Warm numba's on-disk cache of every compiled kernel: ``python -m app.quality.warm``.

``make setup`` (and ``make pytest``) run this once so that no process compiles at run time:
the compiled engine (``app.sim.warm``: closing, contacts, signed distances, GJK; about a
minute on a 2-core machine when cold) and the force-closure kernel
(``app.quality.force_closure_compiled``, about 30 s when cold). It prints how long each took.
"""

from __future__ import annotations

import shutil
import time
from pathlib import Path

from app import numba_cache_dir
from app.quality import force_closure_compiled
from app.sim import warm as sim_warm


def warm_force_closure() -> float:
    """Compile or load the force-closure kernels; seconds taken."""
    t0 = time.perf_counter()
    force_closure_compiled.warm()
    return time.perf_counter() - t0


#: Caches of other kernel sources unused this long are removed by ``main``.
STALE_CACHE_DAYS = 14


def prune_stale_caches(current: Path, days: float = STALE_CACHE_DAYS) -> list[Path]:
    """Remove the numba caches of other kernel sources (``numba_cache_dir``'s siblings) not
    modified for ``days``; the ones removed."""
    gone = []
    if not current.parent.is_dir():
        return gone
    cutoff = time.time() - days * 86400.0
    for d in current.parent.iterdir():
        if d.is_dir() and d != current and d.stat().st_mtime < cutoff:
            shutil.rmtree(d, ignore_errors=True)
            gone.append(d)
    return gone


def main() -> None:
    """Warm the cache and say how long it took."""
    prune_stale_caches(numba_cache_dir())
    dt = sim_warm.warm()
    print(f"compiled engine ready (numba cache warm): one hypothesis took {dt:.1f} s")
    dt = warm_force_closure()
    print(f"force-closure kernel ready (numba cache warm): {dt:.1f} s")


if __name__ == "__main__":
    main()
