"""Cost of the brute-force GQM stage (METHOD §6) per grasp, and where it goes. Prints figures.

Usage: .venv/bin/python benchmarks/bench_gqm.py [--objects small_marker chips_can]
       [--grasps 20] [--gh-stride 5] [--workers 2] [--store PATH]

1. Simulates every ``--gh-stride``-th brute-force GH of each object for one design (baseline
   CMC 0°, MCP 45°) into a throwaway store (or ``--store``), and draws up to ``--grasps`` of
   the FC grasps per object (``app.gqm.compare.draw_fc``).
2. The GQM stage per grasp: one process without the store (how the stage ran before the
   ``gqms`` table: the CLI used one process), ``--workers`` processes writing the store
   (first run), and the rerun (every GQM read from the store).
3. Where one grasp's time goes: the wrench-space hull (Q_C1, Q_C2) against the eight other
   GQMs, the number of primitive wrenches, the share of them that are hull vertices, the
   hull's facets, and qhull precision errors (retried with ``QJ``).
4. Alternatives measured and NOT used, each with its deviation from the exact values:
   - ``vertices only``: the hull of the hull's own vertices, the best any exact pruning of
     interior wrenches can do;
   - ``per-link pruning``: drop, one by one, each wrench inside the hull of the remaining
     wrenches of its own link (non-negative least squares), then the hull (time of both);
   - ``Qx Q5``/``QJ``: other qhull options;
   - ``incremental ε``: exact Ferrari–Canny ε without the full hull (a hull of a few extreme
     wrenches, grown by the wrench farthest beyond its closest facets until the closest
     facet supports every wrench; then that facet's distance is ε of the full set), which
     needs Q_C2 to be computed another way to save anything;
   - ``link contacts``: the hull of one contact per link (``--wrench-contacts link``), a
     different Q_C1/Q_C2 (Spearman rank correlation with the patch values printed).
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

import numpy as np
from scipy.optimize import nnls
from scipy.spatial import ConvexHull, QhullError
from scipy.stats import spearmanr

import app.gqm as gqm_pkg
from app.design import ThumbDesign
from app.force_closure import primitive_wrenches
from app.gqm import GQMSettings, compute_gqms, wrench_space_of
from app.gqm.compare import (
    BF_SET,
    GQM_CHUNK,
    _gqm_job,
    _kit,
    _Pose,
    _run_jobs,
    draw_fc,
    score_grasps,
)
from app.gqm.contacts import link_contacts
from app.objects import load_object
from app.settings import SimSettings
from app.store import GraspOutcome, ResultStore
from app.sweep import InlineExecutor, LocalExecutor, execute_tasks, plan_tasks, set_object_key


def epsilon_incremental(W: np.ndarray, n_dirs: int = 64, k: int = 8) -> tuple[float, int]:
    """Exact ε of conv(W) from hulls of subsets (see the module docstring); (ε, points used).

    Sub-hull H ⊂ conv(W): the ball of radius β = min facet distance of H lies in conv(W); if
    the facet at β has no wrench beyond it, it supports conv(W), so ε(W) = β.
    """
    rng = np.random.default_rng(0)
    dirs = np.vstack([np.eye(6), -np.eye(6), rng.normal(size=(n_dirs, 6))])
    idx = np.unique(np.argmax(W @ dirs.T, axis=0))
    tol = 1e-12 * float(np.max(np.abs(W)))
    while True:
        eq = ConvexHull(W[idx]).equations
        d = -eq[:, -1]
        near = np.argsort(d)[:k]
        S = W @ eq[near, :6].T
        beyond = S.max(axis=0) - d[near]
        if beyond[0] <= tol:
            return float(d[near[0]]), len(idx)
        idx = np.union1d(idx, np.argmax(S[:, beyond > tol], axis=0))


def prune_per_link(W: np.ndarray, links: np.ndarray, n_edges: int = 8) -> np.ndarray:
    """Mask of the wrenches kept: each one inside the hull of the remaining ones of its link
    (NNLS residual ≤ 1e-12 · max|W|) is dropped, sequentially, so conv(kept) = conv(W)."""
    keep = np.ones(len(W), bool)
    tol = 1e-12 * float(np.max(np.abs(W)))
    owner = np.repeat(links, n_edges)
    for name in dict.fromkeys(links):
        group = np.flatnonzero(owner == name)
        for i in group:
            others = group[keep[group] & (group != i)]
            if len(others) < 2:
                continue
            A = np.vstack([W[others].T, np.ones(len(others))])
            if nnls(A, np.append(W[i], 1.0))[1] <= tol:
                keep[i] = False
    return keep


def hull(
    W: np.ndarray, options: str | None = None, reps: int = 2
) -> tuple[float, float, float, int, np.ndarray]:
    """(ms, ε, volume, facets, vertex indices) of a qhull run (NaNs on a precision error);
    ms is the best of ``reps`` runs (the first run of a process is slower: memory)."""
    ms = np.inf
    for _ in range(reps):
        t = time.perf_counter()
        try:
            h = ConvexHull(W, qhull_options=options)
        except QhullError:
            return (time.perf_counter() - t) * 1e3, np.nan, np.nan, 0, np.zeros(0, int)
        ms = min(ms, (time.perf_counter() - t) * 1e3)
    eps = float(np.min(-h.equations[:, -1]))
    return ms, eps, float(h.volume), len(h.equations), np.sort(h.vertices)


def rel(a: np.ndarray, b: np.ndarray) -> float:
    """Largest relative deviation of a from b over the finite pairs."""
    ok = np.isfinite(a) & np.isfinite(b) & (b != 0)
    return float(np.max(np.abs(a[ok] / b[ok] - 1))) if ok.any() else float("nan")


def simulate(store: ResultStore, names: list[str], design: ThumbDesign, stride: int, workers: int):
    sim = SimSettings()
    tasks = plan_tasks(store, [design], names, sim, gh_stride=stride, hypothesis_set=BF_SET)
    ex = InlineExecutor() if workers == 1 else LocalExecutor(workers)
    t = time.perf_counter()
    try:
        n = execute_tasks(tasks, store, sim.key(), lambda k: set_object_key(k, BF_SET), ex, False)
    finally:
        ex.close()
    print(f"simulated {n} brute-force grasps in {time.perf_counter() - t:.1f} s")


def analyse(name: str, design: ThumbDesign, drawn: list[tuple[str, GraspOutcome]]) -> None:
    obj = load_object(name)
    hand = _kit(design.cmc_deg, design.mcp_deg, design.cmc_tilt).hand
    c, r = np.asarray(obj.centroid_object, float), float(obj.max_radius)
    rows = []
    for _, o in drawn:
        cs = o.contacts
        W = primitive_wrenches(np.asarray(cs.p_object, float), np.asarray(cs.n_object, float), c, r)
        pose = _Pose(o.q_final_rad, np.asarray(o.extra["T_object_palm"], float), cs)
        t = time.process_time()
        compute_gqms(pose, obj, hand)  # type: ignore[arg-type]
        total = (time.process_time() - t) * 1e3
        ws = gqm_pkg.wrench_space_of(cs, link_contacts(cs), c, r, GQMSettings())
        gqm_pkg.wrench_space_of = lambda *_, ws=ws: ws  # the same GQMs without the hull
        try:
            t = time.process_time()
            compute_gqms(pose, obj, hand)  # type: ignore[arg-type]
            others = (time.process_time() - t) * 1e3
        finally:
            gqm_pkg.wrench_space_of = wrench_space_of
        ms, eps, vol, facets, verts = hull(W)
        failed = not np.isfinite(eps)
        if failed:  # the product retries with QJ: time both, compare with QJ's values
            qj_ms, eps, vol, facets, verts = hull(W, "QJ")
            ms += qj_ms
        v_ms, v_eps, v_vol = hull(W[verts])[:3]
        t = time.perf_counter()
        keep = prune_per_link(W, np.asarray([str(x) for x in cs.link]))
        p_ms = (time.perf_counter() - t) * 1e3
        pr = hull(W[keep])
        q5 = hull(W, "Qx Q5")
        qj = hull(W, "QJ")
        t = time.perf_counter()
        try:
            inc_eps, inc_n = epsilon_incremental(W)
        except QhullError:
            inc_eps, inc_n = np.nan, 0
        inc_ms = (time.perf_counter() - t) * 1e3
        lc = link_contacts(cs)
        lk = hull(primitive_wrenches(lc.p, lc.n, c, r))
        rows.append(
            dict(
                total=total, others=others, hull=ms, M=len(W), vshare=len(verts) / len(W),
                facets=facets, qhullerr=float(failed), eps=eps, vol=vol,
                v_ms=v_ms, v_eps=v_eps, v_vol=v_vol,
                p_ms=p_ms + pr[0], p_eps=pr[1], p_vol=pr[2], p_n=float(np.sum(~keep)),
                q5_ms=q5[0], q5_eps=q5[1], q5_vol=q5[2], qj_ms=qj[0], qj_eps=qj[1], qj_vol=qj[2],
                inc_ms=inc_ms, inc_eps=inc_eps, inc_n=inc_n,
                lk_ms=lk[0], lk_eps=lk[1], lk_vol=lk[2],
            )
        )  # fmt: skip
    col = {k: np.array([row[k] for row in rows], float) for k in rows[0]}
    a = col["M"]
    n = len(a)
    print(
        f"\n{name} ({load_object(name).spec.grasp_type}), {n} FC grasps: "
        f"{np.mean(col['M']):.0f} primitive wrenches per grasp, "
        f"{np.nanmean(col['vshare']):.1%} of them hull vertices, "
        f"{np.mean(col['facets']):,.0f} facets, {int(np.sum(col['qhullerr']))} qhull precision "
        f"errors (retried with QJ)"
    )
    print(
        f"  one grasp, ten GQMs: {np.mean(col['total']):.0f} ms CPU, of which the eight GQMs "
        f"other than Q_C1/Q_C2 {np.mean(col['others']):.1f} ms; the exact hull alone "
        f"{np.mean(col['hull']):.0f} ms (best of 2; a precision error: + the QJ retry)"
    )
    ok = col["qhullerr"] == 0
    print("  alternatives (ms per grasp without a precision error, best of 2; largest relative")
    print("  deviation from the exact ε and volume, QJ's where qhull failed):")
    print(
        f"    vertices only      {np.mean(col['v_ms'][ok]):6.0f} ms   "
        f"ε {rel(col['v_eps'], col['eps']):.0e}  vol {rel(col['v_vol'], col['vol']):.0e}"
    )
    print(
        f"    per-link pruning   {np.mean(col['p_ms'][ok]):6.0f} ms   "
        f"ε {rel(col['p_eps'], col['eps']):.0e}  vol {rel(col['p_vol'], col['vol']):.0e}  "
        f"({np.mean(col['p_n']):.0f} of {np.mean(col['M'] * (1 - col['vshare'])):.0f} interior "
        f"wrenches dropped)"
    )
    print(
        f"    qhull 'Qx Q5'      {np.mean(col['q5_ms'][ok]):6.0f} ms   "
        f"ε {rel(col['q5_eps'], col['eps']):.0e}  vol {rel(col['q5_vol'], col['vol']):.0e}"
    )
    print(
        f"    qhull 'QJ'         {np.mean(col['qj_ms'][ok]):6.0f} ms   "
        f"ε {rel(col['qj_eps'], col['eps']):.0e}  vol {rel(col['qj_vol'], col['vol']):.0e}"
    )
    print(
        f"    incremental ε      {np.mean(col['inc_ms']):6.1f} ms   "
        f"ε {rel(col['inc_eps'], col['eps']):.0e}  (no volume; "
        f"{np.mean(col['inc_n']):.0f} of {np.mean(col['M']):.0f} wrenches used)"
    )
    rho_e = spearmanr(col["lk_eps"], col["eps"], nan_policy="omit")[0]
    rho_v = spearmanr(col["lk_vol"], col["vol"], nan_policy="omit")[0]
    print(
        f"    link contacts      {np.mean(col['lk_ms']):6.1f} ms   "
        f"a different measure: ε {rel(col['lk_eps'], col['eps']):.0e}  vol "
        f"{rel(col['lk_vol'], col['vol']):.0e}; rank correlation ε {rho_e:.2f}, vol {rho_v:.2f}"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--objects", nargs="+", default=["small_marker", "chips_can"])
    ap.add_argument("--grasps", type=int, default=20, help="FC grasps per object")
    ap.add_argument("--gh-stride", type=int, default=5, help="simulate every k-th GH")
    ap.add_argument("--workers", type=int, default=2, help="processes of the GQM stage")
    ap.add_argument("--store", help="results store to reuse (default: a throwaway one)")
    args = ap.parse_args()
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    design = ThumbDesign(0, 45)
    sim = SimSettings()
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(args.store) if args.store else Path(tmp) / "bench.sqlite"
        with ResultStore(path) as store:
            simulate(store, args.objects, design, args.gh_stride, args.workers)
            drawn = {
                (name, design): draw_fc(store, name, design, sim, args.grasps, 0)
                for name in args.objects
            }
            # warm this process (objects, hands) and time a pool's start: spawn, imports, loads
            empty = [
                (name, (design.cmc_deg, design.mcp_deg, design.cmc_tilt), [], GQMSettings())
                for name in args.objects
            ]
            for job in empty:
                _gqm_job(job)
            t = time.perf_counter()
            list(_run_jobs(empty * args.workers, args.workers))
            start = time.perf_counter() - t
            print(f"\nstarting {args.workers} GQM processes (spawn, imports, loads): {start:.1f} s")
            n = sum(len(v) for v in drawn.values())
            counts = ", ".join(f"{k[0]} {len(v)}" for k, v in drawn.items())
            print(f"GQM stage, {n} FC grasps ({counts}), wall time per grasp:")
            if n == 0:
                return
            t, cpu = time.perf_counter(), time.process_time()
            score_grasps(drawn, workers=1)
            before = (time.perf_counter() - t) / n * 1e3
            before_cpu = (time.process_time() - cpu) / n * 1e3
            t = time.perf_counter()
            first = score_grasps(drawn, workers=args.workers, store=store, sim=sim)
            after = (time.perf_counter() - t) / n * 1e3
            t = time.perf_counter()
            again = score_grasps(drawn, workers=args.workers, store=store, sim=sim)
            rerun = (time.perf_counter() - t) / n * 1e3
            same = [s.values for s in first.scored] == [s.values for s in again.scored]
            jobs = sum(-(-len(v) // GQM_CHUNK) for v in drawn.values())
            print(
                f"  one process, no store (the stage before):   {before:7.0f} ms "
                f"(CPU {before_cpu:.0f} ms)"
            )
            print(
                f"  {args.workers} processes, store (first run, jobs: {jobs}): {after:7.0f} ms "
                f"({first.computed} computed; includes the process start)"
            )
            print(
                f"  rerun, every GQM from the store:            {rerun:7.2f} ms "
                f"({again.computed} computed, values {'identical' if same else 'DIFFERENT'})"
            )
            for name in args.objects:
                if drawn[(name, design)]:
                    analyse(name, design, drawn[(name, design)])


if __name__ == "__main__":
    main()
