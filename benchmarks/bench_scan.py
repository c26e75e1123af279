"""Imported scans against their built-in objects: milliseconds per hypothesis, one design, one core.

For each pair (scan key, built-in key) the same sampled hypotheses (every ``--stride``-th)
are simulated and judged at one design, on the engine asked for, in this process. Two
figures per object:

- **one design** (the fair comparison): what ``handbench evaluate --object KEY`` costs a
  user after set-up and import, i.e. with the object's palm stages known (the built-ins'
  palm tables come from ``make setup``, an imported object's from ``objects import``; both
  are read from the disk cache, or built here first and their build time printed): the
  open thumb's approach check, the thumb's CMC stage, the thumb's closing and contacts,
  judging;
- **from scratch** (the raw one): the palm stage computed too (approach, back-off, long
  fingers, their contacts), as on a cold cache.

Wall and CPU time (``time.process_time``) per hypothesis, the scan/built-in ratios, the
time one design of the full hypothesis set takes on one core, and the load average at the
start and the end. Prints figures; asserts nothing.

The scans must have been imported first (docs/objects.md, "Using YCB scans"), e.g.

    handbench objects import /tmp/ycb/master_chef_can.stl --like coffee_can \
        --key ycb_master_chef_can

With ``--decimate N`` the script also imports a copy of each scan simplified to N faces
(registered in this process only, its field and palm table cached as usual), to measure
e.g. a 16k-face scan (needs ``pip install fast-simplification``).

Usage: .venv/bin/python benchmarks/bench_scan.py [--engine compiled|fcl] [--stride 10]
           [--cmc 0 --mcp 45] [--pairs ycb_master_chef_can:coffee_can ...] [--decimate 16000]
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import time
from dataclasses import dataclass

from app.model.design import ThumbDesign
from app.model.objects import load_object
from app.quality.judge import judge
from app.quality.settings import SimSettings
from app.runs.palm_cache import build_tables, palm_table
from app.sim.hypothesis_sets import cached_hypotheses
from app.sim.simulate import base_kit, cached_kit, simulate_base, simulate_thumb

PAIRS = (
    "ycb_chips_can:chips_can",
    "ycb_master_chef_can:coffee_can",
    "ycb_pear:plastic_pear",
    "ycb_power_drill:power_drill",
)


def _decimated(key: str, faces: int) -> str:
    """Register a copy of scan ``key`` simplified to about ``faces`` faces, repaired by the
    importer's checks (``read_mesh``: a simplification may leave duplicate or degenerate
    faces); its key ("" when no watertight simplification came out). Needs
    ``pip install fast-simplification``."""
    import tempfile
    import warnings
    from pathlib import Path

    from app.errors import MeshImportError
    from app.model.objects.importer import read_mesh
    from app.model.objects.model import GraspObject, register_object
    from app.model.objects.shapes import from_mesh

    obj = load_object(key)
    if len(obj.mesh.faces) <= faces:
        return ""
    m = obj.mesh.simplify_quadric_decimation(face_count=faces)
    if not m.is_watertight:
        with tempfile.TemporaryDirectory() as d, warnings.catch_warnings():
            warnings.simplefilter("ignore")
            path = Path(d) / "simplified.ply"
            m.export(str(path))
            try:
                m = read_mesh(path, units="mm")
            except MeshImportError:
                return ""
    new_key = f"{key}_{faces // 1000}k"
    spec = dataclasses.replace(obj.spec, key=new_key)
    register_object(GraspObject(spec, from_mesh(m)))
    return new_key


@dataclass(frozen=True)
class Timing:
    """Seconds per hypothesis of one object at one design."""

    wall: float
    """One design on known palm stages, wall time."""
    cpu: float
    """The same, CPU time of this process."""
    raw_wall: float
    """From scratch (the palm stage computed too), wall time."""
    raw_cpu: float
    """The same, CPU time."""
    palm_note: str
    """Where the palm table came from: the disk cache, or built here (seconds)."""


def time_object(key: str, design: ThumbDesign, s: SimSettings, stride: int) -> Timing:
    """Per-hypothesis times over every ``stride``-th hypothesis (``Timing``)."""
    obj, hyps = load_object(key), cached_hypotheses(key)
    kit, bkit = cached_kit(design.cmc_deg, design.mcp_deg, design.cmc_tilt), base_kit(design)
    obj.prepare_distance_field()  # load or build the field before timing
    table = palm_table(key, s)
    if table.from_disk:
        note = "disk cache"
    else:
        ((_, _, dt, cached),) = build_tables((key,), s)
        note = "disk cache" if cached else f"built {dt:.1f} s"
    judge(simulate_thumb(kit, obj, simulate_base(bkit, obj, hyps, 0, s), s), obj, s, 0)
    idx = range(0, len(hyps), stride)

    def one_design(i: int) -> None:
        base = simulate_base(bkit, obj, hyps, i, s, palm=table.get(i))
        judge(simulate_thumb(kit, obj, base, s), obj, s, i)

    def from_scratch(i: int) -> None:
        judge(simulate_thumb(kit, obj, simulate_base(bkit, obj, hyps, i, s), s), obj, s, i)

    out: list[float] = []
    for run in (one_design, from_scratch):
        t0, c0 = time.perf_counter(), time.process_time()
        for i in idx:
            run(i)
        out += [(time.perf_counter() - t0) / len(idx), (time.process_time() - c0) / len(idx)]
    return Timing(out[0], out[1], out[2], out[3], note)


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
    load = " ".join(f"{x:.2f}" for x in os.getloadavg())
    print(f"engine {a.engine}, design CMC {a.cmc:g}° MCP {a.mcp:g}°, every {a.stride}th GH")
    print(f"load average at the start: {load}")
    print("one design = palm stages known (the fair comparison); from scratch = palm computed")
    print("ms per hypothesis, wall / CPU; × = the scan's wall time over its built-in's")
    print(
        f"{'object':<24}{'faces':>7}{'palm table':>17}{'one design':>15}{'×':>7}"
        f"{'from scratch':>15}{'×':>7}{'1 design, 1 core':>18}"
    )
    for pair in a.pairs:
        scan, builtin = pair.split(":")
        keys = [builtin, scan]
        if a.decimate:
            dec = _decimated(scan, a.decimate)
            if dec:
                keys.append(dec)
            else:
                print(f"({scan}: no watertight {a.decimate}-face simplification)")
        ref: Timing | None = None
        for k in keys:
            t = time_object(k, design, s, a.stride)
            n_gh = len(cached_hypotheses(k))
            r1 = "" if ref is None else f"{t.wall / ref.wall:6.2f}×"
            r2 = "" if ref is None else f"{t.raw_wall / ref.raw_wall:6.2f}×"
            ref = t if ref is None else ref
            faces = len(load_object(k).mesh.faces)
            print(
                f"{k:<24}{faces:>7}{t.palm_note:>17}"
                f"{t.wall * 1e3:8.2f} /{t.cpu * 1e3:5.2f}{r1:>7}"
                f"{t.raw_wall * 1e3:8.1f} /{t.raw_cpu * 1e3:5.1f}{r2:>7}"
                f"{t.wall * n_gh:16.2f} s"
            )
    load = " ".join(f"{x:.2f}" for x in os.getloadavg())
    print(f"load average at the end: {load}")


if __name__ == "__main__":
    main()
