"""Agreement and speed of the compiled closing engine against the FCL engine.

For every object, a deterministic subsample of hypotheses (every ``--stride``-th) and a few
designs (default the baseline 0/45 and 30/75; ``--full``: the 28 published designs, every
hypothesis), each hypothesis is simulated and judged on both engines back to back in this
process (``simulate_base`` with the design's base kit, ``simulate_thumb``, ``judge``). Prints
per object: the fraction of hypotheses whose (is_fc, is_correct) match, S_GAS on both engines
and the difference, the largest joint-angle difference, the fraction with identical stage
events, and the time ratio (whole simulation + judge, and the closing part alone: approach
and closing stages). It prints, it does not assert.

The floor column (``--floor``) is the agreement of the FCL engine with itself when its final
joint angles are moved by a random ±``--floor-rad`` (default 1e-7 rad) before the contacts and
the judge: outcomes that flip under such a perturbation cannot be reproduced by any engine
that is not bit-identical (up to engine 5, patches were centred on FCL's nearest point, which
jumps along a link lying parallel to a flat face; since engine 6 they are not).

    python benchmarks/bench_engine_agreement.py [--stride 7] [--full] [--objects a,b]
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import time
from collections import defaultdict
from collections.abc import Callable
from typing import Any

import numpy as np

import app.sim.closing as closing_mod
import app.sim.simulate as simulate_mod
from app.model.design import ThumbDesign, published_designs
from app.model.objects import OBJECT_KEYS, load_object
from app.quality.judge import judge
from app.quality.settings import SimSettings
from app.sim.closing import ClosingStats
from app.sim.hypothesis_sets import cached_hypotheses
from app.sim.simulate import Grasp, HandKit, base_kit, cached_kit, simulate_base, simulate_thumb

_CLOSING_S = [0.0]


def _timed(fn: Callable[..., Any]) -> Callable[..., Any]:
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        t0 = time.perf_counter()
        try:
            return fn(*args, **kwargs)
        finally:
            _CLOSING_S[0] += time.perf_counter() - t0

    return wrapper


def _instrument() -> None:
    """Time the approach and every closing stage (either engine) without changing them."""
    closing_mod._advance = _timed(closing_mod._advance)  # type: ignore[attr-defined]
    simulate_mod.approach = _timed(simulate_mod.approach)  # type: ignore[attr-defined]


def _run(kit, bkit, obj, hyps, i: int, s: SimSettings) -> tuple[Any, Any, float, float]:
    c0 = _CLOSING_S[0]
    t0 = time.perf_counter()
    st = ClosingStats()
    base = simulate_base(bkit, obj, hyps, i, s, st)
    g = simulate_thumb(kit, obj, base, s, ClosingStats())
    out = judge(g, obj, s, g.queries + base.queries)
    return g, out, time.perf_counter() - t0, _CLOSING_S[0] - c0


def _perturbed_outcome(kit: HandKit, obj, g: Grasp, s: SimSettings, eps: float, seed: int):
    """Judge ``g`` with its joint angles moved by uniform noise of ±eps rad (contacts anew)."""
    if not g.approached:
        return judge(g, obj, s, 0)
    rng = np.random.default_rng(seed)
    q = g.q + rng.uniform(-eps, eps, g.q.shape)
    T_links = g.T_object_palm @ kit.hand.link_poses(q)
    non_thumb = [j for j, n in enumerate(kit.names) if not n.startswith("thumb")]
    idx = non_thumb + list(kit.chains["thumb"].link_indices)
    cs, _ = kit.contacts(obj, T_links, idx, s)
    thumb_distal = kit.chains["thumb"].link_indices[2]
    gp = dataclasses.replace(g, q=q, contacts=cs, thumb_n_main_object=T_links[thumb_distal][:3, 1])
    return judge(gp, obj, s, 0)


def _s_gas(fc: np.ndarray, correct: np.ndarray) -> float:
    c = (fc & correct).sum()
    nc = (fc & ~correct).sum()
    return 100.0 * (c + 0.5 * nc) / max(len(fc), 1)


def main() -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--stride", type=int, default=7, help="every n-th hypothesis (default 7)")
    ap.add_argument("--full", action="store_true", help="28 designs, every hypothesis")
    ap.add_argument("--designs", default="0/45,30/75", help="cmc/mcp pairs (default 0/45,30/75)")
    ap.add_argument("--objects", default=",".join(OBJECT_KEYS))
    ap.add_argument("--floor", action="store_true", help="also the FCL self-agreement floor")
    ap.add_argument("--floor-rad", type=float, default=1e-7, help="perturbation of --floor")
    a = ap.parse_args()
    if a.full:
        designs, stride = published_designs(), 1
    else:
        pairs = [[float(x) for x in d.split("/")] for d in a.designs.split(",")]
        designs = [ThumbDesign(c, m) for c, m in pairs]
        stride = a.stride
    s0 = SimSettings()
    sF = dataclasses.replace(s0, closing=dataclasses.replace(s0.closing, engine="fcl"))
    sC = dataclasses.replace(s0, closing=dataclasses.replace(s0.closing, engine="compiled"))
    _instrument()
    print(f"load average at start: {os.getloadavg()}")
    # JIT: compile (or load numba's on-disk cache) once before timing
    obj0, hy0 = load_object(OBJECT_KEYS[0]), cached_hypotheses(OBJECT_KEYS[0])
    k0 = cached_kit(0.0, 45.0, "ulnar")
    _run(k0, base_kit(ThumbDesign(0.0, 0.0)), obj0, hy0, 0, sF)
    t0 = time.perf_counter()
    _run(k0, base_kit(ThumbDesign(0.0, 0.0)), obj0, hy0, 0, sC)
    dt = time.perf_counter() - t0
    print(f"first compiled hypothesis (numba import + JIT or its disk cache): {dt:.1f} s")
    tot: dict[str, float] = defaultdict(float)
    print(
        f"{'object':13} {'n':>6} {'outcome=':>9} {'events=':>8} {'S_GAS fcl':>9} "
        f"{'compiled':>9} {'diff':>6} {'max|dq|°':>9} {'speed×':>7} {'closing×':>8} "
        f"{'floor':>7} {'S_GAS fl':>8}"
    )
    for key in a.objects.split(","):
        obj, hyps = load_object(key), cached_hypotheses(key)
        idx = list(range(0, len(hyps), stride))
        res: dict[str, list[tuple[bool, bool]]] = {"fcl": [], "compiled": [], "floor": []}
        same_ev, dq_max = 0, 0.0
        t = {"fcl": 0.0, "compiled": 0.0, "fcl_c": 0.0, "compiled_c": 0.0}
        for d in designs:
            kit = cached_kit(d.cmc_deg, d.mcp_deg, d.cmc_tilt)
            bkit = base_kit(d)
            for i in idx:
                gf, of, tf, cf = _run(kit, bkit, obj, hyps, i, sF)
                gc, oc, tc, cc = _run(kit, bkit, obj, hyps, i, sC)
                res["fcl"].append((of.is_fc, of.is_correct))
                res["compiled"].append((oc.is_fc, oc.is_correct))
                if a.floor:
                    op = _perturbed_outcome(kit, obj, gf, sF, a.floor_rad, i)
                    res["floor"].append((op.is_fc, op.is_correct))
                same_ev += gf.events == gc.events
                dq_max = max(dq_max, float(np.abs(gf.q - gc.q).max()))
                t["fcl"] += tf
                t["compiled"] += tc
                t["fcl_c"] += cf
                t["compiled_c"] += cc
        f, c = np.array(res["fcl"]), np.array(res["compiled"])
        n = len(f)
        agree = float((f == c).all(1).mean())
        p = np.array(res["floor"]) if a.floor else np.zeros((0, 2), bool)
        floor = float((f == p).all(1).mean()) if a.floor else float("nan")
        s_floor = _s_gas(p[:, 0], p[:, 1]) if a.floor else float("nan")
        sf, sc = _s_gas(f[:, 0], f[:, 1]), _s_gas(c[:, 0], c[:, 1])
        print(
            f"{key:13} {n:6d} {100 * agree:8.2f}% {100 * same_ev / n:7.2f}% {sf:9.2f} {sc:9.2f} "
            f"{sc - sf:+6.2f} {np.degrees(dq_max):9.4f} {t['fcl'] / t['compiled']:7.2f} "
            f"{t['fcl_c'] / t['compiled_c']:8.2f} {100 * floor:6.2f}% {s_floor:8.2f}"
        )
        for k_ in t:
            tot[k_] += t[k_]
        tot["n"] += n
        tot["agree"] += agree * n
        tot["floor"] += floor * n
    n = tot["n"]
    print(
        f"all objects: {n:.0f} hypothesis-designs, outcomes agree on "
        f"{100 * tot['agree'] / n:.2f}% (FCL floor {100 * tot['floor'] / n:.2f}%)"
    )
    for e in ("fcl", "compiled"):
        print(
            f"{e:9}: {1e3 * tot[e] / n:7.2f} ms per GH (simulate + judge), "
            f"closing alone {1e3 * tot[e + '_c'] / n:7.2f} ms"
        )
    print(
        f"ratio fcl/compiled: whole {tot['fcl'] / tot['compiled']:.2f}×, "
        f"closing {tot['fcl_c'] / tot['compiled_c']:.2f}×"
    )
    print(f"load average at end: {os.getloadavg()}")


if __name__ == "__main__":
    main()
