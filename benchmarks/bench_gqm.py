"""Cost of the brute-force GQM stage (METHOD §6) per grasp, and where it goes. Prints figures.

Usage: .venv/bin/python benchmarks/bench_gqm.py [--objects small_marker chips_can]
       [--grasps 20] [--gh-stride 5] [--workers 2] [--store PATH] [--alternatives]
       [--tune]

1. Simulates every ``--gh-stride``-th brute-force GH of each object for one design (baseline
   CMC 0°, MCP 45°) into a throwaway store (or ``--store``), and draws up to ``--grasps`` of
   the FC grasps per object (``app.runs.gqm_compare.draw_fc``).
2. The GQM stage per grasp, one process without the store: GQM_VERSION 1 (Q_C1 and Q_C2 on
   one full hull of every patch point, ``v1_wrench_measures``) against the product (Q_C1 by
   the grown hull, ``app.quality.gqm.epsilon``; Q_C2 on per-link contacts); then ``--workers``
   processes writing the store (first run), and the rerun (every GQM read from the store;
   with a reused ``--store`` that already holds them, the first run computes none either).
3. Per object, per grasp (CPU): the ten GQMs before and after, the eight others, Q_C1's
   grown ε and Q_C2's per-link hull apart; the grown ε against the full hull's (largest
   relative deviation, how often it fell back to the full hull, wrenches used, rounds); and
   Spearman's rank correlation of the new Q_C2 (per link) with the old one (every patch
   point), and of Q_C1 on per-link contacts with Q_C1 on patches, for the record.
4. ``--tune``: the grown ε's time for a few (``n_dirs``, ``per_round``) settings.
5. ``--alternatives``: the exact full-hull speed-ups measured and NOT used (before the
   decision of GQM_VERSION 2), each with its deviation from the exact values:
   - ``vertices only``: the hull of the hull's own vertices, the best any exact pruning of
     interior wrenches can do;
   - ``per-link pruning``: drop, one by one, each wrench inside the hull of the remaining
     wrenches of its own link (non-negative least squares), then the hull (time of both);
   - ``Qx Q5``/``QJ``: other qhull options.
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

import app.quality.gqm as gqm_pkg
from app.model.contact_set import ContactSet
from app.model.design import ThumbDesign
from app.model.objects import load_object
from app.quality.force_closure import primitive_wrenches
from app.quality.gqm import GQMSettings, compute_gqms, epsilon_wrenches, wrench_measures
from app.quality.gqm.contacts import LinkContacts, link_contacts
from app.quality.gqm.epsilon import grown_epsilon
from app.quality.gqm.wrench_space import wrench_hull
from app.quality.outcome import GraspOutcome
from app.quality.settings import SimSettings
from app.runs.executors import InlineExecutor, LocalExecutor
from app.runs.gqm_compare import BF_SET, GQM_CHUNK, _gqm_job, _Pose, draw_fc, score_grasps
from app.runs.keys import set_object_key
from app.runs.store import ResultStore
from app.runs.sweep import execute_tasks
from app.runs.tasks import plan_tasks
from app.sim.simulate import cached_kit


def v1_wrench_measures(
    contacts: ContactSet, lc: LinkContacts, c: np.ndarray, r: float, s: GQMSettings
) -> tuple[float, float]:
    """(Q_C1, Q_C2) of GQM_VERSION 1: ε and volume of one full hull of Q_C1's wrenches."""
    ws = wrench_hull(epsilon_wrenches(contacts, lc, c, r, s))
    return max(ws.epsilon, 0.0), ws.volume


def cpu_ms(f, *args, **kw):
    """(result, CPU ms) of one call."""
    t = time.process_time()
    out = f(*args, **kw)
    return out, (time.process_time() - t) * 1e3


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


def patched(measures):
    """Context: ``compute_gqms`` with its (Q_C1, Q_C2) computed by ``measures``."""

    class _Patch:
        def __enter__(self):
            gqm_pkg.wrench_measures = measures

        def __exit__(self, *exc):
            gqm_pkg.wrench_measures = wrench_measures

    return _Patch()


def analyse(
    name: str, design: ThumbDesign, drawn: list[tuple[str, GraspOutcome]], alternatives: bool
) -> dict[str, np.ndarray]:
    """Print where one grasp's GQM time goes, before and after; the per-grasp columns."""
    obj = load_object(name)
    hand = cached_kit(design.cmc_deg, design.mcp_deg, design.cmc_tilt).hand
    c, r = np.asarray(obj.centroid_object, float), float(obj.max_radius)
    s = GQMSettings()
    rows = []
    for _, o in drawn:
        cs = o.contacts
        lc = link_contacts(cs)
        pose = _Pose(o.q_final_rad, np.asarray(o.extra["T_object_palm"], float), cs)
        new, total = cpu_ms(compute_gqms, pose, obj, hand)
        with patched(v1_wrench_measures):
            old, total_v1 = cpu_ms(compute_gqms, pose, obj, hand)
        with patched(lambda *_: (0.0, 0.0)):  # the eight other GQMs alone
            others = cpu_ms(compute_gqms, pose, obj, hand)[1]
        W = epsilon_wrenches(cs, lc, c, r, s)
        ge, c1_ms = cpu_ms(grown_epsilon, W)
        lw = primitive_wrenches(lc.p, lc.n, c, r, s.mu, s.n_edges)
        lws, c2_ms = cpu_ms(wrench_hull, lw)
        full = wrench_hull(W)
        row = dict(
            total=total, total_v1=total_v1, others=others, c1_ms=c1_ms, c2_ms=c2_ms,
            M=len(W), L=len(lc.links), eps=full.epsilon, vol=full.volume,
            g_eps=ge.epsilon, g_full=float(ge.method != "grown"), g_n=ge.n_used,
            g_rounds=ge.rounds, lk_eps=grown_epsilon(lw).epsilon, lk_vol=lws.volume,
            c1_new=new["Q_C1"], c1_old=old["Q_C1"], c2_new=new["Q_C2"], c2_old=old["Q_C2"],
            qhullerr=float(plain_failed(W)),
        )  # fmt: skip
        if alternatives:
            row.update(alternative_row(W, cs))
        rows.append(row)
    col = {k: np.array([row[k] for row in rows], float) for k in rows[0]}
    n = len(rows)
    ok = col["qhullerr"] == 0
    print(
        f"\n{name} ({obj.spec.grasp_type}), {n} FC grasps: {np.mean(col['M']):.0f} patch "
        f"wrenches, {np.mean(col['L']):.1f} touching links ({np.mean(col['L']) * s.n_edges:.0f} "
        f"link wrenches) per grasp; {int(np.sum(~ok))} full hulls with a qhull precision error"
    )
    print(
        f"  ten GQMs per grasp (CPU): GQM_VERSION 1 {np.mean(col['total_v1']):.0f} ms -> "
        f"{np.mean(col['total']):.1f} ms now (max {np.max(col['total']):.1f} ms); the eight "
        f"others {np.mean(col['others']):.1f} ms, Q_C1 grown ε {np.mean(col['c1_ms']):.1f} ms "
        f"(max {np.max(col['c1_ms']):.1f}), Q_C2 per-link hull {np.mean(col['c2_ms']):.1f} ms "
        f"(max {np.max(col['c2_ms']):.1f})"
    )
    qj = (
        f"{rel(col['g_eps'][~ok], col['eps'][~ok]):.0e} where the full hull needed QJ"
        if np.any(~ok)
        else "no full hull needed QJ"
    )
    print(
        f"  grown ε vs the full patch hull: largest relative deviation "
        f"{rel(col['g_eps'][ok], col['eps'][ok]):.0e} (plain qhull), {qj}; "
        f"{int(np.sum(col['g_full']))} fell back to the full hull; "
        f"{np.mean(col['g_n']):.0f} of {np.mean(col['M']):.0f} wrenches used, "
        f"{np.mean(col['g_rounds']):.1f} rounds (max {int(np.max(col['g_rounds']))})"
    )
    print(
        f"  stored Q_C1 old vs new: largest relative deviation "
        f"{rel(col['c1_new'], col['c1_old']):.0e}"
    )
    rho_v = spearmanr(col["lk_vol"], col["vol"], nan_policy="omit")[0]
    rho_e = spearmanr(col["lk_eps"], col["eps"], nan_policy="omit")[0]
    print(
        f"  Spearman rank correlation, per link vs every patch point: Q_C2 (volume) "
        f"{rho_v:.2f}, Q_C1 (ε) {rho_e:.2f}; Q_C2 per link / per patch: median "
        f"{np.median(col['lk_vol'] / col['vol']):.2g}"
    )
    if alternatives:
        print_alternatives(col)
    return col


def plain_failed(W: np.ndarray) -> bool:
    """Does plain qhull raise a precision error on W?"""
    try:
        ConvexHull(W)
    except QhullError:
        return True
    return False


def alternative_row(W: np.ndarray, cs: ContactSet) -> dict[str, float]:
    """Timings and values of the exact full-hull speed-ups (``--alternatives``)."""
    ms, eps, vol, facets, verts = hull(W)
    if not np.isfinite(eps):  # the product retries with QJ: time both, compare with QJ's values
        qj_ms, eps, vol, facets, verts = hull(W, "QJ")
        ms += qj_ms
    v_ms, v_eps, v_vol = hull(W[verts])[:3]
    t = time.perf_counter()
    keep = prune_per_link(W, np.asarray([str(x) for x in cs.link]))
    p_ms = (time.perf_counter() - t) * 1e3
    pr = hull(W[keep])
    q5 = hull(W, "Qx Q5")
    qj = hull(W, "QJ")
    return dict(
        hull=ms, vshare=len(verts) / len(W), facets=facets, a_eps=eps, a_vol=vol,
        v_ms=v_ms, v_eps=v_eps, v_vol=v_vol,
        p_ms=p_ms + pr[0], p_eps=pr[1], p_vol=pr[2], p_n=float(np.sum(~keep)),
        q5_ms=q5[0], q5_eps=q5[1], q5_vol=q5[2], qj_ms=qj[0], qj_eps=qj[1], qj_vol=qj[2],
    )  # fmt: skip


def print_alternatives(col: dict[str, np.ndarray]) -> None:
    ok = col["qhullerr"] == 0
    print(
        f"  full patch hull: {np.nanmean(col['vshare']):.1%} of the wrenches are vertices, "
        f"{np.mean(col['facets']):,.0f} facets, {np.mean(col['hull']):.0f} ms (best of 2)"
    )
    print("  full-hull alternatives (ms per grasp without a precision error, best of 2; largest")
    print("  relative deviation from the exact ε and volume, QJ's where qhull failed):")
    print(
        f"    vertices only      {np.mean(col['v_ms'][ok]):6.0f} ms   "
        f"ε {rel(col['v_eps'], col['a_eps']):.0e}  vol {rel(col['v_vol'], col['a_vol']):.0e}"
    )
    print(
        f"    per-link pruning   {np.mean(col['p_ms'][ok]):6.0f} ms   "
        f"ε {rel(col['p_eps'], col['a_eps']):.0e}  vol {rel(col['p_vol'], col['a_vol']):.0e}  "
        f"({np.mean(col['p_n']):.0f} of {np.mean(col['M'] * (1 - col['vshare'])):.0f} interior "
        f"wrenches dropped)"
    )
    print(
        f"    qhull 'Qx Q5'      {np.mean(col['q5_ms'][ok]):6.0f} ms   "
        f"ε {rel(col['q5_eps'], col['a_eps']):.0e}  vol {rel(col['q5_vol'], col['a_vol']):.0e}"
    )
    print(
        f"    qhull 'QJ'         {np.mean(col['qj_ms'][ok]):6.0f} ms   "
        f"ε {rel(col['qj_eps'], col['a_eps']):.0e}  vol {rel(col['qj_vol'], col['a_vol']):.0e}"
    )


def tune(name: str, design: ThumbDesign, drawn: list[tuple[str, GraspOutcome]]) -> None:
    """The grown ε's CPU time per grasp for a few (n_dirs, per_round) settings."""
    obj = load_object(name)
    c, r = np.asarray(obj.centroid_object, float), float(obj.max_radius)
    s = GQMSettings()
    Ws = [epsilon_wrenches(o.contacts, link_contacts(o.contacts), c, r, s) for _, o in drawn]
    ref = np.array([grown_epsilon(W).epsilon for W in Ws])
    parts = []
    for n_dirs, k in [(0, 4), (0, 8), (0, 16), (16, 8), (64, 8)]:
        got, ms = cpu_ms(lambda n_dirs=n_dirs, k=k: [grown_epsilon(W, n_dirs, k) for W in Ws])
        eps = np.array([g.epsilon for g in got])
        parts.append(
            f"({n_dirs}, {k}) {ms / len(Ws):.1f} ms, "
            f"{np.mean([g.n_used for g in got]):.0f} used, dev {rel(eps, ref):.0e}"
        )
    print(f"  tune {name} (n_dirs, per_round): " + "; ".join(parts))


def main() -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--objects", nargs="+", default=["small_marker", "chips_can"])
    ap.add_argument("--grasps", type=int, default=20, help="FC grasps per object")
    ap.add_argument("--gh-stride", type=int, default=5, help="simulate every k-th GH")
    ap.add_argument("--workers", type=int, default=2, help="processes of the GQM stage")
    ap.add_argument("--store", help="results store to reuse (default: a throwaway one)")
    ap.add_argument("--alternatives", action="store_true", help="time full-hull speed-ups too")
    ap.add_argument("--tune", action="store_true", help="time grown-ε parameter settings")
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
            n = sum(len(v) for v in drawn.values())
            counts = ", ".join(f"{k[0]} {len(v)}" for k, v in drawn.items())
            print(f"\nGQM stage, {n} FC grasps ({counts}), wall time per grasp:")
            if n == 0:
                return
            for name in args.objects:  # warm this process: objects, hands
                _gqm_job(
                    (name, (design.cmc_deg, design.mcp_deg, design.cmc_tilt), [], GQMSettings())
                )
            with patched(v1_wrench_measures):
                t, cpu = time.perf_counter(), time.process_time()
                v1 = score_grasps(drawn, workers=1)
                before = (time.perf_counter() - t) / n * 1e3
                before_cpu = (time.process_time() - cpu) / n * 1e3
            t, cpu = time.perf_counter(), time.process_time()
            v2 = score_grasps(drawn, workers=1)
            now = (time.perf_counter() - t) / n * 1e3
            now_cpu = (time.process_time() - cpu) / n * 1e3
            print(
                f"  one process, no store, GQM_VERSION 1 (full patch hull): {before:7.1f} ms "
                f"(CPU {before_cpu:.1f} ms)"
            )
            print(
                f"  one process, no store, now:                             {now:7.1f} ms "
                f"(CPU {now_cpu:.1f} ms)"
            )
            same8 = all(
                a.values[g] == b.values[g]
                for a, b in zip(v1.scored, v2.scored, strict=True)
                for g in a.values
                if g not in ("Q_C1", "Q_C2")
            )
            print(f"  the eight other GQMs {'identical' if same8 else 'DIFFERENT'} before/after")
            t = time.perf_counter()
            first = score_grasps(drawn, workers=args.workers, store=store, sim=sim)
            after = (time.perf_counter() - t) / n * 1e3
            t = time.perf_counter()
            again = score_grasps(drawn, workers=args.workers, store=store, sim=sim)
            rerun = (time.perf_counter() - t) / n * 1e3
            same = [s.values for s in first.scored] == [s.values for s in again.scored]
            jobs = sum(-(-len(v) // GQM_CHUNK) for v in drawn.values())
            print(
                f"  {args.workers} processes, store (first run, jobs: {jobs}): {after:7.1f} ms "
                f"({first.computed} computed; includes the process start)"
            )
            print(
                f"  rerun, every GQM from the store:            {rerun:7.2f} ms "
                f"({again.computed} computed, values {'identical' if same else 'DIFFERENT'})"
            )
            cols = []
            for name in args.objects:
                if drawn[(name, design)]:
                    cols.append(analyse(name, design, drawn[(name, design)], args.alternatives))
                    if args.tune:
                        tune(name, design, drawn[(name, design)])
            if len(cols) > 1:
                pooled = {k: np.concatenate([c[k] for c in cols]) for k in ("lk_vol", "vol")}
                rho = spearmanr(pooled["lk_vol"], pooled["vol"])[0]
                print(f"\nQ_C2 per link vs patch, all {n} grasps pooled: Spearman {rho:.2f}")


if __name__ == "__main__":
    main()
