"""Engine figures (issue 3 item 6, issue 6 item 1). Prints figures; asserts nothing.

- GH closings per second per core and FCL queries per closing (base stage and thumb stage)
- seconds for one design over all six objects (4,260 GHs), cold store, local process pool
  (fresh pool: its start-up included), and for a new design on a running pool (the
  explorer's case)
- the same on a warm store (everything cached)
- with --full: seconds for the 28-design sweep, cold store
- peak RSS of this process and its workers

Usage: .venv/bin/python benchmarks/bench_sweep.py [--workers N] [--full] [--sample K]
       [--engine fcl|compiled] [--no-sweep]
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import resource
import shutil
import tempfile
import time
from pathlib import Path

from app.model.design import ThumbDesign, published_designs
from app.model.objects import OBJECT_KEYS, load_object
from app.quality.judge import judge
from app.quality.settings import SimSettings
from app.runs.executors import LocalExecutor
from app.runs.palm_cache import palm_table
from app.runs.store import ResultStore
from app.runs.sweep import run_sweep
from app.sim.closing import ClosingStats
from app.sim.hypothesis_sets import cached_hypotheses
from app.sim.simulate import cached_kit, simulate_base, simulate_thumb


def settings_of(engine: str) -> SimSettings:
    """The default settings with the closing engine ``engine``."""
    s = SimSettings()
    return dataclasses.replace(s, closing=dataclasses.replace(s.closing, engine=engine))


def per_core_rates(sample: int, engine: str) -> None:
    """Single-process timing of the two stages on every ``sample``-th GH of each object."""
    s = settings_of(engine)
    kit = cached_kit(0.0, 45.0, "ulnar")
    tb = tt = 0.0
    nb = nq_b = nq_t = 0
    # one-time set-up per process (object meshes, SDF tables, hypotheses), timed apart
    t0 = time.perf_counter()
    for key in OBJECT_KEYS:
        obj, hy = load_object(key), cached_hypotheses(key)
        simulate_thumb(kit, obj, simulate_base(kit, obj, hy, len(hy) - 1, s), s)
    print(f"first-use set-up, six objects        : {time.perf_counter() - t0:8.2f} s per process")
    siblings = [cached_kit(0.0, m, "ulnar") for m in (0.0, 15.0, 30.0, 60.0, 75.0, 90.0)]
    tj = ts = 0.0
    ns = 0
    cpu = 0.0  # process CPU time of base + thumb + judge (robust to a busy machine)
    cpu_new = 0.0  # the same on a known palm stage
    palms = {key: palm_table(key, s) for key in OBJECT_KEYS}
    for t in palms.values():  # the palm stages of the sample (computed when not cached)
        for i in range(0, len(t), sample):
            t.get(i)
    for key in OBJECT_KEYS:
        obj, hy = load_object(key), cached_hypotheses(key)
        for i in range(0, len(hy), sample):
            sb = ClosingStats()
            c0 = time.process_time()
            t0 = time.perf_counter()
            base = simulate_base(kit, obj, hy, i, s, sb)
            t1 = time.perf_counter()
            g = simulate_thumb(kit, obj, base, s)
            t2 = time.perf_counter()
            judge(g, obj, s, 0)
            t3 = time.perf_counter()
            cpu += time.process_time() - c0
            # a new design whose hypothesis' palm stage is known (the palm table)
            palm = palms[key].get(i)
            c0 = time.process_time()
            judge(
                simulate_thumb(kit, obj, simulate_base(kit, obj, hy, i, s, palm=palm), s), obj, s, 0
            )
            cpu_new += time.process_time() - c0
            for k in siblings:  # the other MCP angles of c = 0 on the same base (CMC memo)
                simulate_thumb(k, obj, base, s)
            t4 = time.perf_counter()
            tb += t1 - t0
            tt += t2 - t1
            tj += t3 - t2
            ts += t4 - t3
            ns += len(siblings)
            nb += 1
            nq_b += base.queries
            nq_t += g.queries
    print(f"sampled GHs                          : {nb} (every {sample}th of each object)")
    print(
        f"base stage (approach + long fingers) : {nb / tb:8.1f} GH/s per core, "
        f"{nq_b / nb:6.1f} FCL queries per GH"
    )
    print(
        f"thumb stage (per design)             : {nb / tt:8.1f} GH/s per core, "
        f"{nq_t / nb:6.1f} FCL queries per GH"
    )
    print(
        f"thumb stage, 6 more MCP designs      : {ns / ts:8.1f} GH/s per core "
        "(same base: the CMC stage is shared)"
    )
    print(f"judge (force closure + grasp type)   : {nb / tj:8.1f} GH/s per core")
    print(f"full closing (base + thumb + judge)  : {nb / (tb + tt + tj):8.1f} GH/s per core")
    print(f"the same in CPU time                 : {1e3 * cpu / nb:8.2f} ms per GH")
    print(f"a new design on known palm stages    : {1e3 * cpu_new / nb:8.2f} ms per GH (CPU)")


def timed_sweep(
    designs: list[ThumbDesign],
    workers: int,
    store_path: Path,
    engine: str,
    executor: LocalExecutor | None = None,
) -> float:
    """Seconds to sweep ``designs`` over the six objects into ``store_path``; on a fresh
    process pool (its start-up included) unless ``executor`` is given."""
    with ResultStore(store_path) as store:
        ex = executor or LocalExecutor(workers)
        try:
            t0 = time.perf_counter()
            c0 = time.process_time()
            res = run_sweep(
                designs,
                OBJECT_KEYS,
                settings=settings_of(engine),
                store=store,
                executor=ex,
                progress=False,
            )
            dt = time.perf_counter() - t0
            # the driver unpickles and stores every outcome: CPU the workers do not get
            print(f"  (driver CPU {time.process_time() - c0:.1f} s of {dt:.1f} s)")
        finally:
            if executor is None:
                ex.close()
    assert res is not None
    return dt


def peak_rss_mib() -> tuple[float, float]:
    me = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    kids = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
    return me, kids


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--full", action="store_true", help="also time the 28-design sweep")
    ap.add_argument("--sample", type=int, default=20, help="GH stride for per-core rates")
    ap.add_argument("--engine", default=SimSettings().closing.engine, choices=("fcl", "compiled"))
    ap.add_argument("--no-sweep", action="store_true", help="per-core rates only")
    args = ap.parse_args()
    print(f"engine {args.engine}, load average at start: {os.getloadavg()}")
    per_core_rates(args.sample, args.engine)
    if args.no_sweep:
        print(f"load average at end: {os.getloadavg()}")
        return
    tmp = Path(tempfile.mkdtemp(prefix="handbench-bench-"))
    try:
        n = sum(len(cached_hypotheses(k)) for k in OBJECT_KEYS)
        dt = timed_sweep([ThumbDesign(0, 45)], args.workers, tmp / "one.sqlite", args.engine)
        print(f"one design, six objects ({n} GHs), cold : {dt:8.1f} s  ({args.workers} workers)")
        dt = timed_sweep([ThumbDesign(0, 45)], args.workers, tmp / "one.sqlite", args.engine)
        print(f"the same, warm store                    : {dt:8.2f} s")
        # the explorer's case: its worker pool is running (started as the explorer starts
        # it: every worker has loaded the objects, palm tables and kernels) when a new design
        # comes; the store has nothing of that design
        pool = LocalExecutor(args.workers, warm_objects=OBJECT_KEYS)
        pool.start()
        try:
            timed_sweep([ThumbDesign(0, 45)], args.workers, tmp / "pool.sqlite", args.engine, pool)
            for d in (ThumbDesign(30, 75), ThumbDesign(20, 50)):
                dt = timed_sweep([d], args.workers, tmp / "pool.sqlite", args.engine, pool)
                print(
                    f"new design {d.cmc_deg:g}/{d.mcp_deg:g} on a running pool, cold  : {dt:8.1f} s"
                )
        finally:
            pool.close()
        if args.full:
            dt = timed_sweep(published_designs(), args.workers, tmp / "all.sqlite", args.engine)
            print(
                f"28-design sweep, cold                   : {dt:8.1f} s  ({args.workers} workers)"
            )
        me, kids = peak_rss_mib()
        print(f"peak RSS: driver {me:.0f} MiB, largest worker {kids:.0f} MiB")
        print(f"load average at end: {os.getloadavg()}")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
