"""Imported scans against their built-in objects: seconds per hypothesis, one design, one core.

For each pair (scan key, built-in key) the same sampled hypotheses (every ``--stride``-th)
are simulated and judged at one design, on the engine asked for, in this process; the script
prints ms per hypothesis, the scan/built-in ratio, and the time one design of the full
hypothesis set takes on one core. Prints figures; asserts nothing.

The scans must have been imported first (docs/objects.md, "Using YCB scans"), e.g.

    handbench objects import /tmp/ycb/master_chef_can.stl --like coffee_can \
        --key ycb_master_chef_can

With ``--decimate N`` the script also imports a copy of each scan simplified to N faces
(registered in this process only, its field cached as usual), to measure e.g. a 16k-face
scan (needs ``pip install fast-simplification``).

Usage: .venv/bin/python benchmarks/bench_scan.py [--engine compiled|fcl] [--stride 10]
           [--cmc 0 --mcp 45] [--pairs ycb_master_chef_can:coffee_can ...] [--decimate 16000]
"""

from __future__ import annotations

import argparse
import dataclasses
import time

from app.model.design import ThumbDesign
from app.model.objects import load_object
from app.quality.judge import judge
from app.quality.settings import SimSettings
from app.sim.hypothesis_sets import cached_hypotheses
from app.sim.simulate import base_kit, cached_kit, simulate_base, simulate_thumb

PAIRS = (
    "ycb_chips_can:chips_can",
    "ycb_master_chef_can:coffee_can",
    "ycb_pear:plastic_pear",
    "ycb_power_drill:power_drill",
)


def _decimated(key: str, faces: int) -> str:
    """Register a copy of scan ``key`` simplified to ``faces`` faces; its key ("" when the
    simplification is not watertight). Needs ``pip install fast-simplification``."""
    from app.model.objects.model import GraspObject, register_object
    from app.model.objects.shapes import from_mesh

    obj = load_object(key)
    if len(obj.mesh.faces) <= faces:
        return ""
    m = obj.mesh.simplify_quadric_decimation(face_count=faces)
    if not m.is_watertight:
        return ""
    new_key = f"{key}_{faces // 1000}k"
    spec = dataclasses.replace(obj.spec, key=new_key)
    register_object(GraspObject(spec, from_mesh(m)))
    return new_key


def time_object(key: str, design: ThumbDesign, s: SimSettings, stride: int) -> tuple[float, int]:
    """(seconds per hypothesis, hypotheses timed) over every ``stride``-th hypothesis."""
    obj, hyps = load_object(key), cached_hypotheses(key)
    kit, bkit = cached_kit(design.cmc_deg, design.mcp_deg, design.cmc_tilt), base_kit(design)
    prep = obj.prepare_distance_field()  # load or build the field before timing
    judge(simulate_thumb(kit, obj, simulate_base(bkit, obj, hyps, 0, s), s), obj, s, 0)
    idx = range(0, len(hyps), stride)
    t0 = time.perf_counter()
    for i in idx:
        judge(simulate_thumb(kit, obj, simulate_base(bkit, obj, hyps, i, s), s), obj, s, i)
    dt = (time.perf_counter() - t0) / len(idx)
    _ = prep
    return dt, len(idx)


def main() -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    ap.add_argument("--engine", default="compiled", choices=("compiled", "fcl"))
    ap.add_argument("--stride", type=int, default=10)
    ap.add_argument("--cmc", type=float, default=0.0)
    ap.add_argument("--mcp", type=float, default=45.0)
    ap.add_argument("--pairs", nargs="+", default=list(PAIRS))
    ap.add_argument("--decimate", type=int, default=0, help="also time an N-face copy")
    a = ap.parse_args()
    s = SimSettings()
    s = dataclasses.replace(s, closing=dataclasses.replace(s.closing, engine=a.engine))
    design = ThumbDesign(a.cmc, a.mcp)
    print(f"engine {a.engine}, design CMC {a.cmc:g}° MCP {a.mcp:g}°, every {a.stride}th GH")
    print(f"{'object':<28}{'faces':>7}{'ms/GH':>9}{'× built-in':>12}{'1 design, 1 core':>18}")
    for pair in a.pairs:
        scan, builtin = pair.split(":")
        keys = [builtin, scan]
        if a.decimate:
            dec = _decimated(scan, a.decimate)
            if dec:
                keys.append(dec)
            else:
                print(f"({scan}: no watertight {a.decimate}-face simplification)")
        ref = None
        for k in keys:
            dt, _ = time_object(k, design, s, a.stride)
            n_gh = len(cached_hypotheses(k))
            ratio = "" if ref is None else f"{dt / ref:10.2f}×"
            ref = dt if ref is None else ref
            faces = len(load_object(k).mesh.faces)
            print(f"{k:<28}{faces:>7}{dt * 1e3:9.1f}{ratio:>12}{dt * n_gh:16.1f} s")


if __name__ == "__main__":
    main()
